// "bsdfs" and every "bsdf" reference: Tungsten's BSDF types Telescope implements. A new
// material family is read here (and added to BsdfType, scene.h).
#include "scene/complex_ior.h"
#include "scene/scene_reader.h"

namespace telescope::scene_reader {

namespace {

// Tungsten types that exist but Telescope does not implement (yet)
constexpr std::string_view kUnsupportedBsdfs[] = {
    "phong", "mixed", "smooth_coat", "thinsheet", "rough_coat", "transparency",
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
    else if (type == "conductor") m.type = BsdfType::Conductor;
    else if (type == "rough_conductor") m.type = BsdfType::RoughConductor;
    else if (type == "plastic") m.type = BsdfType::Plastic;
    else if (type == "rough_plastic") m.type = BsdfType::RoughPlastic;
    else if (type == "oren_nayar") m.type = BsdfType::OrenNayar;
    else if (type == "rough_dielectric") m.type = BsdfType::RoughDielectric;
    else if (isOneOf(kUnsupportedBsdfs, type)) fail(member(key, "type"), fmt::format("unsupported bsdf type '{}'", type));
    else fail(member(key, "type"), fmt::format("unknown bsdf type '{}'", type));

    m.key = key;
    rejectMedia(v, key, {"int_medium", "ext_medium"});
    if (const json* name = find(v, "name")) m.name = string(*name, member(key, "name"));
    if (const json* albedo = find(v, "albedo")) {
        if (auto t = readTexture(*albedo, member(key, "albedo"), false, m.albedo)) m.albedoTexture = int32_t(*t);
    }
    if (m.type == BsdfType::Dielectric) {
        if (const json* ior = find(v, "ior")) {
            m.ior = number(*ior, member(key, "ior"));
            if (m.ior <= 0.0f) fail(member(key, "ior"), "the index of refraction must be positive");
        }
        if (const json* refraction = find(v, "enable_refraction"))
            m.enableRefraction = boolean(*refraction, member(key, "enable_refraction"));
        ignoreUnread(v, key, {"name", "type", "albedo", "ior", "enable_refraction"});
    } else if (m.type == BsdfType::Conductor || m.type == BsdfType::RoughConductor) {
        readConductor(v, key, m);
    } else if (m.type == BsdfType::Plastic || m.type == BsdfType::RoughPlastic) {
        // Tungsten's defaults: ior 1.5, thickness 1, sigma_a 0; rough: GGX, roughness 0.02.
        m.roughness = 0.02f;
        readIor(v, key, m);
        if (const json* t = find(v, "thickness")) {
            m.thickness = number(*t, member(key, "thickness"));
            if (!(m.thickness >= 0.0f)) fail(member(key, "thickness"), "the thickness must not be negative");
        }
        if (const json* a = find(v, "sigma_a")) m.sigmaA = colour(*a, member(key, "sigma_a"));
        std::vector<std::string_view> read = {"name", "type", "albedo", "ior", "thickness", "sigma_a"};
        if (m.type == BsdfType::RoughPlastic) readMicrofacet(v, key, m, read);
        ignoreUnread(v, key, read);
    } else if (m.type == BsdfType::OrenNayar) {
        m.roughness = 1.0f;  // Tungsten's default
        if (const json* r = find(v, "roughness")) readRoughness(*r, member(key, "roughness"), m);
        ignoreUnread(v, key, {"name", "type", "albedo", "roughness"});
    } else if (m.type == BsdfType::RoughDielectric) {
        readIor(v, key, m);
        if (const json* refraction = find(v, "enable_refraction"))
            m.enableRefraction = boolean(*refraction, member(key, "enable_refraction"));
        std::vector<std::string_view> read = {"name", "type", "albedo", "ior", "enable_refraction"};
        readMicrofacet(v, key, m, read);
        ignoreUnread(v, key, read);
    } else {
        ignoreUnread(v, key, {"name", "type", "albedo"});
    }
    return m;
}

// "material" (a name from Tungsten's table) or "eta" and "k"; rough_conductor also "distribution"
// and "roughness".
void SceneReader::readConductor(const json& v, const std::string& key, Material& m) {
    const json* material = find(v, "material");
    const json* eta = find(v, "eta");
    const json* k = find(v, "k");
    if (material && (eta || k))
        fail(member(key, eta ? "eta" : "k"), "give either a named \"material\" or \"eta\" and \"k\", not both");
    if (bool(eta) != bool(k))
        fail(member(key, eta ? "k" : "eta"), "\"eta\" and \"k\" go together (the complex index eta + i k)");
    if (material) {
        const std::string name = string(*material, member(key, "material"));
        const ComplexIor* c = findComplexIor(name);
        if (!c) {
            std::string names;
            for (std::string_view n : complexIorNames()) names += (names.empty() ? "" : ", ") + std::string(n);
            fail(member(key, "material"), fmt::format("unknown conductor '{}' (known: {})", name, names));
        }
        m.eta = c->eta;
        m.k = c->k;
    } else if (eta) {
        m.eta = vec3(*eta, member(key, "eta"));
        m.k = vec3(*k, member(key, "k"));
    }
    std::vector<std::string_view> read = {"name", "type", "albedo", "material", "eta", "k"};
    if (m.type == BsdfType::RoughConductor) readMicrofacet(v, key, m, read);
    ignoreUnread(v, key, read);
}

// "distribution" and "roughness" of a microfacet material.
void SceneReader::readMicrofacet(const json& v, const std::string& key, Material& m, std::vector<std::string_view>& read) {
    if (const json* d = find(v, "distribution")) {
        const std::string name = string(*d, member(key, "distribution"));
        if (name == "ggx") m.distribution = shader::kMicrofacetGGX;
        else if (name == "beckmann") m.distribution = shader::kMicrofacetBeckmann;
        else if (name == "phong") m.distribution = shader::kMicrofacetPhong;
        else fail(member(key, "distribution"), fmt::format("unknown distribution '{}' (ggx, beckmann, phong)", name));
    }
    if (const json* r = find(v, "roughness")) readRoughness(*r, member(key, "roughness"), m);
    read.insert(read.end(), {"distribution", "roughness"});
}

float SceneReader::roughness(const json& v, const std::string& key) const {
    if (!v.is_number()) fail(key, "expected a number, got " + quote(v));
    const float r = number(v, key);
    if (!(r >= 0.0f)) fail(key, "the roughness must not be negative");
    return r;
}

// A number, or a texture read as a scalar (its first channel; a bitmap's mean of R, G, B).
void SceneReader::readRoughness(const json& v, const std::string& key, Material& m) {
    if (v.is_number()) {
        m.roughness = roughness(v, key);
        return;
    }
    glm::vec3 constant(m.roughness);
    if (auto t = readTexture(v, key, true, constant)) m.roughnessTexture = int32_t(*t);
    else m.roughness = roughness(json(constant.x), key);
}

void SceneReader::readIor(const json& v, const std::string& key, Material& m) {
    if (const json* ior = find(v, "ior")) {
        m.ior = number(*ior, member(key, "ior"));
        if (m.ior <= 0.0f) fail(member(key, "ior"), "the index of refraction must be positive");
    }
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
