// "bsdfs" and every "bsdf" reference: Tungsten's BSDF types Telescope implements. A new
// material family is read here (and added to BsdfType, scene.h).
#include "scene/complex_ior.h"
#include "scene/scene_reader.h"

namespace telescope::scene_reader {

namespace {

// Tungsten types that exist but Telescope does not implement (yet)
constexpr std::string_view kUnsupportedBsdfs[] = {
    "phong", "smooth_coat", "rough_coat", "lambertian_fiber", "rough_wire", "hair", "diffuse_transmission"};

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
    // Tungsten's bump maps perturb the shading normal: they change the image, and Telescope has none.
    if (const json* bump = find(v, "bump"); bump && !bump->is_null())
        fail(member(key, "bump"), "bump maps are not supported: remove the key to render without it");

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
    else if (type == "thinsheet") m.type = BsdfType::ThinSheet;
    else if (type == "mixed") m.type = BsdfType::Mixed;
    else if (type == "transparency") m.type = BsdfType::Transparency;
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
    } else if (m.type == BsdfType::ThinSheet) {
        // Tungsten's defaults: ior 1.5, thickness 0.5, sigma_a 0, no interference. (Its albedo
        // is read but unused: a thin sheet's weights are its Fresnel terms.)
        m.thickness = 0.5f;
        readIor(v, key, m);
        if (const json* t = find(v, "thickness")) {
            if (!t->is_number()) fail(member(key, "thickness"), "expected a number (textured thickness is not supported), got " + quote(*t));
            m.thickness = number(*t, member(key, "thickness"));
            if (!(m.thickness >= 0.0f)) fail(member(key, "thickness"), "the thickness must not be negative");
        }
        if (const json* a = find(v, "sigma_a")) m.sigmaA = colour(*a, member(key, "sigma_a"));  // (colours are >= 0)
        if (const json* i = find(v, "enable_interference"))
            m.enableInterference = boolean(*i, member(key, "enable_interference"));
        ignoreUnread(v, key, {"name", "type", "albedo", "ior", "thickness", "sigma_a", "enable_interference"});
    } else if (m.type == BsdfType::Mixed || m.type == BsdfType::Transparency) {
        std::vector<std::string_view> read = {"name", "type", "albedo"};
        readComponents(v, key, m, read);
        ignoreUnread(v, key, read);
    } else {
        ignoreUnread(v, key, {"name", "type", "albedo"});
    }
    return m;
}

// mixed: "bsdf0", "bsdf1" (names or inline objects, both required, as in Tungsten) and "ratio"
// (Tungsten's default 0.5); transparency: "base" (Tungsten's default a white lambert) and
// "alpha" (default 1). Textured ratio and alpha are not supported yet.
void SceneReader::readComponents(const json& v, const std::string& key, Material& m, std::vector<std::string_view>& read) {
    if (m.type == BsdfType::Mixed) {
        for (int i = 0; i < 2; ++i) {
            const char* name = i == 0 ? "bsdf0" : "bsdf1";
            const json* c = find(v, name);
            if (!c) fail(member(key, name), "a mixed bsdf needs \"bsdf0\" and \"bsdf1\"");
            m.component[i] = componentRef(*c, member(key, name));
        }
        if (const json* r = find(v, "ratio")) m.ratio = unitScalar(*r, member(key, "ratio"), "ratio");
        read.insert(read.end(), {"bsdf0", "bsdf1", "ratio"});
    } else {
        if (const json* b = find(v, "base")) {
            m.component[0] = componentRef(*b, member(key, "base"));
        } else {
            inlineComponents_.push_back(Material{});  // white lambert
            inlineComponents_.back().key = member(key, "base");
            componentRefs_.push_back({false, inlineComponents_.size() - 1});
            m.component[0] = uint32_t(componentRefs_.size() - 1);
        }
        m.component[1] = m.component[0];
        if (const json* a = find(v, "alpha")) m.alpha = unitScalar(*a, member(key, "alpha"), "alpha");
        read.insert(read.end(), {"base", "alpha"});
    }
}

// A number in [0, 1] (ratio, alpha): textures are not supported yet.
float SceneReader::unitScalar(const json& v, const std::string& key, const char* what) const {
    if (!v.is_number())
        fail(key, fmt::format("expected a number in [0, 1] (a textured {} is not supported), got {}", what, quote(v)));
    const float x = number(v, key);
    if (!(x >= 0.0f && x <= 1.0f)) fail(key, fmt::format("the {} must be in [0, 1]", what));
    return x;
}

// A component reference (by name: a bsdf defined earlier in the list, so references cannot form
// a cycle; or an inline object), recorded in componentRefs_.
uint32_t SceneReader::componentRef(const json& ref, const std::string& key) {
    if (ref.is_string()) {
        const std::string name = ref.get<std::string>();
        const auto it = bsdfByName_.find(name);
        if (it == bsdfByName_.end())
            fail(key, fmt::format("unknown bsdf '{}' (a component must be defined before the bsdf that uses it)", name));
        componentRefs_.push_back({true, it->second});
    } else if (ref.is_object()) {
        inlineComponents_.push_back(readBsdf(ref, key));
        componentRefs_.push_back({false, inlineComponents_.size() - 1});
    } else {
        fail(key, "expected a bsdf name or an inline bsdf object, got " + quote(ref));
    }
    return uint32_t(componentRefs_.size() - 1);
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
        return namedMaterial(it->second);
    }
    if (ref.is_object()) return addMaterial(readBsdf(ref, key));
    fail(key, "expected a bsdf name or an inline bsdf object, got " + quote(ref));
}

uint32_t SceneReader::namedMaterial(size_t named) {
    if (!namedBsdfMaterial_[named]) namedBsdfMaterial_[named] = addMaterial(namedBsdfs_[named]);
    return *namedBsdfMaterial_[named];
}

// Mixed and transparency levels from material i down (0 for the others).
uint32_t SceneReader::nestingOf(uint32_t i) const {
    const Material& m = scene_.materials[i];
    if (m.type != BsdfType::Mixed && m.type != BsdfType::Transparency) return 0;
    return 1 + std::max(nestingOf(m.component[0]), nestingOf(m.component[1]));
}

// Adds m to the scene, and its components (mixed, transparency) with it.
uint32_t SceneReader::addMaterial(Material m) {
    const uint32_t index = static_cast<uint32_t>(scene_.materials.size());
    scene_.materials.push_back(m);
    if (m.type != BsdfType::Mixed && m.type != BsdfType::Transparency) return index;
    uint32_t resolved[2];
    for (int i = 0; i < 2; ++i) {
        if (i == 1 && m.component[1] == m.component[0]) {
            resolved[1] = resolved[0];
            continue;
        }
        const ComponentRef ref = componentRefs_.at(m.component[i]);
        resolved[i] = ref.named ? namedMaterial(ref.index) : addMaterial(inlineComponents_[ref.index]);
    }
    scene_.materials[index].component[0] = resolved[0];
    scene_.materials[index].component[1] = resolved[1];
    if (nestingOf(index) > shader::kMaxMaterialNesting)
        fail(m.key, fmt::format("mixed and transparency bsdfs nest at most {} deep", shader::kMaxMaterialNesting));
    return index;
}

}  // namespace telescope::scene_reader
