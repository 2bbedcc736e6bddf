// "primitives": Tungsten's shapes flattened into the world-space triangles, spheres and disks the
// GPU traces (quad orientation and power -> radiance as in Tungsten), plus point and environment
// lights. A new shape is read here.
#include "scene/scene_reader.h"

#include <cmath>

#include "scene/image_file.h"
#include "scene/mesh_io.h"
#include "scene/transform.h"
#include "shared/environment_map.h"

namespace telescope::scene_reader {

namespace {

constexpr float kPi = 3.14159265358979323846f;

constexpr std::string_view kUnsupportedPrimitives[] = {
    "curves", "cylinder", "instances", "minecraft_map", "skydome", "spot"};

Geometry triangle(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, const glm::vec3& normal) {
    Geometry g;
    g.type = GeometryType::Triangle;
    g.p0 = p0;
    g.p1 = p1;
    g.p2 = p2;
    g.normal = normal;
    return g;
}

// One analytic quad for the parallelogram base + [0,1] e0 + [0,1] e1 (Tungsten's quad and cube
// faces are analytic too), its edges ordered so that cross(p1 - p0, p2 - p0) points along the
// given unit normal. uvBase, uv0, uv1: Tungsten's uvs at base, base + e0 and base + e1.
void appendParallelogram(std::vector<Geometry>& out, const glm::vec3& base, const glm::vec3& e0,
                         const glm::vec3& e1, const glm::vec3& normal, glm::vec2 uvBase, glm::vec2 uv0, glm::vec2 uv1) {
    const bool keep = glm::dot(glm::cross(e0, e1), normal) >= 0.0f;
    Geometry g = triangle(base, base + (keep ? e0 : e1), base + (keep ? e1 : e0), normal);
    g.type = GeometryType::Quad;
    g.uv[0] = uvBase;
    g.uv[1] = keep ? uv0 : uv1;
    g.uv[2] = keep ? uv1 : uv0;
    out.push_back(g);
}

}  // namespace

void SceneReader::readPrimitive(const json& v, const std::string& key) {
    const std::string type = requiredType(v, key);
    const std::string typeKey = member(key, "type");
    const bool known = isOneOf({"quad", "cube", "sphere", "disk", "mesh", "point", "infinite_sphere", "infinite_sphere_cap"}, type);
    if (!known && isOneOf(kUnsupportedPrimitives, type)) fail(typeKey, fmt::format("unsupported primitive type '{}'", type));
    if (!known) fail(typeKey, fmt::format("unknown primitive type '{}'", type));
    // Tungsten narrows a disk's emission to a cone of this half-angle; Telescope's disks emit over
    // the hemisphere, Tungsten's default (90 degrees), the one value honoured.
    if (const json* cone = find(v, "cone_angle")) {
        if (number(*cone, member(key, "cone_angle")) != 90.0)
            fail(member(key, "cone_angle"), "only 90 (the whole hemisphere, Tungsten's default) is supported");
    }

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

    // An infinite_sphere's emission (or power) may be an image (Tungsten's bitmap texture).
    auto isImage = [](const json* e) { return e && (e->is_string() || e->is_object()); };
    if (type == "infinite_sphere" && (isImage(find(v, "emission")) || isImage(find(v, "power")))) {
        readEnvironmentImage(v, key, m, shape.name);
        return;
    }

    // Emission: radiance, or power converted with the shape's power-to-radiance factor
    std::optional<glm::vec3> emission, power;
    if (const json* e = find(v, "emission")) emission = colour(*e, member(key, "emission"));
    if (const json* p = find(v, "power")) power = colour(*p, member(key, "power"));
    if (emission && power) ignore(member(key, "emission"));

    // Tungsten's infinite_sphere_cap: radiance from a cone of directions around the transformed
    // +y axis, half angle cap_angle (degrees, 10 by default); power P is radiance P / (2 pi (1 - cos)).
    if (type == "infinite_sphere_cap") {
        PointLikeLight light;
        light.type = LightType::Cap;
        light.name = shape.name;
        const glm::vec3 axis = transformVector(m, {0, 1, 0});
        if (isDegenerate(axis)) fail(member(key, "transform"), "the cap's axis has zero length");
        light.direction = glm::normalize(axis);
        float degrees = 10.0f;
        if (const json* a = find(v, "cap_angle")) degrees = number(*a, member(key, "cap_angle"));
        if (!(degrees > 0.0f && degrees <= 180.0f)) fail(member(key, "cap_angle"), "must be in (0, 180] degrees");
        light.cosCap = std::cos(degrees * kPi / 180.0f);
        const float solidAngle = 2.0f * kPi * (1.0f - light.cosCap);
        light.intensity = power ? *power / solidAngle : emission.value_or(glm::vec3(0.0f));
        if (find(v, "skydome")) fail(member(key, "skydome"), "unsupported: a cap pivoting on a skydome (skydome emitters are unsupported)");
        if (find(v, "sample")) ignore(member(key, "sample"));
        for (const PointLikeLight& l : scene_.lights)
            if (l.type == LightType::Cap) fail(key, "only one infinite_sphere_cap per scene is supported");
        if (light.intensity != glm::vec3(0.0f)) scene_.lights.push_back(light);
        ignoreUnread(v, key, {"name", "type", "transform", "emission", "power", "cap_angle", "sample"});
        return;
    }

    // Point and environment lights
    if (type == "point" || type == "infinite_sphere") {
        PointLikeLight light;
        light.type = type == "point" ? LightType::Point : LightType::Environment;
        light.position = glm::vec3(m[3]);
        light.intensity = power ? *power / (4.0f * kPi) : emission.value_or(glm::vec3(0.0f));
        light.name = shape.name;
        if (light.intensity != glm::vec3(0.0f)) scene_.lights.push_back(light);
        if (find(v, "sample")) ignore(member(key, "sample"));  // Tungsten's light-sampling switch: same image
        for (const PointLikeLight& l : scene_.lights)
            if (type == "infinite_sphere" && l.type == LightType::Environment && l.image)
                fail(key, "only one infinite_sphere per scene is supported when one has an image");
        ignoreUnread(v, key, {"name", "type", "transform", "emission", "power", "sample"});
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
        // Tungsten's quad uv at base + l0 e0 + l1 e1 is (l0, 1 - l1).
        if (!isDegenerate(n))
            appendParallelogram(shapeGeometry, transformPoint(m, glm::vec3(0.0f)) - 0.5f * (e0 + e1), e0, e1, n / float(area),
                                {0.0f, 1.0f}, {1.0f, 1.0f}, {0.0f, 0.0f});
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
                // Tungsten's cube uv on this face: the local coordinates along s and t, in [0, 1].
                appendParallelogram(shapeGeometry, centre + half[dim] * n - 0.5f * (u + w), u, w, n, {0.0f, 0.0f},
                                    {1.0f, 0.0f}, {0.0f, 1.0f});
            }
        }
    } else if (type == "sphere") {
        // Unit sphere: radius = largest column length
        const glm::vec3 lengths = columnLengths(m);
        Geometry g;
        g.type = GeometryType::Sphere;
        g.p0 = glm::vec3(m[3]);
        g.radius = std::max({lengths.x, lengths.y, lengths.z});
        // Tungsten's sphere uv is taken in the sphere's local frame: rows of the inverse rotation.
        const glm::mat3 rot = columnDirections(m);
        g.uvFrame[0] = rot[0];
        g.uvFrame[1] = rot[1];
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
            // Tungsten's TangentFrame(n) of the disk: its uv is (azimuth, r / radius) in this frame.
            glm::vec3 tangent = std::abs(g.normal.x) > std::abs(g.normal.y) ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
            const glm::vec3 bitangent = glm::normalize(glm::cross(g.normal, tangent));
            tangent = glm::cross(bitangent, g.normal);
            g.uvFrame[0] = bitangent;
            g.uvFrame[1] = tangent;
            shapeGeometry.push_back(g);
        }
    } else {
        // Mesh: vertices by M, geometric normal cross(p1 - p0, p2 - p0). Tungsten's keys: "smooth"
        // (default false) shades with the vertex normals interpolated, the file's own or, with
        // "recompute_normals" (default false; Tungsten recomputes only for smooth meshes), its
        // smoothVertexNormals, each taken to world space by the inverse transpose of M;
        // "backface_culling" false is what Tungsten 0.2.2 renders for either value (its culling
        // is not implemented), so true is refused rather than silently ignored.
        const std::string fileKey = member(key, "file");
        const json* fileValue = find(v, "file");
        if (!fileValue) fail(key, "missing 'file'");
        const bool smooth = find(v, "smooth") && boolean(v["smooth"], member(key, "smooth"));
        const bool recompute = find(v, "recompute_normals") && boolean(v["recompute_normals"], member(key, "recompute_normals"));
        if (find(v, "backface_culling") && boolean(v["backface_culling"], member(key, "backface_culling")))
            fail(member(key, "backface_culling"),
                 "backface_culling true is not supported (Tungsten 0.2.2 does not cull either: its meshes render "
                 "both faces); remove the key or set it to false");
        const fs::path relative = string(*fileValue, fileKey);
        const MeshData mesh = loadMesh((relative.is_absolute() ? relative : baseDir_ / relative).string(), file_, fileKey);
        std::vector<glm::vec3> world(mesh.positions.size());
        for (size_t i = 0; i < world.size(); ++i) world[i] = transformPoint(m, mesh.positions[i]);
        std::vector<std::array<glm::vec3, 3>> shading;
        if (smooth) shading = recompute ? smoothVertexNormals(mesh) : mesh.normals;
        const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(m)));
        for (size_t i = 0; i < mesh.triangles.size(); ++i) {
            const auto& t = mesh.triangles[i];
            const glm::vec3 n = glm::cross(world[t[1]] - world[t[0]], world[t[2]] - world[t[0]]);
            if (isDegenerate(n)) continue;
            area += 0.5 * glm::length(n);
            Geometry g = triangle(world[t[0]], world[t[1]], world[t[2]], glm::normalize(n));
            if (smooth) {
                // A corner without a usable normal (a file without any) takes the face's.
                g.smooth = true;
                for (int k = 0; k < 3; ++k) {
                    const glm::vec3 w = normalMatrix * shading[i][k];
                    g.vertexNormal[k] = isDegenerate(w) || !std::isfinite(w.x + w.y + w.z) ? g.normal : glm::normalize(w);
                }
            }
            for (int k = 0; k < 3; ++k) g.uv[k] = mesh.uvs[i][k];
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
    std::vector<std::string_view> read = {"name", "type", "transform", "bsdf", "emission", "power", "file", "int_medium",
                                          "ext_medium"};
    if (type == "mesh") read.insert(read.end(), {"smooth", "recompute_normals", "backface_culling"});
    ignoreUnread(v, key, read);
}

// An infinite_sphere whose emission (or power) is an image: a file name relative to the scene file,
// or a {"type": "bitmap", "file": ...} object with Tungsten's BitmapTexture keys (gamma_correct
// only concerns 8-bit images, which are refused; interpolate true and clamp false by default).
// Power is radiance times 4 pi (InfiniteSphere::powerToRadianceFactor).
void SceneReader::readEnvironmentImage(const json& v, const std::string& key, const glm::mat4& m,
                                       const std::string& name) {
    const bool fromPower = find(v, "emission") == nullptr;
    const std::string valueKey = member(key, fromPower ? "power" : "emission");
    if (!fromPower && find(v, "power")) ignore(member(key, "power"));
    const json& value = v[fromPower ? "power" : "emission"];
    auto image = std::make_shared<EnvironmentImage>();
    std::string fileKey = valueKey;
    fs::path relative;
    if (value.is_string()) {
        relative = string(value, valueKey);
    } else {
        const std::string textureType = requiredType(value, valueKey);
        if (textureType != "bitmap")
            fail(member(valueKey, "type"), fmt::format("unsupported texture type '{}' for an infinite_sphere (only "
                                                       "'bitmap' images)", textureType));
        fileKey = member(valueKey, "file");
        const json* file = find(value, "file");
        if (!file) fail(valueKey, "missing 'file'");
        relative = string(*file, fileKey);
        if (const json* b = find(value, "interpolate")) image->interpolate = boolean(*b, member(valueKey, "interpolate"));
        if (const json* b = find(value, "clamp")) image->clamp = boolean(*b, member(valueKey, "clamp"));
        if (const json* b = find(value, "gamma_correct")) boolean(*b, member(valueKey, "gamma_correct"));
        if (const json* s = find(value, "scale")) {
            image->scale = number(*s, member(valueKey, "scale"));
            if (!(image->scale >= 0.0f) || !std::isfinite(image->scale))
                fail(member(valueKey, "scale"), "must be finite and non-negative");
        }
        ignoreUnread(value, valueKey, {"type", "file", "interpolate", "clamp", "gamma_correct", "scale"});
    }
    if (relative.empty()) fail(fileKey, "empty image file name");
    const fs::path path = relative.is_absolute() ? relative : baseDir_ / relative;
    image->file = path.string();

    // The buffer (shaders/shared/environment_map.h) must fit one storage-buffer binding.
    const uint64_t maxTexels = (shader::kEnvMaxBufferBytes / 4 - shader::kEnvHeaderFloats) / 4;
    ImageFileData data;
    try {
        int32_t status = kImageOk;
        data = readImageFile(path.string(), maxTexels, status);
    } catch (const std::exception& e) {
        fail(fileKey, fmt::format("{}{}", e.what(),
                                  std::string(e.what()).find("more than") != std::string::npos
                                      ? " (an environment image and its sampling tables must fit one 128 MiB "
                                        "storage-buffer binding)"
                                      : ""));
    }
    if (shader::envBufferFloats(data.width, data.height) * 4 > shader::kEnvMaxBufferBytes)
        fail(fileKey, fmt::format("image '{}' ({}x{}) is too large: an environment image and its sampling tables "
                                  "must fit one 128 MiB storage-buffer binding",
                                  path.string(), data.width, data.height));
    if (!data.floatingPoint)
        fail(fileKey, fmt::format("image '{}' is not a high-dynamic-range image (8- or 16-bit integer pixels); "
                                  "an infinite_sphere needs radiance: use .exr, .hdr or .pfm",
                                  path.string()));
    for (float c : data.pixels)
        if (!std::isfinite(c)) fail(fileKey, fmt::format("image '{}' has non-finite pixels", path.string()));
    // RGB from the file's channels: one channel is grey, more than three keep the first three.
    image->width = data.width;
    image->height = data.height;
    const size_t texels = size_t(data.width) * data.height, channels = data.channels;
    image->rgb.resize(texels * 3);
    for (size_t i = 0; i < texels; ++i)
        for (size_t c = 0; c < 3; ++c)
            image->rgb[3 * i + c] = data.pixels[i * channels + (channels >= 3 ? c : 0)];
    if (fromPower) image->scale *= 1.0f / (4.0f * kPi);

    PointLikeLight light;
    light.type = LightType::Environment;
    light.name = name;
    light.rotation = columnDirections(m);
    for (int c = 0; c < 3; ++c)
        if (isDegenerate(light.rotation[c])) fail(member(key, "transform"), "the rotation is degenerate");
    double mean = 0.0;
    for (float c : image->rgb) mean += std::abs(c);
    // Tungsten's `sample` (InfiniteSphere::_doSample) only changes the noise: the environment is
    // always light-sampled here.
    if (find(v, "sample")) ignore(member(key, "sample"));
    for (const PointLikeLight& l : scene_.lights)
        if (l.type == LightType::Environment) fail(key, "only one infinite_sphere per scene is supported when one has an image");
    light.image = std::move(image);
    light.intensity = glm::vec3(0.0f);  // the mean radiance, set by the GPU scene
    if (mean > 0.0 && light.image->scale > 0.0f) scene_.lights.push_back(light);
    ignoreUnread(v, key, {"name", "type", "transform", "emission", "power", "sample"});
}

}  // namespace telescope::scene_reader
