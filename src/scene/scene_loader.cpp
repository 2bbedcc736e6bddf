// Tungsten scene loader: parse, apply --set overrides, then interpret with Tungsten's
// conventions into the world-space model of scene.h. Every error names the file and the JSON key
// path at fault; keys Telescope reads but does not use are collected in Scene::ignoredKeys.
#include "scene/scene_loader.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <tiny_obj_loader.h>

#include "core/error.h"
#include "scene/density_grid.h"
#include "scene/photon_levels.h"
#include "scene/transform.h"

namespace telescope {

// ---- Default pmfs (docs/ESTIMATORS.md section 1, "Defaults") ----
PmfSettings defaultPathDepthPmf() {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = 0.25f;
    p.origin = "default for path depth: on the shipped path-traced scenes E[D_j^2] falls ~0.5 per level, so a "
               "geometric pmf has finite variance only for r < 0.5; the auto pilot picks r = 0.22 to 0.29 there "
               "(docs/ACCURACY.md)";
    return p;
}

PmfSettings defaultTransmittancePmf() {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = 0.65f;
    p.origin = "default for ray marching: for a smooth density E[D_j^2] ~ 4^-j at cost 2^j, so the optimum is "
               "p(j) ~ 2^(-1.5 j), r = 1 - 2^-1.5 ~ 0.65 (finite variance and cost need 0.5 < r < 0.75)";
    return p;
}

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr float kPi = 3.14159265358979323846f;
constexpr uint32_t kMaxResolution = 16384;
constexpr uint32_t kMaxBounces = 1024;
constexpr uint32_t kMaxSpp = 1u << 24;
constexpr uint32_t kMaxPhotonCount = 1u << 27;  // photon paths per pass (4 GiB of photons at 32 bytes)

// Tungsten types that exist but Telescope does not implement (yet)
constexpr std::string_view kUnsupportedBsdfs[] = {
    "phong", "mixed", "conductor", "rough_conductor", "rough_dielectric", "smooth_coat",
    "thinsheet", "oren_nayar", "plastic", "rough_plastic", "rough_coat", "transparency",
    "lambertian_fiber", "rough_wire", "hair", "diffuse_transmission"};
constexpr std::string_view kUnsupportedPrimitives[] = {
    "curves", "cylinder", "instances", "infinite_sphere_cap", "minecraft_map", "skydome", "spot"};
constexpr std::string_view kUnsupportedCameras[] = {"thinlens", "equirectangular", "cubemap"};
constexpr std::string_view kUnsupportedIntegrators[] = {
    "bidirectional_path_tracer", "light_tracer",
    "kelemen_mlt", "multiplexed_mlt", "reversible_jump_mlt"};
constexpr std::string_view kFilters[] = {
    "dirac", "box", "tent", "gaussian", "mitchell_netravali", "catmull_rom", "lanczos"};

template <size_t N>
bool isOneOf(const std::string_view (&list)[N], std::string_view s) {
    return std::find(std::begin(list), std::end(list), s) != std::end(list);
}

bool isOneOf(std::initializer_list<std::string_view> list, std::string_view s) {
    return std::find(list.begin(), list.end(), s) != list.end();
}

// ---- JSON key paths ("primitives[3].transform.scale") ----

std::string member(const std::string& parent, std::string_view key) {
    return parent.empty() ? std::string(key) : parent + "." + std::string(key);
}

std::string element(const std::string& parent, size_t index) { return fmt::format("{}[{}]", parent, index); }

// A value as it appears in the file, shortened for messages.
std::string quote(const json& v) {
    std::string s = v.dump();
    if (s.size() > 40) s = s.substr(0, 37) + "...";
    return s;
}

// ---- Geometry helpers ----
bool isDegenerate(const glm::vec3& n) { return !(glm::dot(n, n) > 0.0f) || !std::isfinite(glm::dot(n, n)); }

Geometry triangle(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& normal) {
    Geometry g;
    g.type = GeometryType::Triangle;
    g.p0 = p0;
    g.p1 = p1;
    g.p2 = p2;
    g.normal = normal;
    return g;
}

// Two triangles for the parallelogram base + [0,1] e0 + [0,1] e1, wound so that
// cross(p1 - p0, p2 - p0) points along the given unit normal.
void appendParallelogram(std::vector<Geometry>& out, const glm::vec3& base, const glm::vec3& e0,
                         const glm::vec3& e1, const glm::vec3& normal) {
    const glm::vec3 a = glm::dot(glm::cross(e0, e1), normal) >= 0.0f ? e0 : e1;
    const glm::vec3 b = a == e0 ? e1 : e0;
    out.push_back(triangle(base, base + a, base + a + b, normal));
    out.push_back(triangle(base, base + a + b, base + b, normal));
}


// Line and column (1-based) of a byte offset, for parse errors.
std::pair<size_t, size_t> lineColumn(const std::string& text, size_t byte) {
    byte = std::min(byte, text.size());
    size_t line = 1, column = 1;
    for (size_t i = 0; i < byte; ++i) {
        if (text[i] == '\n') { ++line; column = 1; }
        else ++column;
    }
    return {line, column};
}

// ---- Overrides ----

struct KeyToken {
    bool isIndex = false;
    std::string name;
    size_t index = 0;
};

// Splits "primitives[2].bsdf" into primitives, [2], bsdf.
std::vector<KeyToken> parseKeyPath(const std::string& key, const std::string& sceneName) {
    auto malformed = [&](const std::string& why) {
        throw InputError("", key, fmt::format("malformed --set key path for {}: {}", sceneName, why));
    };
    std::vector<KeyToken> tokens;
    size_t i = 0;
    while (true) {
        const size_t start = i;
        while (i < key.size() && key[i] != '.' && key[i] != '[' && key[i] != ']') ++i;
        if (i == start) malformed("empty name");
        tokens.push_back({false, key.substr(start, i - start), 0});
        while (i < key.size() && key[i] == '[') {
            const size_t close = key.find(']', i);
            if (close == std::string::npos) malformed("missing ']'");
            const std::string digits = key.substr(i + 1, close - i - 1);
            if (digits.empty() || digits.size() > 9 ||
                !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
                malformed("index '" + digits + "' is not a non-negative integer");
            tokens.push_back({true, "", std::stoul(digits)});
            i = close + 1;
        }
        if (i == key.size()) return tokens;
        if (key[i] != '.') malformed(fmt::format("unexpected '{}'", key[i]));
        ++i;
    }
}

// Sets the value at the key path, creating missing object keys on the way.
void applyOverride(json& doc, const SceneOverride& o, const std::string& sceneName) {
    json* node = &doc;
    // The key and a bare-string value enter the document, which must stay valid UTF-8 to be
    // written out (fuzz/regressions/set-value-invalid-utf8.bin).
    try {
        (void)json(o.key + o.value).dump();
    } catch (const json::type_error&) {
        throw InputError("", "--set", fmt::format("the override of '{}' is not valid UTF-8 text",
                                                  json(o.key).dump(-1, ' ', false, json::error_handler_t::replace)));
    }
    std::string walked;
    for (const KeyToken& t : parseKeyPath(o.key, sceneName)) {
        if (t.isIndex) {
            if (!node->is_array())
                throw InputError("", o.key, fmt::format("--set: '{}' in {} is not an array", walked, sceneName));
            if (t.index >= node->size())
                throw InputError("", o.key,
                                 fmt::format("--set: index {} is out of range, '{}' in {} has {} elements",
                                             t.index, walked, sceneName, node->size()));
            node = &(*node)[t.index];
            walked = element(walked, t.index);
        } else {
            if (node->is_null()) *node = json::object();
            if (!node->is_object())
                throw InputError("", o.key,
                                 fmt::format("--set: '{}' in {} is a {}, not an object", walked.empty() ? "(top level)" : walked,
                                             sceneName, node->type_name()));
            node = &(*node)[t.name];
            walked = member(walked, t.name);
        }
    }
    json value = json::parse(o.value, nullptr, /*allow_exceptions=*/false);
    *node = value.is_discarded() ? json(o.value) : std::move(value);
}

// ---- Meshes on disk, in local space ----

struct MeshData {
    std::vector<glm::vec3> positions;
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<int32_t> materials;  // per triangle, index into the primitive's bsdf list
};

// ---- The interpreter ----

class SceneReader {
public:
    SceneReader(std::string file, fs::path baseDir, Scene& scene)
        : file_(std::move(file)), baseDir_(std::move(baseDir)), scene_(scene) {}

    void read(const json& doc);

private:
    [[noreturn]] void fail(const std::string& key, const std::string& what) const { throw InputError(file_, key, what); }

    // Typed values
    const json* find(const json& obj, std::string_view key) const;
    void expectObject(const json& v, const std::string& key) const;
    float number(const json& v, const std::string& key) const;
    uint32_t integer(const json& v, const std::string& key, uint32_t lo, uint32_t hi) const;
    bool boolean(const json& v, const std::string& key) const;
    std::string string(const json& v, const std::string& key) const;
    glm::vec3 vec3(const json& v, const std::string& key) const;
    glm::vec3 colour(const json& v, const std::string& key) const;
    glm::mat4 transform(const json& v, const std::string& key);

    // Bookkeeping of keys
    void ignore(const std::string& key);
    void ignoreUnread(const json& obj, const std::string& key, std::initializer_list<std::string_view> read);
    void rejectMedia(const json& obj, const std::string& key, std::initializer_list<std::string_view> keys) const;

    // Sections
    void readBsdfs(const json& list);
    Material readBsdf(const json& v, const std::string& key);
    uint32_t material(const json& ref, const std::string& key);
    void readPrimitive(const json& v, const std::string& key);
    void readCamera(const json& v);
    void readIntegrator(const json& v);
    void readDebias(const json& v, const std::string& key, bool photons = false);
    void readPhotonBlocks(const json& v, const std::string& key);
    void readPhotonSettings(const json& v, const std::string& key);
    void readRenderer(const json& v);

    // Participating media (docs/MEDIA.md)
    void readMedia(const json& list);
    Medium readMedium(const json& v, const std::string& key);
    TransmittanceModel readTransmittance(const json& v, const std::string& key, bool nested);
    DensityGrid readGrid(const json& v, const std::string& key);
    int32_t mediumRef(const json& ref, const std::string& key);
    void readTransmittanceEstimator(const json& v, const std::string& key);
    void checkEstimatorFitsMedia(const json& doc) const;

    // Geometry
    MeshData loadMesh(const json& v, const std::string& key) const;
    MeshData loadWo3(const fs::path& path, const std::string& key) const;
    MeshData loadObj(const fs::path& path, const std::string& key) const;

    std::string file_;
    fs::path baseDir_;
    Scene& scene_;
    std::set<std::string> ignoredSet_;
    std::vector<Material> namedBsdfs_;
    std::map<std::string, size_t> bsdfByName_;                 // first bsdf of each name
    std::vector<std::optional<uint32_t>> namedBsdfMaterial_;   // index in scene_.materials once used
    std::map<std::string, int32_t> mediumByName_;
};

// ---- Typed values ----

const json* SceneReader::find(const json& obj, std::string_view key) const {
    const auto it = obj.find(key);
    return it == obj.end() ? nullptr : &*it;
}

void SceneReader::expectObject(const json& v, const std::string& key) const {
    if (!v.is_object()) fail(key, "expected an object, got " + quote(v));
}

float SceneReader::number(const json& v, const std::string& key) const {
    if (!v.is_number()) fail(key, "expected a number, got " + quote(v));
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(key, "the number is not finite");
    if (!std::isfinite(static_cast<float>(d))) fail(key, "the number is too large for single precision");
    return static_cast<float>(d);
}

uint32_t SceneReader::integer(const json& v, const std::string& key, uint32_t lo, uint32_t hi) const {
    const std::string expected = fmt::format("expected an integer in [{}, {}], got {}", lo, hi, quote(v));
    if (!v.is_number()) fail(key, expected);
    const double d = v.get<double>();
    if (!std::isfinite(d) || d != std::floor(d) || d < lo || d > hi) fail(key, expected);
    return static_cast<uint32_t>(d);
}

bool SceneReader::boolean(const json& v, const std::string& key) const {
    if (!v.is_boolean()) fail(key, "expected true or false, got " + quote(v));
    return v.get<bool>();
}

std::string SceneReader::string(const json& v, const std::string& key) const {
    if (!v.is_string()) fail(key, "expected a string, got " + quote(v));
    return v.get<std::string>();
}

// A Vec3: a number (broadcast) or [x, y, z].
glm::vec3 SceneReader::vec3(const json& v, const std::string& key) const {
    if (v.is_number()) return glm::vec3(number(v, key));
    if (!v.is_array()) fail(key, "expected a number or an array of 3 numbers, got " + quote(v));
    if (v.size() != 3) fail(key, fmt::format("expected an array of 3 numbers, got {} elements", v.size()));
    return {number(v[0], element(key, 0)), number(v[1], element(key, 1)), number(v[2], element(key, 2))};
}

// A constant colour texture: a number or [r, g, b], non-negative. Bitmaps and procedural
// textures are rejected.
glm::vec3 SceneReader::colour(const json& v, const std::string& key) const {
    if (v.is_string()) fail(key, fmt::format("textures are not supported (bitmap {})", quote(v)));
    if (v.is_object()) fail(key, "textures are not supported (texture object)");
    const glm::vec3 c = vec3(v, key);
    if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) fail(key, "colour components must be non-negative");
    return c;
}

// A transform: a row-major 16-element array or a Tungsten transform object.
glm::mat4 SceneReader::transform(const json& v, const std::string& key) {
    if (v.is_array()) {
        if (v.size() != 16) fail(key, fmt::format("expected a 16-element matrix, got {} elements", v.size()));
        std::array<float, 16> a;
        for (size_t i = 0; i < 16; ++i) a[i] = number(v[i], element(key, i));
        return matrixFromRowMajor(a);
    }
    if (!v.is_object()) fail(key, "expected a transform object or a 16-element matrix, got " + quote(v));

    TransformSpec spec;
    auto optionalVec3 = [&](std::string_view name) -> std::optional<glm::vec3> {
        const json* f = find(v, name);
        if (!f) return std::nullopt;
        return vec3(*f, member(key, name));
    };
    auto nonZero = [&](const std::optional<glm::vec3>& axis, std::string_view name) {
        if (axis && glm::dot(*axis, *axis) == 0.0f) fail(member(key, name), "the axis has zero length");
    };
    spec.position = optionalVec3("position").value_or(glm::vec3(0.0f));
    spec.lookAt = optionalVec3("look_at");
    spec.up = optionalVec3("up");
    spec.xAxis = optionalVec3("x_axis");
    spec.yAxis = optionalVec3("y_axis");
    spec.zAxis = optionalVec3("z_axis");
    spec.scale = optionalVec3("scale").value_or(glm::vec3(1.0f));
    spec.rotationDegrees = optionalVec3("rotation").value_or(glm::vec3(0.0f));
    if (spec.lookAt && *spec.lookAt == spec.position) fail(member(key, "look_at"), "look_at equals position");
    nonZero(spec.up, "up");
    nonZero(spec.xAxis, "x_axis");
    nonZero(spec.yAxis, "y_axis");
    nonZero(spec.zAxis, "z_axis");
    ignoreUnread(v, key, {"position", "look_at", "up", "x_axis", "y_axis", "z_axis", "scale", "rotation"});
    return buildTransform(spec);
}

// ---- Bookkeeping of keys ----

void SceneReader::ignore(const std::string& key) {
    if (ignoredSet_.insert(key).second) scene_.ignoredKeys.push_back(key);
}

void SceneReader::ignoreUnread(const json& obj, const std::string& key, std::initializer_list<std::string_view> read) {
    for (const auto& [name, value] : obj.items())
        if (!isOneOf(read, name)) ignore(member(key, name));
}

void SceneReader::rejectMedia(const json& obj, const std::string& key, std::initializer_list<std::string_view> keys) const {
    for (std::string_view name : keys)
        if (const json* m = find(obj, name); m && !m->is_null())
            fail(member(key, name), "media are set on primitives (int_medium, ext_medium) and the camera (medium)");
}

// ---- Top level ----

void SceneReader::read(const json& doc) {
    if (!doc.is_object()) fail("", "the top level must be a JSON object, got " + quote(doc));

    if (const json* media = find(doc, "media")) {
        if (!media->is_array() && !media->is_null()) fail("media", "expected an array, got " + quote(*media));
        if (media->is_array()) readMedia(*media);
    }
    if (const json* bsdfs = find(doc, "bsdfs")) readBsdfs(*bsdfs);
    if (const json* primitives = find(doc, "primitives")) {
        if (!primitives->is_array()) fail("primitives", "expected an array, got " + quote(*primitives));
        for (size_t i = 0; i < primitives->size(); ++i) readPrimitive((*primitives)[i], element("primitives", i));
    }
    readCamera(find(doc, "camera") ? doc["camera"] : json::object());
    if (const json* integrator = find(doc, "integrator")) readIntegrator(*integrator);
    if (const json* renderer = find(doc, "renderer")) readRenderer(*renderer);
    checkEstimatorFitsMedia(doc);
    // The photon gather pass samples dirac, box and tent only; the wide filters are path tracing's.
    if (usesPhotons(scene_.integrator) && !isOneOf({"dirac", "box", "tent"}, scene_.camera.filter))
        fail("camera.reconstruction_filter",
             fmt::format("photon mapping supports the dirac, box and tent filters, not '{}'", scene_.camera.filter));
    ignoreUnread(doc, "", {"media", "bsdfs", "primitives", "camera", "integrator", "renderer"});
}

// ---- BSDFs ----

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
    expectObject(v, key);
    const json* typeValue = find(v, "type");
    if (!typeValue) fail(key, "missing 'type'");
    const std::string type = string(*typeValue, member(key, "type"));

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

// ---- Primitives ----

void SceneReader::readPrimitive(const json& v, const std::string& key) {
    expectObject(v, key);
    const json* typeValue = find(v, "type");
    if (!typeValue) fail(key, "missing 'type'");
    const std::string typeKey = member(key, "type");
    const std::string type = string(*typeValue, typeKey);
    const bool known = isOneOf({"quad", "cube", "sphere", "disk", "mesh", "point", "infinite_sphere"}, type);
    if (!known && isOneOf(kUnsupportedPrimitives, type)) fail(typeKey, fmt::format("unsupported primitive type '{}'", type));
    if (!known) fail(typeKey, fmt::format("unknown primitive type '{}'", type));

    Shape shape{"", type};
    if (const json* name = find(v, "name")) shape.name = string(*name, member(key, "name"));
    const uint32_t shapeIndex = static_cast<uint32_t>(scene_.shapes.size());
    scene_.shapes.push_back(shape);
    // Media on the two sides: a missing one of the two is vacuum; neither leaves the medium unchanged.
    const json* intMedium = find(v, "int_medium");
    const json* extMedium = find(v, "ext_medium");
    const bool hasMedia = (intMedium && !intMedium->is_null()) || (extMedium && !extMedium->is_null());
    const int32_t intIndex = intMedium && !intMedium->is_null() ? mediumRef(*intMedium, member(key, "int_medium")) : -1;
    const int32_t extIndex = extMedium && !extMedium->is_null() ? mediumRef(*extMedium, member(key, "ext_medium")) : -1;

    const glm::mat4 m = find(v, "transform") ? transform(v["transform"], member(key, "transform")) : glm::mat4(1.0f);

    // Emission: radiance, or power converted with the shape's power-to-radiance factor
    std::optional<glm::vec3> emission, power;
    if (const json* e = find(v, "emission")) emission = colour(*e, member(key, "emission"));
    if (const json* p = find(v, "power")) power = colour(*p, member(key, "power"));
    if (emission && power) ignore(member(key, "emission"));

    // Point and environment lights
    if (type == "point" || type == "infinite_sphere") {
        PointLikeLight light;
        light.type = type == "point" ? LightType::Point : LightType::Environment;
        light.position = glm::vec3(m[3]);
        light.intensity = power ? *power / (4.0f * kPi) : emission.value_or(glm::vec3(0.0f));
        light.name = shape.name;
        if (light.intensity != glm::vec3(0.0f)) scene_.lights.push_back(light);
        ignoreUnread(v, key, {"name", "type", "transform", "emission", "power"});
        return;
    }

    // Surfaces: material(s), world-space geometry and area
    const json* bsdf = find(v, "bsdf");
    if (!bsdf) fail(key, "missing 'bsdf'");
    std::vector<uint32_t> materials;
    if (type == "mesh" && bsdf->is_array()) {
        if (bsdf->empty()) fail(member(key, "bsdf"), "the bsdf array is empty");
        for (size_t i = 0; i < bsdf->size(); ++i) materials.push_back(material((*bsdf)[i], element(member(key, "bsdf"), i)));
    } else {
        materials.push_back(material(*bsdf, member(key, "bsdf")));
    }

    std::vector<Geometry> shapeGeometry;
    double area = 0.0;
    if (type == "quad") {
        // Unit square in local XZ at y = 0; normal = edge1 x edge0 (local +Y)
        const glm::vec3 e0 = transformVector(m, {1, 0, 0}), e1 = transformVector(m, {0, 0, 1});
        const glm::vec3 n = glm::cross(e1, e0);
        area = glm::length(n);
        if (!isDegenerate(n)) appendParallelogram(shapeGeometry, transformPoint(m, glm::vec3(0.0f)) - 0.5f * (e0 + e1), e0, e1, n / float(area));
    } else if (type == "cube") {
        // Unit cube [-0.5, 0.5]^3 placed by the rotation, column lengths and translation of M
        const glm::mat3 rot = columnDirections(m);
        const glm::vec3 half = 0.5f * columnLengths(m), centre(m[3]);
        for (int dim = 0; dim < 3; ++dim) {
            const int s = (dim + 1) % 3, t = (dim + 2) % 3;
            area += 8.0 * half[s] * half[t];
            for (float sign : {-1.0f, 1.0f}) {
                const glm::vec3 n = sign * rot[dim];
                const glm::vec3 u = 2.0f * half[s] * rot[s], w = 2.0f * half[t] * rot[t];
                if (isDegenerate(glm::cross(u, w)) || isDegenerate(n)) continue;
                appendParallelogram(shapeGeometry, centre + half[dim] * n - 0.5f * (u + w), u, w, n);
            }
        }
    } else if (type == "sphere") {
        // Unit sphere: radius = largest column length
        const glm::vec3 lengths = columnLengths(m);
        Geometry g;
        g.type = GeometryType::Sphere;
        g.p0 = glm::vec3(m[3]);
        g.radius = std::max({lengths.x, lengths.y, lengths.z});
        area = 4.0 * kPi * double(g.radius) * g.radius;
        if (g.radius > 0.0f) shapeGeometry.push_back(g);
    } else if (type == "disk") {
        // Unit disk in local XZ facing local +Y (Tungsten Disk: r = max of the X and Z column lengths)
        const glm::vec3 lengths = columnLengths(m);
        const glm::vec3 n = transformVector(m, {0, 1, 0});
        Geometry g;
        g.type = GeometryType::Disk;
        g.p0 = glm::vec3(m[3]);
        g.radius = std::max(lengths.x, lengths.z);
        area = kPi * double(g.radius) * g.radius;
        if (g.radius > 0.0f && !isDegenerate(n)) {
            g.normal = glm::normalize(n);
            shapeGeometry.push_back(g);
        }
    } else {
        // Mesh: vertices by M, geometric normal cross(p1 - p0, p2 - p0), flat shading
        const MeshData mesh = loadMesh(v, key);
        std::vector<glm::vec3> world(mesh.positions.size());
        for (size_t i = 0; i < world.size(); ++i) world[i] = transformPoint(m, mesh.positions[i]);
        for (size_t i = 0; i < mesh.triangles.size(); ++i) {
            const auto& t = mesh.triangles[i];
            const glm::vec3 n = glm::cross(world[t[1]] - world[t[0]], world[t[2]] - world[t[0]]);
            if (isDegenerate(n)) continue;
            area += 0.5 * glm::length(n);
            Geometry g = triangle(world[t[0]], world[t[1]], world[t[2]], glm::normalize(n));
            g.material = materials[std::clamp<int32_t>(mesh.materials[i], 0, int32_t(materials.size()) - 1)];
            shapeGeometry.push_back(g);
        }
    }

    glm::vec3 radiance = emission.value_or(glm::vec3(0.0f));
    if (power) {
        if (!(area > 0.0) && *power != glm::vec3(0.0f)) fail(member(key, "power"), "power on a primitive with zero area");
        radiance = area > 0.0 ? *power / float(kPi * area) : glm::vec3(0.0f);
    }
    for (Geometry& g : shapeGeometry) {
        if (type != "mesh") g.material = materials[0];
        g.emission = radiance;
        g.shape = shapeIndex;
        g.hasMedia = hasMedia;
        g.intMedium = intIndex;
        g.extMedium = extIndex;
        scene_.geometry.push_back(g);
    }
    ignoreUnread(v, key, {"name", "type", "transform", "bsdf", "emission", "power", "file", "int_medium", "ext_medium"});
}

// ---- Meshes ----

MeshData SceneReader::loadMesh(const json& v, const std::string& key) const {
    const std::string fileKey = member(key, "file");
    const json* fileValue = find(v, "file");
    if (!fileValue) fail(key, "missing 'file'");
    const fs::path relative = string(*fileValue, fileKey);
    const fs::path path = relative.is_absolute() ? relative : baseDir_ / relative;

    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (ext != ".wo3" && ext != ".obj")
        fail(fileKey, fmt::format("unsupported mesh format '{}' (expected .wo3 or .obj)", path.string()));
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) fail(fileKey, fmt::format("cannot open mesh file '{}'", path.string()));
    return ext == ".wo3" ? loadWo3(path, fileKey) : loadObj(path, fileKey);
}

// .wo3: uint64 vertex count, {pos, normal, uv} float records, uint64 triangle count,
// {uint32 v0, v1, v2; int32 material} records; little-endian, no header.
MeshData SceneReader::loadWo3(const fs::path& path, const std::string& key) const {
    static_assert(std::endian::native == std::endian::little, ".wo3 is read with memcpy");
    constexpr uint64_t kVertexBytes = 32, kTriangleBytes = 16;
    auto malformed = [&](const std::string& why) -> void { fail(key, fmt::format("malformed .wo3 '{}': {}", path.string(), why)); };

    std::ifstream in(path, std::ios::binary);
    if (!in) fail(key, fmt::format("cannot open mesh file '{}'", path.string()));
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());

    uint64_t offset = 0;
    auto readU64 = [&]() {
        uint64_t n = 0;
        if (bytes.size() - offset < 8) malformed("the file is truncated");
        std::memcpy(&n, bytes.data() + offset, 8);
        offset += 8;
        return n;
    };
    MeshData mesh;
    const uint64_t numVerts = readU64();
    if (numVerts > (bytes.size() - offset) / kVertexBytes) malformed(fmt::format("{} vertices do not fit in the file", numVerts));
    mesh.positions.resize(numVerts);
    for (uint64_t i = 0; i < numVerts; ++i) std::memcpy(&mesh.positions[i], bytes.data() + offset + i * kVertexBytes, 12);
    offset += numVerts * kVertexBytes;

    const uint64_t numTris = readU64();
    if (numTris > (bytes.size() - offset) / kTriangleBytes) malformed(fmt::format("{} triangles do not fit in the file", numTris));
    if (offset + numTris * kTriangleBytes != bytes.size())
        malformed(fmt::format("{} bytes after the triangle list", bytes.size() - offset - numTris * kTriangleBytes));
    mesh.triangles.resize(numTris);
    mesh.materials.resize(numTris);
    for (uint64_t i = 0; i < numTris; ++i) {
        const char* record = bytes.data() + offset + i * kTriangleBytes;
        std::memcpy(mesh.triangles[i].data(), record, 12);
        std::memcpy(&mesh.materials[i], record + 12, 4);
        for (uint32_t index : mesh.triangles[i])
            if (index >= numVerts) malformed(fmt::format("triangle {} uses vertex {} of {}", i, index, numVerts));
    }
    for (uint64_t i = 0; i < numVerts; ++i)
        if (!std::isfinite(mesh.positions[i].x) || !std::isfinite(mesh.positions[i].y) || !std::isfinite(mesh.positions[i].z))
            malformed(fmt::format("vertex {} is not finite", i));
    return mesh;
}

// .obj through tinyobjloader, triangulated; per-triangle material = usemtl index (0 if none).
MeshData SceneReader::loadObj(const fs::path& path, const std::string& key) const {
    auto malformed = [&](std::string why) -> void {
        while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
        std::replace(why.begin(), why.end(), '\n', ' ');
        fail(key, fmt::format("malformed .obj '{}': {}", path.string(), why));
    };
    tinyobj::ObjReaderConfig config;
    config.triangulate = true;
    config.vertex_color = false;
    config.mtl_search_path = path.parent_path().string();
    tinyobj::ObjReader reader;
    if (!reader.ParseFromFile(path.string(), config)) malformed(reader.Error().empty() ? "parse failed" : reader.Error());

    MeshData mesh;
    const std::vector<tinyobj::real_t>& v = reader.GetAttrib().vertices;
    if (v.size() % 3 != 0) malformed("incomplete vertex list");
    mesh.positions.resize(v.size() / 3);
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
        mesh.positions[i] = {v[3 * i], v[3 * i + 1], v[3 * i + 2]};
        if (!std::isfinite(v[3 * i]) || !std::isfinite(v[3 * i + 1]) || !std::isfinite(v[3 * i + 2]))
            malformed(fmt::format("vertex {} is not finite", i + 1));
    }
    for (const tinyobj::shape_t& shape : reader.GetShapes()) {
        const tinyobj::mesh_t& m = shape.mesh;
        size_t first = 0;
        for (size_t f = 0; f < m.num_face_vertices.size(); ++f) {
            const size_t count = m.num_face_vertices[f];
            if (count != 3) malformed(fmt::format("face with {} vertices after triangulation", count));
            std::array<uint32_t, 3> tri;
            for (size_t k = 0; k < 3; ++k) {
                const int index = m.indices[first + k].vertex_index;
                if (index < 0 || size_t(index) >= mesh.positions.size())
                    malformed(fmt::format("a face in '{}' uses vertex {} of {}", shape.name, index + 1, mesh.positions.size()));
                tri[k] = uint32_t(index);
            }
            mesh.triangles.push_back(tri);
            mesh.materials.push_back(f < m.material_ids.size() ? std::max(m.material_ids[f], 0) : 0);
            first += count;
        }
    }
    return mesh;
}

// ---- Camera ----

void SceneReader::readCamera(const json& v) {
    const std::string key = "camera";
    expectObject(v, key);
    Camera& cam = scene_.camera;

    const std::string type = find(v, "type") ? string(v["type"], "camera.type") : "pinhole";
    if (isOneOf(kUnsupportedCameras, type)) fail("camera.type", fmt::format("unsupported camera type '{}'", type));
    if (type != "pinhole") fail("camera.type", fmt::format("unknown camera type '{}'", type));
    if (const json* medium = find(v, "medium"); medium && !medium->is_null()) cam.medium = mediumRef(*medium, "camera.medium");

    if (const json* fov = find(v, "fov")) {
        cam.fovDegrees = number(*fov, "camera.fov");
        if (!(cam.fovDegrees > 0.0f && cam.fovDegrees < 180.0f)) fail("camera.fov", "the field of view must be in (0, 180) degrees");
    }
    if (const json* res = find(v, "resolution")) {
        if (res->is_array()) {
            if (res->size() != 2) fail("camera.resolution", fmt::format("expected [width, height], got {} elements", res->size()));
            cam.width = integer((*res)[0], "camera.resolution[0]", 1, kMaxResolution);
            cam.height = integer((*res)[1], "camera.resolution[1]", 1, kMaxResolution);
        } else {
            cam.width = cam.height = integer(*res, "camera.resolution", 1, kMaxResolution);
        }
    }
    if (const json* filter = find(v, "reconstruction_filter")) {
        cam.filter = string(*filter, "camera.reconstruction_filter");
        if (!isOneOf(kFilters, cam.filter))
            fail("camera.reconstruction_filter", fmt::format("unknown reconstruction filter '{}'", cam.filter));
    }

    // Basis: z = forward, y = up; image right = forward x up (Tungsten negates its basis x)
    const glm::mat4 m = find(v, "transform") ? transform(v["transform"], "camera.transform") : glm::mat4(1.0f);
    const glm::vec3 forward = transformVector(m, {0, 0, 1}), up = transformVector(m, {0, 1, 0});
    const glm::vec3 right = glm::cross(forward, up);
    if (isDegenerate(forward) || isDegenerate(right)) fail("camera.transform", "the camera basis is degenerate");
    cam.position = glm::vec3(m[3]);
    cam.forward = glm::normalize(forward);
    cam.right = glm::normalize(right);
    cam.up = glm::cross(cam.right, cam.forward);

    ignoreUnread(v, key, {"type", "fov", "resolution", "reconstruction_filter", "transform", "medium"});
}

// ---- Integrator ----

void SceneReader::readIntegrator(const json& v) {
    const std::string key = "integrator";
    expectObject(v, key);
    IntegratorSettings& s = scene_.integrator;

    const std::string type = find(v, "type") ? string(v["type"], "integrator.type") : "path_tracer";
    if (isOneOf(kUnsupportedIntegrators, type)) fail("integrator.type", fmt::format("unsupported integrator type '{}'", type));
    if (type == "photon_map" || type == "progressive_photon_map") {
        s.type = type == "photon_map" ? IntegratorType::PhotonMap : IntegratorType::ProgressivePhotonMap;
        readPhotonSettings(v, key);
        return;
    }
    if (type != "path_tracer") fail("integrator.type", fmt::format("unknown integrator type '{}'", type));
    s.type = IntegratorType::PathTracer;

    if (const json* n = find(v, "min_bounces")) s.minBounces = integer(*n, "integrator.min_bounces", 0, kMaxBounces);
    if (const json* n = find(v, "max_bounces")) s.maxBounces = integer(*n, "integrator.max_bounces", 0, kMaxBounces);
    if (const json* b = find(v, "enable_light_sampling")) s.enableLightSampling = boolean(*b, "integrator.enable_light_sampling");
    if (const json* b = find(v, "enable_two_sided_shading"))
        s.enableTwoSidedShading = boolean(*b, "integrator.enable_two_sided_shading");
    if (const json* d = find(v, "debias"); d && !d->is_null()) readDebias(*d, "integrator.debias");
    if (const json* t = find(v, "transmittance_estimator"); t && !t->is_null())
        readTransmittanceEstimator(*t, "integrator.transmittance_estimator");

    ignoreUnread(v, key, {"type", "min_bounces", "max_bounces", "enable_light_sampling", "enable_two_sided_shading", "debias",
                          "transmittance_estimator"});
}

// photon_map and progressive_photon_map: Tungsten's keys (photon_count, gather_radius, alpha,
// max_bounces) plus Telescope's debias, direct_lighting and kernel. The gather radius is
// required: Tungsten's default (1e30 with a k-nearest-neighbour cap) has no meaning for the
// fixed-radius estimators here.
void SceneReader::readPhotonSettings(const json& v, const std::string& key) {
    IntegratorSettings& s = scene_.integrator;
    PhotonSettings& p = s.photon;
    const std::string type = string(v["type"], "integrator.type");
    for (const PointLikeLight& l : scene_.lights)
        if (l.type == LightType::Environment)
            fail("integrator.type", fmt::format("'{}' does not support infinite_sphere emitters (light '{}')", type, l.name));

    if (const json* n = find(v, "min_bounces"); n && integer(*n, "integrator.min_bounces", 0, kMaxBounces) != 0)
        fail("integrator.min_bounces", "photon mapping supports only min_bounces = 0");
    if (const json* n = find(v, "max_bounces")) s.maxBounces = integer(*n, "integrator.max_bounces", 0, kMaxBounces);
    if (const json* b = find(v, "enable_two_sided_shading"))
        s.enableTwoSidedShading = boolean(*b, "integrator.enable_two_sided_shading");
    if (const json* n = find(v, "photon_count"))
        p.photonCount = integer(*n, "integrator.photon_count", 1, kMaxPhotonCount);

    const json* radius = find(v, "gather_radius");
    if (!radius) fail("integrator.gather_radius", fmt::format("missing: '{}' needs a gather radius in scene units", type));
    p.gatherRadius = number(*radius, "integrator.gather_radius");
    if (!(p.gatherRadius > 0.0f)) fail("integrator.gather_radius", fmt::format("must be positive, got {}", p.gatherRadius));

    if (const json* a = find(v, "alpha")) {
        p.alpha = number(*a, "integrator.alpha");
        if (!(p.alpha > 0.0f && p.alpha < 1.0f)) fail("integrator.alpha", fmt::format("alpha must be in (0, 1), got {}", p.alpha));
    }
    if (const json* k = find(v, "kernel")) {
        const std::string name = string(*k, "integrator.kernel");
        if (name == "cone") p.kernel = PhotonKernel::Cone;
        else if (name == "uniform") p.kernel = PhotonKernel::Uniform;
        else if (name == "epanechnikov") p.kernel = PhotonKernel::Epanechnikov;
        else fail("integrator.kernel", fmt::format("unknown kernel '{}' (expected \"cone\", \"uniform\" or \"epanechnikov\")", name));
    }
    if (const json* d = find(v, "direct_lighting")) {
        const std::string name = string(*d, "integrator.direct_lighting");
        if (name == "photons") p.directLighting = DirectLighting::Photons;
        else if (name == "next_event") p.directLighting = DirectLighting::NextEvent;
        else fail("integrator.direct_lighting",
                  fmt::format("unknown direct lighting '{}' (expected \"photons\" or \"next_event\")", name));
    }
    if (const json* d = find(v, "debias"); d && !d->is_null()) {
        readDebias(*d, "integrator.debias", true);
        readPhotonBlocks(*d, "integrator.debias");
    }
    ignoreUnread(v, key, {"type", "min_bounces", "max_bounces", "enable_two_sided_shading", "photon_count",
                          "gather_radius", "alpha", "kernel", "direct_lighting", "debias"});
}

// Photon mapping's blocks (docs/PHOTON-MAPPING.md): the geometric level pmf (r = 0.7 by default,
// continuing with q = 0.3), area_ratio s, photon_growth m, level_cap K and the schedule
// (uniform by default). Settings whose expected cost is infinite (q m >= 1) or whose samples
// have no finite mean (tail index a <= 1, i.e. m s <= 1) are rejected.
void SceneReader::readPhotonBlocks(const json& v, const std::string& key) {
    DebiasSettings& d = scene_.integrator.debias;
    PhotonBlockSettings& b = d.photon;
    if (d.estimator != DebiasEstimator::SingleTerm)
        fail(member(key, "estimator"), "photon mapping supports only the \"single_term\" estimator");
    if (!v.contains("pmf")) {
        d.pmf.type = PmfType::Geometric;
        d.pmf.r = 0.7f;
        d.pmf.origin = "default for photon mapping's blocks: r = 0.7 (continue with q = 0.3) with m = 3, s = 1/sqrt(2): "
                       "7 passes per sample, tail index 1.45, typical error ~ cost^-0.31 (docs/PHOTON-MAPPING.md)";
    } else if (d.pmf.type != PmfType::Geometric) {
        fail(member(member(key, "pmf"), "type"),
             "photon mapping's block levels take a \"geometric\" pmf (expected photon passes are infinite with a "
             "power law, and there is no pilot for \"auto\")");
    }
    d.schedule = LevelSchedule::Uniform;
    if (const json* schedule = find(v, "level_schedule")) {
        const std::string scheduleKey = member(key, "level_schedule");
        const std::string name = string(*schedule, scheduleKey);
        if (name == "uniform") d.schedule = LevelSchedule::Uniform;
        else if (name == "per_pixel") d.schedule = LevelSchedule::PerPixel;
        else fail(scheduleKey, fmt::format("photon mapping takes the level schedule \"uniform\" or \"per_pixel\", got '{}'", name));
        if (d.schedule == LevelSchedule::PerPixel && scene_.integrator.type == IntegratorType::ProgressivePhotonMap)
            fail(scheduleKey, "progressive_photon_map shrinks the base radius per block, which needs the \"uniform\" schedule");
    }
    if (const json* a = find(v, "area_ratio")) {
        const std::string areaKey = member(key, "area_ratio");
        b.areaRatio = number(*a, areaKey);
        if (!(b.areaRatio > 0.0f && b.areaRatio < 1.0f)) fail(areaKey, fmt::format("must be in (0, 1), got {}", b.areaRatio));
    }
    if (const json* m = find(v, "photon_growth")) b.photonGrowth = integer(*m, member(key, "photon_growth"), 1, 1024);
    const PhotonBlockTheory t = photonBlockTheory(d.pmf.r, b.areaRatio, b.photonGrowth);
    if (!(t.q * b.photonGrowth < 1.0))
        fail(member(key, "photon_growth"),
             fmt::format("the expected photon passes per sample (1 - q) / (1 - q m) are infinite: q m = {:.4g} >= 1 "
                         "(q = 1 - pmf.r = {:.4g}, m = {})",
                         t.q * b.photonGrowth, t.q, b.photonGrowth));
    if (!(t.tailIndex > 1.0))
        fail(member(key, "photon_growth"),
             fmt::format("the samples have no finite mean: tail index a = ln(1/q) / (ln(1/q) - ln(m s) / 2) = {:.4g} <= 1 "
                         "(needs photon_growth x area_ratio > 1, got {} x {:.4g} = {:.4g})",
                         t.tailIndex, b.photonGrowth, b.areaRatio, b.photonGrowth * b.areaRatio));
    const std::string capKey = member(key, "level_cap");
    if (const json* k = find(v, "level_cap")) b.levelCap = integer(*k, capKey, 1, 64);
    else b.levelCap = photonDefaultLevelCap(b.areaRatio);
    const double longest = std::pow(double(b.photonGrowth), double(b.levelCap) - 1.0);
    if (!(longest < 2147483648.0))
        fail(capKey, fmt::format("a block at the last level would take m^(K-1) = {:.4g} photon passes (at most 2^31); "
                                 "lower the cap (K = {}{}) or photon_growth",
                                 longest, b.levelCap, find(v, "level_cap") ? "" : ", the default for this area_ratio"));
}

// Telescope's own block, read strictly: every key must be known.
void SceneReader::readDebias(const json& v, const std::string& key, bool photons) {
    expectObject(v, key);
    auto rejectUnknown = [&](const json& obj, const std::string& objKey, std::initializer_list<std::string_view> known) {
        for (const auto& [name, value] : obj.items())
            if (!isOneOf(known, name)) fail(member(objKey, name), fmt::format("unknown key '{}' in {}", name, objKey));
    };
    if (photons) rejectUnknown(v, key, {"estimator", "pmf", "level_schedule", "area_ratio", "photon_growth", "level_cap"});
    else rejectUnknown(v, key, {"estimator", "pmf", "level_schedule", "test_pmf_weight"});
    DebiasSettings& d = scene_.integrator.debias;
    if (const json* w = find(v, "test_pmf_weight")) {
        const std::string wKey = member(key, "test_pmf_weight");
        d.testPmfWeight = number(*w, wKey);
        if (!(d.testPmfWeight > 0.0f && std::isfinite(d.testPmfWeight)))
            fail(wKey, fmt::format("test_pmf_weight must be positive, got {}", d.testPmfWeight));
    }

    const std::string estimatorKey = member(key, "estimator");
    const json* estimator = find(v, "estimator");
    if (!estimator) fail(estimatorKey, "missing (expected \"single_term\" or \"sum\")");
    const std::string name = string(*estimator, estimatorKey);
    if (name == "single_term") d.estimator = DebiasEstimator::SingleTerm;
    else if (name == "sum") d.estimator = DebiasEstimator::Sum;
    else fail(estimatorKey, fmt::format("unknown debias estimator '{}' (expected \"single_term\" or \"sum\")", name));

    if (const json* schedule = find(v, "level_schedule"); schedule && !photons) {
        const std::string scheduleKey = member(key, "level_schedule");
        const std::string s = string(*schedule, scheduleKey);
        if (s == "per_pixel") d.schedule = LevelSchedule::PerPixel;
        else if (s == "uniform") d.schedule = LevelSchedule::Uniform;
        else if (s == "queued") d.schedule = LevelSchedule::Queued;
        else fail(scheduleKey, fmt::format("unknown level schedule '{}' (expected \"per_pixel\", \"uniform\" or \"queued\")", s));
    }

    const json* pmf = find(v, "pmf");
    if (!pmf) return;
    const std::string pmfKey = member(key, "pmf");
    expectObject(*pmf, pmfKey);
    const std::string type = find(*pmf, "type") ? string((*pmf)["type"], member(pmfKey, "type")) : "geometric";
    auto openUnit = [&](const char* field) {
        const std::string fieldKey = member(pmfKey, field);
        const float x = number((*pmf)[field], fieldKey);
        if (!(x > 0.0f && x < 1.0f)) fail(fieldKey, fmt::format("{} must be in (0, 1), got {}", field, x));
        return x;
    };
    d.pmf.origin = "given in the scene";
    if (type == "geometric") {
        rejectUnknown(*pmf, pmfKey, {"type", "r"});
        d.pmf.type = PmfType::Geometric;
        if (find(*pmf, "r")) d.pmf.r = openUnit("r");
    } else if (type == "power_law") {
        rejectUnknown(*pmf, pmfKey, {"type", "alpha"});
        d.pmf.type = PmfType::PowerLaw;
        if (find(*pmf, "alpha")) d.pmf.alpha = openUnit("alpha");
    } else if (type == "auto") {
        rejectUnknown(*pmf, pmfKey, {"type", "pilot_spp", "pilot_levels"});
        d.pmf.type = PmfType::Auto;
        if (const json* s = find(*pmf, "pilot_spp")) d.pmf.pilotSpp = integer(*s, member(pmfKey, "pilot_spp"), 1, 1024);
        if (const json* l = find(*pmf, "pilot_levels"))
            d.pmf.pilotLevels = integer(*l, member(pmfKey, "pilot_levels"), 3, 32);
    } else {
        fail(member(pmfKey, "type"),
             fmt::format("unknown pmf type '{}' (expected \"geometric\", \"power_law\" or \"auto\")", type));
    }
}

// ---- Renderer ----

void SceneReader::readRenderer(const json& v) {
    expectObject(v, "renderer");
    if (const json* spp = find(v, "spp")) scene_.renderer.spp = integer(*spp, "renderer.spp", 1, kMaxSpp);
    ignoreUnread(v, "renderer", {"spp"});
}

// ---- Participating media ----

// Every key of a Telescope-only object must be known.
void rejectUnknownKeys(const json& obj, const std::string& objKey, std::initializer_list<std::string_view> known,
                       const std::string& file) {
    for (const auto& [name, value] : obj.items())
        if (!isOneOf(known, name)) throw InputError(file, member(objKey, name), fmt::format("unknown key '{}' in {}", name, objKey));
}

void SceneReader::readMedia(const json& list) {
    for (size_t i = 0; i < list.size(); ++i) {
        const std::string key = element("media", i);
        Medium m = readMedium(list[i], key);
        if (!m.name.empty()) mediumByName_.emplace(m.name, int32_t(scene_.media.size()));
        scene_.media.push_back(std::move(m));
    }
}

// A medium reference: a name from the media list or an inline medium object.
int32_t SceneReader::mediumRef(const json& ref, const std::string& key) {
    if (ref.is_string()) {
        const auto it = mediumByName_.find(ref.get<std::string>());
        if (it == mediumByName_.end()) fail(key, fmt::format("unknown medium '{}'", ref.get<std::string>()));
        return it->second;
    }
    if (ref.is_object()) {
        scene_.media.push_back(readMedium(ref, key));
        return int32_t(scene_.media.size() - 1);
    }
    fail(key, "expected a medium name or an inline medium object, got " + quote(ref));
}

Medium SceneReader::readMedium(const json& v, const std::string& key) {
    expectObject(v, key);
    const json* typeValue = find(v, "type");
    if (!typeValue) fail(key, "missing 'type'");
    const std::string typeKey = member(key, "type");
    const std::string type = string(*typeValue, typeKey);
    Medium m;
    if (type == "homogeneous") m.type = MediumType::Homogeneous;
    else if (type == "exponential") m.type = MediumType::Exponential;
    else if (type == "voxel") m.type = MediumType::Grid;
    else if (type == "atmosphere") fail(typeKey, "unsupported medium type 'atmosphere'");
    else fail(typeKey, fmt::format("unknown medium type '{}' (expected \"homogeneous\", \"exponential\" or \"voxel\")", type));

    if (const json* name = find(v, "name")) m.name = string(*name, member(key, "name"));
    auto nonNegative = [&](const char* field, glm::vec3 fallback) {
        const json* f = find(v, field);
        if (!f) return fallback;
        glm::vec3 c = vec3(*f, member(key, field));
        if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) fail(member(key, field), "must be non-negative");
        return c;
    };
    m.sigmaA = nonNegative("sigma_a", glm::vec3(0.0f));
    m.sigmaS = nonNegative("sigma_s", glm::vec3(0.0f));
    if (const json* d = find(v, "density")) {
        m.density = number(*d, member(key, "density"));
        if (m.density < 0.0f) fail(member(key, "density"), "must be non-negative");
    }
    std::vector<std::string_view> read = {"name", "type", "sigma_a", "sigma_s", "density", "phase_function", "transmittance",
                                          "max_bounces"};
    if (find(v, "max_bounces")) ignore(member(key, "max_bounces"));

    if (m.type == MediumType::Exponential) {
        if (const json* f = find(v, "falloff_scale")) {
            m.falloffScale = number(*f, member(key, "falloff_scale"));
            if (m.falloffScale < 0.0f) fail(member(key, "falloff_scale"), "must be non-negative");
        }
        if (const json* f = find(v, "unit_point")) m.unitPoint = vec3(*f, member(key, "unit_point"));
        if (const json* f = find(v, "falloff_direction")) {
            glm::vec3 d = vec3(*f, member(key, "falloff_direction"));
            if (isDegenerate(d)) fail(member(key, "falloff_direction"), "the direction has zero length");
            m.falloffDirection = glm::normalize(d);
        }
        read.insert(read.end(), {"falloff_scale", "unit_point", "falloff_direction"});
    }
    if (m.type == MediumType::Grid) {
        const json* grid = find(v, "grid");
        if (!grid) fail(key, "missing 'grid' (a voxel medium needs a grid)");
        m.grid = readGrid(*grid, member(key, "grid"));
        read.push_back("grid");
    }

    if (const json* phase = find(v, "phase_function")) {
        const std::string pk = member(key, "phase_function");
        expectObject(*phase, pk);
        const std::string ptype = find(*phase, "type") ? string((*phase)["type"], member(pk, "type")) : "isotropic";
        if (ptype == "isotropic") {
            m.phase = 0;
            ignoreUnread(*phase, pk, {"type"});
        } else if (ptype == "henyey_greenstein") {
            m.phase = 1;
            if (const json* g = find(*phase, "g")) m.phaseG = number(*g, member(pk, "g"));
            if (!(m.phaseG > -1.0f && m.phaseG < 1.0f)) fail(member(pk, "g"), "must be in (-1, 1)");
            ignoreUnread(*phase, pk, {"type", "g"});
        } else if (ptype == "rayleigh") {
            fail(member(pk, "type"), "unsupported phase function 'rayleigh'");
        } else {
            fail(member(pk, "type"), fmt::format("unknown phase function '{}'", ptype));
        }
    }
    if (const json* t = find(v, "transmittance")) m.transmittance = readTransmittance(*t, member(key, "transmittance"), false);
    for (const auto& [name, value] : v.items())
        if (std::find(read.begin(), read.end(), name) == read.end()) ignore(member(key, name));
    return m;
}

// Tungsten's transmittance models with its parameter names and defaults.
TransmittanceModel SceneReader::readTransmittance(const json& v, const std::string& key, bool nested) {
    expectObject(v, key);
    const std::string type = find(v, "type") ? string(v["type"], member(key, "type")) : "exponential";
    TransmittanceModel t;
    t.name = type;
    auto param = [&](const char* field, float fallback, bool positive) {
        const json* f = find(v, field);
        if (!f) return fallback;
        float x = number(*f, member(key, field));
        if (positive && !(x > 0.0f)) fail(member(key, field), "must be positive");
        return x;
    };
    if (type == "exponential") {
        t.type = 0;
        ignoreUnread(v, key, {"type"});
    } else if (type == "linear" || type == "quadratic") {
        t.type = type == "linear" ? 1 : 2;
        t.params.x = param("max_t", type == "linear" ? 1.0f : 0.75f, true);
        ignoreUnread(v, key, {"type", "max_t"});
    } else if (type == "double_exponential") {
        t.type = 3;
        t.params = glm::vec4(param("sigma_a", 0.5f, true), param("sigma_b", 10.0f, true), 0, 0);
        ignoreUnread(v, key, {"type", "sigma_a", "sigma_b"});
    } else if (type == "erlang") {
        t.type = 4;
        t.params.x = param("rate", 5.0f, true);
        ignoreUnread(v, key, {"type", "rate"});
    } else if (type == "davis") {
        t.type = 5;
        t.params.x = param("alpha", 1.1f, true);
        ignoreUnread(v, key, {"type", "alpha"});
    } else if (type == "davis_weinstein") {
        t.type = 6;
        t.params = glm::vec4(param("h", 0.75f, true), param("c", 1.0f, true), 0, 0);
        if (t.params.x < 0.5f || t.params.x > 1.0f) fail(member(key, "h"), "must be in [0.5, 1]");
        ignoreUnread(v, key, {"type", "h", "c"});
    } else if (type == "pulse") {
        t.type = 7;
        t.params = glm::vec4(param("min", 0.0f, false), param("max", 1.0f, false), 0, 0);
        if (!(t.params.y > t.params.x)) fail(member(key, "max"), "must be larger than min");
        t.params.z = find(v, "num_pulses") ? float(integer(v["num_pulses"], member(key, "num_pulses"), 1, 1024)) : 4.0f;
        ignoreUnread(v, key, {"type", "min", "max", "num_pulses"});
    } else if (type == "interpolated") {
        if (nested) fail(member(key, "type"), "an interpolated transmittance cannot nest another interpolated one");
        TransmittanceModel a, b;
        a.type = 1;
        a.params.x = 1.0f;  // linear
        b.type = 4;
        b.params.x = 5.0f;  // erlang
        if (const json* f = find(v, "tr_a")) a = readTransmittance(*f, member(key, "tr_a"), true);
        if (const json* f = find(v, "tr_b")) b = readTransmittance(*f, member(key, "tr_b"), true);
        t.type = 8;
        t.typeA = a.type;
        t.params = a.params;
        t.typeB = b.type;
        t.paramsB = b.params;
        t.ratio = param("ratio", 0.5f, false);
        if (t.ratio < 0.0f || t.ratio > 1.0f) fail(member(key, "ratio"), "must be in [0, 1]");
        ignoreUnread(v, key, {"type", "tr_a", "tr_b", "ratio"});
        return t;
    } else {
        fail(member(key, "type"), fmt::format("unknown transmittance type '{}'", type));
    }
    t.typeA = t.typeB = t.type;
    t.paramsB = t.params;
    return t;
}

// A grid: {"type": "procedural_cloud" | "constant", "resolution", "transform", ...}. OpenVDB files
// ("vdb") need libopenvdb, which this build does not use.
DensityGrid SceneReader::readGrid(const json& v, const std::string& key) {
    expectObject(v, key);
    const std::string type = find(v, "type") ? string(v["type"], member(key, "type")) : "";
    if (type == "vdb")
        fail(member(key, "type"), "OpenVDB grids are not supported by this build of Telescope (no libopenvdb); "
                                  "use a \"procedural_cloud\" or \"constant\" grid");
    if (type != "procedural_cloud" && type != "constant" && type != "linear")
        fail(member(key, "type"),
             fmt::format("unknown grid type '{}' (expected \"procedural_cloud\", \"constant\" or \"linear\")", type));
    glm::uvec3 res(32);
    if (const json* r = find(v, "resolution")) {
        const std::string rk = member(key, "resolution");
        if (r->is_array()) {
            if (r->size() != 3) fail(rk, fmt::format("expected [x, y, z], got {} elements", r->size()));
            for (int i = 0; i < 3; ++i) res[i] = integer((*r)[i], element(rk, i), 1, 512);
        } else {
            res = glm::uvec3(integer(*r, rk, 1, 512));
        }
    }
    DensityGrid g;
    if (type == "linear") {
        auto value = [&](const char* field) {
            const float x = find(v, field) ? number(v[field], member(key, field)) : 1.0f;
            if (x < 0.0f) fail(member(key, field), "must be non-negative");
            return x;
        };
        g = linearGrid(res, value("from"), value("to"));
        rejectUnknownKeys(v, key, {"type", "resolution", "transform", "from", "to"}, file_);
    } else if (type == "constant") {
        const float value = find(v, "value") ? number(v["value"], member(key, "value")) : 1.0f;
        if (value < 0.0f) fail(member(key, "value"), "must be non-negative");
        g = constantGrid(res, value);
        rejectUnknownKeys(v, key, {"type", "resolution", "transform", "value"}, file_);
    } else {
        ProceduralCloudSettings c;
        c.resolution = res;
        if (const json* f = find(v, "seed")) c.seed = integer(*f, member(key, "seed"), 0, 0x7fffffff);
        if (const json* f = find(v, "frequency")) c.frequency = number(*f, member(key, "frequency"));
        if (const json* f = find(v, "coverage")) c.coverage = number(*f, member(key, "coverage"));
        if (!(c.frequency > 0.0f)) fail(member(key, "frequency"), "must be positive");
        g = proceduralCloud(c);
        rejectUnknownKeys(v, key, {"type", "resolution", "transform", "seed", "frequency", "coverage"}, file_);
    }
    // The grid fills the unit cube [-0.5, 0.5]^3 placed by the transform (translation and scale).
    const glm::mat4 m = find(v, "transform") ? transform(v["transform"], member(key, "transform")) : glm::mat4(1.0f);
    const glm::vec3 half = 0.5f * columnLengths(m), centre(m[3]);
    const glm::mat3 rot = columnDirections(m);
    if (glm::length(glm::abs(rot[0]) - glm::vec3(1, 0, 0)) + glm::length(glm::abs(rot[1]) - glm::vec3(0, 1, 0)) > 1e-4f)
        fail(member(key, "transform"), "grids must be axis-aligned (translation and scale only)");
    if (!(half.x > 0.0f && half.y > 0.0f && half.z > 0.0f)) fail(member(key, "transform"), "the grid box has zero size");
    g.boxMin = centre - half;
    g.boxMax = centre + half;
    return g;
}

void SceneReader::readTransmittanceEstimator(const json& v, const std::string& key) {
    expectObject(v, key);
    rejectUnknownKeys(v, key, {"type", "level", "pmf"}, file_);
    TransmittanceEstimatorSettings& t = scene_.integrator.transmittance;
    const std::string typeKey = member(key, "type");
    if (!find(v, "type")) fail(typeKey, "missing");
    const std::string type = string(v["type"], typeKey);
    bool found = false;
    for (uint32_t i = 0; i <= uint32_t(TransmittanceEstimatorType::UnbiasedRayMarch); ++i)
        if (type == transmittanceEstimatorName(TransmittanceEstimatorType(i))) {
            t.type = TransmittanceEstimatorType(i);
            found = true;
        }
    if (!found)
        fail(typeKey, fmt::format("unknown transmittance estimator '{}' (expected ray_march, debiased_ray_march, "
                                  "delta_tracking, ratio_tracking, residual_ratio_tracking or unbiased_ray_march)", type));
    if (const json* l = find(v, "level")) t.level = integer(*l, member(key, "level"), 0, 16);
    if (const json* pmf = find(v, "pmf")) {
        const std::string pmfKey = member(key, "pmf");
        expectObject(*pmf, pmfKey);
        const std::string ptype = find(*pmf, "type") ? string((*pmf)["type"], member(pmfKey, "type")) : "geometric";
        auto openUnit = [&](const char* field) {
            const float x = number((*pmf)[field], member(pmfKey, field));
            if (!(x > 0.0f && x < 1.0f)) fail(member(pmfKey, field), fmt::format("{} must be in (0, 1), got {}", field, x));
            return x;
        };
        t.pmf.origin = "given in the scene";
        if (ptype == "geometric") {
            rejectUnknownKeys(*pmf, pmfKey, {"type", "r"}, file_);
            t.pmf.type = PmfType::Geometric;
            if (find(*pmf, "r")) t.pmf.r = openUnit("r");
        } else if (ptype == "power_law") {
            rejectUnknownKeys(*pmf, pmfKey, {"type", "alpha"}, file_);
            t.pmf.type = PmfType::PowerLaw;
            if (find(*pmf, "alpha")) t.pmf.alpha = openUnit("alpha");
        } else {
            fail(member(pmfKey, "type"), fmt::format("unknown pmf type '{}' (expected \"geometric\" or \"power_law\")", ptype));
        }
    }
}

// The trackers and unbiased ray marching estimate exp(-tau) only.
void SceneReader::checkEstimatorFitsMedia(const json& doc) const {
    if (usesPhotons(scene_.integrator) && !scene_.media.empty())
        fail("media", fmt::format("the '{}' integrator does not support participating media (use path_tracer)",
                                  scene_.integrator.type == IntegratorType::PhotonMap ? "photon_map"
                                                                                     : "progressive_photon_map"));
    const TransmittanceEstimatorType t = scene_.integrator.transmittance.type;
    if (t == TransmittanceEstimatorType::RayMarch || t == TransmittanceEstimatorType::DebiasedRayMarch) return;
    for (size_t i = 0; i < scene_.media.size(); ++i)
        if (!scene_.media[i].transmittance.exponential()) {
            const std::string where = scene_.media[i].name.empty() ? fmt::format("medium {}", i)
                                                                     : fmt::format("medium '{}'", scene_.media[i].name);
            fail(find(doc, "integrator") ? "integrator.transmittance_estimator.type" : "media",
                 fmt::format("{} works for exponential media only, but {} has the '{}' transmittance "
                             "(use ray_march or debiased_ray_march)",
                             transmittanceEstimatorName(t), where, scene_.media[i].transmittance.name));
        }
}

}  // namespace

const char* transmittanceEstimatorName(TransmittanceEstimatorType t) {
    switch (t) {
        case TransmittanceEstimatorType::RayMarch: return "ray_march";
        case TransmittanceEstimatorType::DebiasedRayMarch: return "debiased_ray_march";
        case TransmittanceEstimatorType::DeltaTracking: return "delta_tracking";
        case TransmittanceEstimatorType::RatioTracking: return "ratio_tracking";
        case TransmittanceEstimatorType::ResidualRatioTracking: return "residual_ratio_tracking";
        case TransmittanceEstimatorType::UnbiasedRayMarch: return "unbiased_ray_march";
    }
    return "?";
}

SceneOverride parseOverride(const std::string& text) {
    const size_t eq = text.find('=');
    if (eq == std::string::npos) throw InputError("", "", fmt::format("--set '{}': expected key=value", text));
    SceneOverride o{text.substr(0, eq), text.substr(eq + 1)};
    if (o.key.empty()) throw InputError("", "", fmt::format("--set '{}': the key before '=' is empty", text));
    return o;
}

Scene loadSceneFromString(const std::string& text, const std::string& displayName, const std::string& baseDir,
                          const std::vector<SceneOverride>& overrides) {
    Scene scene;
    scene.path = displayName;
    try {
        scene.document = json::parse(text);
    } catch (const json::parse_error& e) {
        // nlohmann's byte is the 1-based index of the last character read
        const auto [line, column] = lineColumn(text, e.byte > 0 ? e.byte - 1 : 0);
        std::string reason = e.what();
        if (const size_t colon = reason.find(": "); colon != std::string::npos) reason = reason.substr(colon + 2);
        throw InputError(displayName, "", fmt::format("invalid JSON at line {}, column {}: {}", line, column, reason));
    } catch (const json::exception& e) {
        // Number overflow and the like carry no position
        std::string reason = e.what();
        if (const size_t bracket = reason.find("] "); bracket != std::string::npos) reason = reason.substr(bracket + 2);
        throw InputError(displayName, "", "invalid JSON: " + reason);
    }
    for (const SceneOverride& o : overrides) applyOverride(scene.document, o, displayName);
    SceneReader(displayName, baseDir, scene).read(scene.document);
    return scene;
}

Scene loadScene(const std::string& path, const std::vector<SceneOverride>& overrides) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", fmt::format("cannot open scene file: {}", std::strerror(errno)));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw InputError(path, "", "cannot read scene file");
    return loadSceneFromString(text.str(), path, fs::path(path).parent_path().string(), overrides);
}

}  // namespace telescope
