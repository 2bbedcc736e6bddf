// The scene reader's typed values, key bookkeeping and top level (scene_reader.h).
#include "scene/scene_reader.h"

#include "scene/enum_names.h"

#include <array>
#include <cmath>

#include "core/error.h"
#include "scene/transform.h"

namespace telescope::scene_reader {

std::string quote(const json& v) {
    std::string s = v.dump();
    if (s.size() > 40) s = s.substr(0, 37) + "...";
    return s;
}

void SceneReader::fail(const std::string& key, const std::string& what) const { throw InputError(file_, key, what); }

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

std::string SceneReader::requiredType(const json& v, const std::string& key) const {
    expectObject(v, key);
    const json* type = find(v, "type");
    if (!type) fail(key, "missing 'type'");
    return string(*type, member(key, "type"));
}

std::string SceneReader::typeOr(const json& v, const std::string& key, const char* fallback) const {
    const json* type = find(v, "type");
    return type ? string(*type, member(key, "type")) : fallback;
}

// ---- Bookkeeping of keys ----

void SceneReader::ignore(const std::string& key) {
    if (ignoredSet_.insert(key).second) scene_.ignoredKeys.push_back(key);
}

void SceneReader::ignoreUnread(const json& obj, const std::string& key, const std::vector<std::string_view>& read) {
    // Read everywhere they can appear: a bsdf's "bump" (null; any map is refused by readBsdf) and
    // a primitive's "cone_angle" (90; other angles are refused by readPrimitive).
    static const std::vector<std::string_view> readEverywhere = {"bump", "cone_angle"};
    for (const auto& [name, value] : obj.items())
        if (std::find(read.begin(), read.end(), name) == read.end() &&
            std::find(readEverywhere.begin(), readEverywhere.end(), name) == readEverywhere.end())
            ignore(member(key, name));
}

void SceneReader::rejectUnknownKeys(const json& obj, const std::string& key,
                                    std::initializer_list<std::string_view> known) const {
    for (const auto& [name, value] : obj.items())
        if (!isOneOf(known, name)) fail(member(key, name), fmt::format("unknown key '{}' in {}", name, key));
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
    const PixelFilter filter = scene_.camera.filter;
    if (usesPhotons(scene_.integrator) && filter != PixelFilter::Dirac && filter != PixelFilter::Box &&
        filter != PixelFilter::Tent)
        fail("camera.reconstruction_filter", fmt::format("photon mapping supports the dirac, box and tent filters, not '{}'",
                                                         nameOf(kPixelFilterNames, filter)));
    ignoreUnread(doc, "", {"media", "bsdfs", "primitives", "camera", "integrator", "renderer"});
}

}  // namespace telescope::scene_reader
