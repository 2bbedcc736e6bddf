// The interpreter behind loadScene (scene_loader.h), private to src/scene.
//
// One SceneReader reads one parsed (and overridden) document into a Scene. Its parts live in one
// file per thing read, so a new material family or medium touches one file:
//   scene_reader.cpp     typed values, key bookkeeping, the top level
//   material_reader.cpp  "bsdfs" and every "bsdf" reference
//   shape_reader.cpp     "primitives": Tungsten shapes flattened to triangles, spheres, disks, lights
//   medium_reader.cpp    "media", transmittance models, density grids
//   settings_reader.cpp  "camera", "integrator" (debias, photons, transmittance estimator), "renderer"
//   mesh_io.cpp          .wo3 and .obj files
// Every error names the file and the JSON key path at fault; keys Telescope reads but does not
// use are collected in Scene::ignoredKeys.
#pragma once

#include <algorithm>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "scene/scene.h"

namespace telescope::scene_reader {

using nlohmann::json;
namespace fs = std::filesystem;

template <size_t N>
bool isOneOf(const std::string_view (&list)[N], std::string_view s) {
    return std::find(std::begin(list), std::end(list), s) != std::end(list);
}

inline bool isOneOf(std::initializer_list<std::string_view> list, std::string_view s) {
    return std::find(list.begin(), list.end(), s) != list.end();
}

// ---- JSON key paths ("primitives[3].transform.scale") ----

inline std::string member(const std::string& parent, std::string_view key) {
    return parent.empty() ? std::string(key) : parent + "." + std::string(key);
}

inline std::string element(const std::string& parent, size_t index) { return fmt::format("{}[{}]", parent, index); }

// A zero, non-finite or too long vector (a degenerate normal, axis or direction).
inline bool isDegenerate(const glm::vec3& n) { return !(glm::dot(n, n) > 0.0f) || !std::isfinite(glm::dot(n, n)); }

// A value as it appears in the file, shortened for messages.
std::string quote(const json& v);

class SceneReader {
public:
    SceneReader(std::string file, fs::path baseDir, Scene& scene)
        : file_(std::move(file)), baseDir_(std::move(baseDir)), scene_(scene) {}

    void read(const json& doc);

private:
    [[noreturn]] void fail(const std::string& key, const std::string& what) const;

    // Typed values (scene_reader.cpp)
    const json* find(const json& obj, std::string_view key) const;
    void expectObject(const json& v, const std::string& key) const;
    float number(const json& v, const std::string& key) const;
    uint32_t integer(const json& v, const std::string& key, uint32_t lo, uint32_t hi) const;
    bool boolean(const json& v, const std::string& key) const;
    std::string string(const json& v, const std::string& key) const;
    glm::vec3 vec3(const json& v, const std::string& key) const;
    glm::vec3 colour(const json& v, const std::string& key) const;
    glm::mat4 transform(const json& v, const std::string& key);
    // The "type" of an object: required (the object itself must be one), or with a fallback.
    std::string requiredType(const json& v, const std::string& key) const;
    std::string typeOr(const json& v, const std::string& key, const char* fallback) const;

    // Bookkeeping of keys (scene_reader.cpp)
    void ignore(const std::string& key);
    void ignoreUnread(const json& obj, const std::string& key, const std::vector<std::string_view>& read);
    // A boolean switch of which Telescope renders only `supported`: the other value fails with why.
    void onlyBoolean(const json& v, const std::string& key, const char* name, bool supported, const char* why);
    // Telescope's own objects are read strictly: every key must be known.
    void rejectUnknownKeys(const json& obj, const std::string& key, std::initializer_list<std::string_view> known) const;
    void rejectMedia(const json& obj, const std::string& key, std::initializer_list<std::string_view> keys) const;

    // Materials (material_reader.cpp)
    void readBsdfs(const json& list);
    Material readBsdf(const json& v, const std::string& key);
    uint32_t material(const json& ref, const std::string& key);
    uint32_t componentRef(const json& ref, const std::string& key);
    uint32_t namedMaterial(size_t named);
    uint32_t addMaterial(Material m);
    uint32_t nestingOf(uint32_t index) const;
    void readComponents(const json& v, const std::string& key, Material& m, std::vector<std::string_view>& read);
    float unitScalar(const json& v, const std::string& key, const char* what) const;
    void readConductor(const json& v, const std::string& key, Material& m);
    void readMicrofacet(const json& v, const std::string& key, Material& m, std::vector<std::string_view>& read);
    void readIor(const json& v, const std::string& key, Material& m);
    float roughness(const json& v, const std::string& key) const;
    void readRoughness(const json& v, const std::string& key, Material& m);

    // Textures (texture_reader.cpp): a texture index, or nothing for a constant (set in `constant`).
    std::optional<uint32_t> readTexture(const json& v, const std::string& key, bool scalar, glm::vec3& constant);
    void readBitmap(const json& file, const std::string& key, Texture& t, bool scalar);
    static uint64_t textureTexelBudget();

    // Shapes (shape_reader.cpp)
    void readPrimitive(const json& v, const std::string& key);
    void readEnvironmentImage(const json& v, const std::string& key, const glm::mat4& m, const std::string& name);

    // Settings (settings_reader.cpp)
    void readCamera(const json& v);
    void readIntegrator(const json& v);
    void readDebias(const json& v, const std::string& key, bool photons = false);
    PmfSettings readPmf(const json& v, const std::string& key, PmfSettings pmf, bool allowAuto) const;
    void readPhotonBlocks(const json& v, const std::string& key);
    void readPhotonSettings(const json& v, const std::string& key);
    void readTransmittanceEstimator(const json& v, const std::string& key);
    void readRenderer(const json& v);

    // Participating media (medium_reader.cpp, docs/MEDIA.md)
    void readMedia(const json& list);
    Medium readMedium(const json& v, const std::string& key);
    TransmittanceModel readTransmittance(const json& v, const std::string& key, bool nested);
    DensityGrid readGrid(const json& v, const std::string& key);
    DensityGrid readVdbGrid(const json& v, const std::string& key);
    void readGridCommon(const json& v, const std::string& key, DensityGrid& g);
    int32_t mediumRef(const json& ref, const std::string& key);
    void checkEstimatorFitsMedia(const json& doc) const;

    std::string file_;
    fs::path baseDir_;
    Scene& scene_;
    std::set<std::string> ignoredSet_;
    std::vector<Material> namedBsdfs_;
    std::map<std::string, size_t> bsdfByName_;                 // first bsdf of each name
    std::vector<std::optional<uint32_t>> namedBsdfMaterial_;   // index in scene_.materials once used
    // Components of mixed and transparency bsdfs while reading: Material::component holds an index
    // here (a named bsdf, or an inline one in inlineComponents_), resolved to scene_.materials
    // indices when the material is first used, so unused bsdfs add no materials.
    struct ComponentRef {
        bool named;
        size_t index;
    };
    std::vector<ComponentRef> componentRefs_;
    std::vector<Material> inlineComponents_;
    std::map<std::string, int32_t> mediumByName_;
};

}  // namespace telescope::scene_reader
