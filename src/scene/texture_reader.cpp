// Textures on material parameters ("albedo", "roughness"): Tungsten's Scene::fetchTexture. A
// number or an array is a constant, a string a bitmap file (relative to the scene file), an object
// a texture of its "type": "constant" ("value"), "checker" ("on_color", "off_color", "res_u",
// "res_v") or "bitmap" ("file", "gamma_correct", "interpolate", "clamp", "scale").
#include "scene/scene_reader.h"

#include <cctype>
#include <cmath>

#include "scene/image_file.h"
#include "shared/gpu_types.h"
#include "shared/texture.h"

namespace telescope::scene_reader {

namespace {

// Tungsten's texture types that Telescope does not implement
constexpr std::string_view kUnsupportedTextures[] = {"disk", "blade", "ies"};

}  // namespace

// The texel budget of all bitmaps together: the texture buffer is one storage-buffer binding
// (128 MiB on lavapipe, the Vulkan minimum is less), of vec4 texels; the table and the per-prim
// uv records take the rest.
uint64_t SceneReader::textureTexelBudget() { return (uint64_t(96) << 20) / sizeof(glm::vec4); }

std::optional<uint32_t> SceneReader::readTexture(const json& v, const std::string& key, bool scalar, glm::vec3& constant) {
    if (v.is_number() || v.is_array()) {
        constant = colour(v, key);
        return std::nullopt;
    }
    Texture t;
    t.key = key;
    if (v.is_string()) {
        readBitmap(v, key, t, scalar);
    } else if (v.is_object()) {
        const std::string type = requiredType(v, key);
        if (type == "constant") {
            if (const json* value = find(v, "value")) constant = colour(*value, member(key, "value"));
            else constant = glm::vec3(1.0f);  // Tungsten's ConstantTexture default
            ignoreUnread(v, key, {"type", "value"});
            return std::nullopt;
        }
        if (type == "checker") {
            t.type = TextureType::Checker;
            if (const json* c = find(v, "on_color")) t.on = colour(*c, member(key, "on_color"));
            if (const json* c = find(v, "off_color")) t.off = colour(*c, member(key, "off_color"));
            if (const json* r = find(v, "res_u")) t.resU = integer(*r, member(key, "res_u"), 1, 1u << 24);
            if (const json* r = find(v, "res_v")) t.resV = integer(*r, member(key, "res_v"), 1, 1u << 24);
            ignoreUnread(v, key, {"type", "on_color", "off_color", "res_u", "res_v"});
        } else if (type == "bitmap") {
            const json* file = find(v, "file");
            if (!file) fail(key, "a bitmap texture needs a \"file\"");
            if (const json* g = find(v, "gamma_correct")) t.gammaCorrect = boolean(*g, member(key, "gamma_correct"));
            if (const json* i = find(v, "interpolate")) t.interpolate = boolean(*i, member(key, "interpolate"));
            if (const json* c = find(v, "clamp")) t.clamp = boolean(*c, member(key, "clamp"));
            if (const json* s = find(v, "scale")) {
                const float scale = number(*s, member(key, "scale"));
                if (!(scale >= 0.0f)) fail(member(key, "scale"), "the scale must not be negative");
                t.on = glm::vec3(scale);
            } else {
                t.on = glm::vec3(1.0f);
            }
            readBitmap(*file, member(key, "file"), t, scalar);
            ignoreUnread(v, key, {"type", "file", "gamma_correct", "interpolate", "clamp", "scale"});
        } else if (isOneOf(kUnsupportedTextures, type)) {
            fail(member(key, "type"), fmt::format("unsupported texture type '{}' (constant, checker and bitmap are supported)", type));
        } else {
            fail(member(key, "type"), fmt::format("unknown texture type '{}' (constant, checker, bitmap)", type));
        }
    } else {
        fail(key, "expected a number, a colour, an image file name or a texture object, got " + quote(v));
    }
    if (scalar) {
        // Tungsten reads scalar parameters from the first channel of a constant or checker
        t.on = glm::vec3(t.on.x);
        t.off = glm::vec3(t.off.x);
    }
    scene_.textures.push_back(std::move(t));
    return uint32_t(scene_.textures.size() - 1);
}

// Reads the image named by `file` into t (a bitmap; t.on holds the scale). LDR files are sRGB
// unless gamma_correct is false (Tungsten's ImageIO::loadLdr); HDR files (.exr, .hdr, .pfm, as
// Tungsten tells them apart: by extension) are linear. Scalar parameters take the mean of R, G, B
// (Tungsten's TexelConversion::REQUEST_AVERAGE).
void SceneReader::readBitmap(const json& file, const std::string& key, Texture& t, bool scalar) {
    t.type = TextureType::Bitmap;
    const fs::path relative = string(file, key);
    if (relative.empty()) fail(key, "the image file name is empty");
    const fs::path path = relative.is_absolute() ? relative : baseDir_ / relative;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) fail(key, fmt::format("cannot open image file '{}'", path.string()));
    uint64_t used = 0;
    for (const Texture& other : scene_.textures) used += other.texels.size();
    const uint64_t budget = textureTexelBudget();
    int32_t status = 0;
    ImageFileData image;
    try {
        image = readImageFile(path.string(), budget > used ? budget - used : 0, status);
    } catch (const std::exception& e) {
        fail(key, status == kImageTooLarge
                      ? fmt::format("{} (all bitmap textures together hold at most {} texels)", e.what(), budget)
                      : std::string(e.what()));
    }
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    const bool hdr = isOneOf({".exr", ".hdr", ".pfm"}, ext);
    const bool linearize = !hdr && t.gammaCorrect;
    t.resU = image.width;
    t.resV = image.height;
    t.texels.resize(size_t(image.width) * image.height);
    const uint32_t n = image.channels;
    for (size_t i = 0; i < t.texels.size(); ++i) {
        const float* px = image.pixels.data() + i * n;
        glm::vec4 c = n >= 3 ? glm::vec4(px[0], px[1], px[2], n >= 4 ? px[3] : 1.0f)
                             : glm::vec4(px[0], px[0], px[0], n == 2 ? px[1] : 1.0f);
        if (linearize)
            for (int k = 0; k < 3; ++k) c[k] = shader::srgbToLinear(std::clamp(c[k], 0.0f, 1.0f));
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(c[k]) || c[k] < 0.0f)
                fail(key, fmt::format("image '{}' has a negative or non-finite value at pixel ({}, {})", path.string(),
                                      i % image.width, i / image.width));
        if (scalar) c = glm::vec4(glm::vec3((c.x + c.y + c.z) / 3.0f), c.w);
        t.texels[i] = c;
    }
}

}  // namespace telescope::scene_reader
