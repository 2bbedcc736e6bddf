// "bsdfs" and every "bsdf" reference: Tungsten's BSDF types Telescope implements. A new
// material family is read here (and added to BsdfType, scene.h).
#include "scene/scene_reader.h"

namespace telescope::scene_reader {

namespace {

// Tungsten types that exist but Telescope does not implement (yet)
constexpr std::string_view kUnsupportedBsdfs[] = {
    "phong", "mixed", "conductor", "rough_conductor", "rough_dielectric", "smooth_coat",
    "thinsheet", "oren_nayar", "plastic", "rough_plastic", "rough_coat", "transparency",
    "lambertian_fiber", "rough_wire", "hair", "diffuse_transmission"};

}  // namespace

void SceneReader::readBsdfs(const json& list) {
    if (!list.is_array()) fail("bsdfs", "expected an array, got " + quote(list));
    for (size_t i = 0; i < list.size(); ++i) {
        const std::string key = element("bsdfs", i);
        Material m = readBsdf(list[i], key);
        if (!m.name.empty()) bsdfByName_.emplace(m.name, namedBsdfs_.size());
        namedBsdfs_.push_back(std::move(m));
        namedBsdfMaterial_.emplace_back();
    }
}

Material SceneReader::readBsdf(const json& v, const std::string& key) {
    const std::string type = requiredType(v, key);

    Material m;
    if (type == "lambert") m.type = BsdfType::Lambert;
    else if (type == "mirror") m.type = BsdfType::Mirror;
    else if (type == "dielectric") m.type = BsdfType::Dielectric;
    else if (type == "null") m.type = BsdfType::Null;
    else if (type == "forward") m.type = BsdfType::Forward;
    else if (isOneOf(kUnsupportedBsdfs, type)) fail(member(key, "type"), fmt::format("unsupported bsdf type '{}'", type));
    else fail(member(key, "type"), fmt::format("unknown bsdf type '{}'", type));

    rejectMedia(v, key, {"int_medium", "ext_medium"});
    if (const json* name = find(v, "name")) m.name = string(*name, member(key, "name"));
    if (const json* albedo = find(v, "albedo")) m.albedo = colour(*albedo, member(key, "albedo"));
    if (m.type == BsdfType::Dielectric) {
        if (const json* ior = find(v, "ior")) {
            m.ior = number(*ior, member(key, "ior"));
            if (m.ior <= 0.0f) fail(member(key, "ior"), "the index of refraction must be positive");
        }
        if (const json* refraction = find(v, "enable_refraction"))
            m.enableRefraction = boolean(*refraction, member(key, "enable_refraction"));
        ignoreUnread(v, key, {"name", "type", "albedo", "ior", "enable_refraction"});
    } else {
        ignoreUnread(v, key, {"name", "type", "albedo"});
    }
    return m;
}

// The material for a "bsdf" value: a name from the bsdfs list (added to the scene on first use)
// or an inline object (one material per occurrence).
uint32_t SceneReader::material(const json& ref, const std::string& key) {
    if (ref.is_string()) {
        const std::string name = ref.get<std::string>();
        const auto it = bsdfByName_.find(name);
        if (it == bsdfByName_.end()) fail(key, fmt::format("unknown bsdf '{}'", name));
        std::optional<uint32_t>& index = namedBsdfMaterial_[it->second];
        if (!index) {
            index = static_cast<uint32_t>(scene_.materials.size());
            scene_.materials.push_back(namedBsdfs_[it->second]);
        }
        return *index;
    }
    if (ref.is_object()) {
        scene_.materials.push_back(readBsdf(ref, key));
        return static_cast<uint32_t>(scene_.materials.size() - 1);
    }
    fail(key, "expected a bsdf name or an inline bsdf object, got " + quote(ref));
}

}  // namespace telescope::scene_reader
