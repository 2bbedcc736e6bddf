// Scene loading: Tungsten's conventions on known scenes, overrides, and bad input.
#include "scene/scene_loader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>

#include <gtest/gtest.h>
#include <fmt/format.h>
#include <unistd.h>

#include "core/error.h"

namespace telescope {
namespace {

namespace fs = std::filesystem;

constexpr float kPi = 3.14159265358979323846f;
constexpr const char* kFile = "test-scene.json";

// ---- Fixtures and helpers ----

// A scratch directory for mesh files, one per test process.
const fs::path& scratchDir() {
    static const fs::path dir = [] {
        fs::path d = fs::temp_directory_path() / ("telescope-scene-test-" + std::to_string(::getpid()));
        fs::create_directories(d);
        return d;
    }();
    return dir;
}

// Removes the scratch directory after the last test.
class ScratchCleanup : public testing::Environment {
public:
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(scratchDir(), ec);
    }
};
[[maybe_unused]] testing::Environment* const kScratchCleanup = testing::AddGlobalTestEnvironment(new ScratchCleanup);

void writeFile(const std::string& name, const std::string& bytes) {
    std::ofstream(scratchDir() / name, std::ios::binary) << bytes;
}

Scene load(const std::string& text, const std::vector<SceneOverride>& overrides = {}) {
    return loadSceneFromString(text, kFile, scratchDir().string(), overrides);
}

Scene cornellBox(const std::vector<SceneOverride>& overrides = {}) {
    return loadScene(TELESCOPE_SOURCE_DIR "/scenes/tungsten/cornell-box/scene.json", overrides);
}

// The four corners of a quad.
std::vector<glm::vec3> corners(const Geometry& g) { return {g.p0, g.p1, g.p1 + g.p2 - g.p0, g.p2}; }

std::vector<Geometry> geometryOf(const Scene& scene, const std::string& shapeName) {
    std::vector<Geometry> out;
    for (const Geometry& g : scene.geometry)
        if (scene.shapes.at(g.shape).name == shapeName) out.push_back(g);
    return out;
}

void expectVec(const glm::vec3& actual, const glm::vec3& expected, float tol = 1e-5f) {
    EXPECT_NEAR(actual.x, expected.x, tol) << "x";
    EXPECT_NEAR(actual.y, expected.y, tol) << "y";
    EXPECT_NEAR(actual.z, expected.z, tol) << "z";
}

void expectRelative(const glm::vec3& actual, const glm::vec3& expected, float relTol) {
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(actual[i], expected[i], std::abs(expected[i]) * relTol) << "component " << i;
}

bool hasIgnored(const Scene& s, const std::string& key) {
    return std::find(s.ignoredKeys.begin(), s.ignoredKeys.end(), key) != s.ignoredKeys.end();
}

// A one-primitive scene around the given primitive JSON object.
std::string withPrimitive(const std::string& primitive) {
    return R"({"bsdfs": [{"name": "white", "type": "lambert", "albedo": 0.5}], "primitives": [)" + primitive + "]}";
}

// ---- The Tungsten Cornell box ----

TEST(SceneLoader, CornellBoxCounts) {
    const Scene s = cornellBox();
    EXPECT_EQ(s.geometry.size(), 18u);  // analytic quads: 5 walls + 2 cubes x 6 + the light
    EXPECT_EQ(s.shapes.size(), 8u);
    EXPECT_EQ(s.materials.size(), 8u);
    EXPECT_TRUE(s.lights.empty());
    size_t emissive = 0;
    for (const Geometry& g : s.geometry) {
        EXPECT_EQ(g.type, GeometryType::Quad);
        EXPECT_NEAR(glm::length(g.normal), 1.0f, 1e-5f);
        EXPECT_GT(glm::dot(glm::cross(g.p1 - g.p0, g.p2 - g.p0), g.normal), 0.0f) << "winding follows the normal";
        if (g.emission != glm::vec3(0.0f)) {
            ++emissive;
            expectVec(g.emission, {17, 12, 4});
            EXPECT_EQ(s.shapes[g.shape].name, "light");
            EXPECT_EQ(s.materials[g.material].type, BsdfType::Null);
        }
    }
    EXPECT_EQ(emissive, 1u);
}

TEST(SceneLoader, CornellBoxSettings) {
    const Scene s = cornellBox();
    EXPECT_EQ(s.camera.width, 1000u);
    EXPECT_EQ(s.camera.height, 563u);
    EXPECT_FLOAT_EQ(s.camera.fovDegrees, 35.0f);
    EXPECT_EQ(s.camera.filter, PixelFilter::Tent);
    expectVec(s.camera.position, {0, 1, 6.8f});
    expectVec(s.camera.forward, {0, 0, -1});
    expectVec(s.camera.up, {0, 1, 0});
    expectVec(s.camera.right, {1, 0, 0});  // forward x up
    EXPECT_EQ(s.integrator.maxBounces, 64u);
    EXPECT_TRUE(s.integrator.enableLightSampling);
    EXPECT_TRUE(s.integrator.enableTwoSidedShading);
    EXPECT_EQ(s.integrator.debias.estimator, DebiasEstimator::None);
    EXPECT_EQ(s.renderer.spp, 64u);
    EXPECT_EQ(s.document["camera"]["fov"], 35);
    EXPECT_NE(s.path.find("cornell-box/scene.json"), std::string::npos);
}

TEST(SceneLoader, CornellBoxIgnoredKeysAreListedOnce) {
    const Scene s = cornellBox();
    EXPECT_TRUE(hasIgnored(s, "camera.tonemap"));
    EXPECT_TRUE(hasIgnored(s, "renderer.output_file"));
    // Honoured (the one value Telescope renders), not ignored:
    for (const char* key : {"integrator.enable_volume_light_sampling", "integrator.enable_consistency_checks",
                            "renderer.stratified_sampler", "renderer.enable_resume_render", "renderer.timeout",
                            "renderer.checkpoint_interval", "renderer.adaptive_sampling"})
        EXPECT_FALSE(hasIgnored(s, key)) << key;
    // Every key left ignored says why it cannot change the EXR.
    for (const std::string& key : s.ignoredKeys) EXPECT_FALSE(ignoredKeyReason(key).empty()) << key;
    EXPECT_FALSE(hasIgnored(s, "renderer.spp"));
    EXPECT_EQ(std::set<std::string>(s.ignoredKeys.begin(), s.ignoredKeys.end()).size(), s.ignoredKeys.size());
}

TEST(SceneLoader, CornellFloorSpansUnitSquareFacingUp) {
    // scale (2, 4, 2), rotation (0, 90, 0)
    const std::vector<Geometry> floor = geometryOf(cornellBox(), "floor");
    ASSERT_EQ(floor.size(), 1u);
    glm::vec3 lo(1e9f), hi(-1e9f);
    for (const Geometry& g : floor) {
        EXPECT_EQ(g.type, GeometryType::Quad);
        expectVec(g.normal, {0, 1, 0});
        for (const glm::vec3& p : corners(g)) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    }
    expectVec(lo, {-1, 0, -1});
    expectVec(hi, {1, 0, 1});
}

TEST(SceneLoader, CornellWallAndLightOrientations) {
    const Scene s = cornellBox();
    expectVec(geometryOf(s, "light").at(0).normal, {0, -1, 0});  // rotation (0, 180, 180)
    expectVec(geometryOf(s, "ceiling").at(0).normal, {0, -1, 0});
    // The walls face outward; two-sided shading makes them work
    expectVec(geometryOf(s, "leftWall").at(0).normal, {-1, 0, 0});
    expectVec(geometryOf(s, "rightWall").at(0).normal, {1, 0, 0});
    expectVec(geometryOf(s, "backWall").at(0).normal, {0, 0, -1});
}

TEST(SceneLoader, CornellCubesAreClosedWithOutwardNormals) {
    const Scene s = cornellBox();
    for (const char* name : {"shortBox", "tallBox"}) {
        const std::vector<Geometry> box = geometryOf(s, name);
        ASSERT_EQ(box.size(), 6u) << name;
        glm::vec3 centre(0.0f);
        for (const Geometry& g : box) centre += (g.p1 + g.p2) / 12.0f;  // face centres (p1 + p2) / 2
        for (const Geometry& g : box) EXPECT_GT(glm::dot((g.p1 + g.p2) / 2.0f - centre, g.normal), 0.0f) << name;
        float lowest = 1e9f;
        for (const Geometry& g : box)
            for (const glm::vec3& p : corners(g)) lowest = std::min(lowest, p.y);
        EXPECT_NEAR(lowest, 0.0f, 1e-4f) << name << " stands on the floor";
    }
}

// ---- The bundled scenes ----

TEST(BundledScenes, CornellBoxIsTheTungstenGeometryAt256) {
    const Scene s = loadScene(TELESCOPE_SOURCE_DIR "/scenes/cornell-box.json");
    EXPECT_EQ(s.geometry.size(), 18u);
    EXPECT_EQ(s.camera.width, 256u);
    EXPECT_EQ(s.camera.height, 256u);
    EXPECT_EQ(s.renderer.spp, 16u);
    EXPECT_TRUE(s.ignoredKeys.empty());
    const Scene tungsten = cornellBox();
    for (size_t i = 0; i < s.geometry.size(); ++i) {
        expectVec(s.geometry[i].p0, tungsten.geometry[i].p0);
        expectVec(s.geometry[i].emission, tungsten.geometry[i].emission);
    }
}

TEST(BundledScenes, FurnaceIsAClosedInwardEmittingBox) {
    const Scene s = loadScene(TELESCOPE_SOURCE_DIR "/scenes/furnace.json");
    ASSERT_EQ(s.geometry.size(), 6u);
    EXPECT_TRUE(s.ignoredKeys.empty());
    for (const Geometry& g : s.geometry) {
        const glm::vec3 centroid = (g.p1 + g.p2) / 2.0f;
        EXPECT_LT(glm::dot(centroid, g.normal), 0.0f) << "faces the camera at the origin";
        expectVec(g.emission, glm::vec3(1.0f));
        expectVec(s.materials[g.material].albedo, glm::vec3(0.5f));
    }
    expectVec(s.camera.position, glm::vec3(0.0f));
}

TEST(BundledScenes, PointPlane) {
    const Scene s = loadScene(TELESCOPE_SOURCE_DIR "/scenes/point-plane.json");
    EXPECT_TRUE(s.ignoredKeys.empty());
    ASSERT_EQ(s.lights.size(), 1u);
    expectRelative(s.lights[0].intensity, glm::vec3(1.0f), 1e-6f);
    expectVec(s.lights[0].position, {0, 1, 0});
    ASSERT_EQ(s.geometry.size(), 1u);
    expectVec(s.geometry[0].normal, {0, 1, 0});
    expectVec(s.camera.forward, {0, -1, 0});
}

// ---- Shapes, emission and power ----

TEST(SceneLoader, PowerToRadianceOnQuad) {
    // Tungsten's volumetric-caustic light: power (34, 24, 8) on 0.005 x 0.004
    const Scene s = load(withPrimitive(R"({"type": "quad", "bsdf": "white", "power": [34, 24, 8],
        "transform": {"scale": [0.005, 1, 0.004]}})"));
    ASSERT_EQ(s.geometry.size(), 1u);
    expectRelative(s.geometry[0].emission, {541127, 381972, 127324}, 1e-3f);
}

TEST(SceneLoader, PowerWinsOverEmission) {
    const Scene s = load(withPrimitive(R"({"type": "quad", "bsdf": "white", "power": 3.14159265, "emission": 7})"));
    expectRelative(s.geometry[0].emission, glm::vec3(1.0f), 1e-5f);  // unit area
    EXPECT_TRUE(hasIgnored(s, "primitives[0].emission"));
}

TEST(SceneLoader, SphereRadiusIsTheLargestScale) {
    const Scene s = load(withPrimitive(R"({"type": "sphere", "bsdf": "white", "power": 1,
        "transform": {"position": [1, 2, 3], "scale": [0.1, 0.3, 0.2]}})"));
    ASSERT_EQ(s.geometry.size(), 1u);
    const Geometry& g = s.geometry[0];
    EXPECT_EQ(g.type, GeometryType::Sphere);
    expectVec(g.p0, {1, 2, 3});
    EXPECT_FLOAT_EQ(g.radius, 0.3f);
    expectRelative(g.emission, glm::vec3(1.0f / (kPi * 4.0f * kPi * 0.09f)), 1e-5f);
}

TEST(SceneLoader, DiskFacesLocalYWithRadiusFromXZ) {
    const Scene s = load(withPrimitive(R"({"type": "disk", "bsdf": "white", "power": 1,
        "transform": {"position": [0, 1, 0], "scale": [2, 5, 3], "rotation": [90, 0, 0]}})"));
    ASSERT_EQ(s.geometry.size(), 1u);
    const Geometry& g = s.geometry[0];
    EXPECT_EQ(g.type, GeometryType::Disk);
    expectVec(g.p0, {0, 1, 0});
    expectVec(g.normal, {0, 0, 1});
    EXPECT_FLOAT_EQ(g.radius, 3.0f);
    expectRelative(g.emission, glm::vec3(1.0f / (kPi * kPi * 9.0f)), 1e-5f);
}

TEST(SceneLoader, CubePowerUsesTheWholeSurface) {
    const Scene s = load(withPrimitive(R"({"type": "cube", "bsdf": "white", "power": 1,
        "transform": {"scale": [1, 2, 3]}})"));
    ASSERT_EQ(s.geometry.size(), 6u);
    const float area = 2.0f * (1 * 2 + 2 * 3 + 3 * 1);
    for (const Geometry& g : s.geometry) expectRelative(g.emission, glm::vec3(1.0f / (kPi * area)), 1e-5f);
}

TEST(SceneLoader, PointLightIntensity) {
    const Scene s = load(R"({"primitives": [
        {"type": "point", "name": "bulb", "power": 12.566370614, "transform": {"position": [0, 2, 0]}},
        {"type": "point", "emission": [1, 2, 3]}]})");
    ASSERT_EQ(s.lights.size(), 2u);
    EXPECT_EQ(s.lights[0].type, LightType::Point);
    EXPECT_EQ(s.lights[0].name, "bulb");
    expectVec(s.lights[0].position, {0, 2, 0});
    expectRelative(s.lights[0].intensity, glm::vec3(1.0f), 1e-5f);  // power / (4 pi)
    expectVec(s.lights[1].intensity, {1, 2, 3});                   // emission is the intensity
    EXPECT_TRUE(s.geometry.empty());
    EXPECT_EQ(s.shapes.size(), 2u);
}

TEST(SceneLoader, ConstantEnvironment) {
    const Scene s = load(R"({"primitives": [{"type": "infinite_sphere", "emission": 0.5, "sample": true},
                                            {"type": "infinite_sphere", "power": 12.566370614}]})");
    ASSERT_EQ(s.lights.size(), 2u);
    EXPECT_EQ(s.lights[0].type, LightType::Environment);
    expectVec(s.lights[0].intensity, glm::vec3(0.5f));
    expectRelative(s.lights[1].intensity, glm::vec3(1.0f), 1e-5f);
    EXPECT_TRUE(hasIgnored(s, "primitives[0].sample"));
}

TEST(SceneLoader, ObjMeshIsTransformedWithCrossProductNormals) {
    writeFile("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 2 2\nf 1 2 3\nf 1 1 4\nf 1 3 2\n");
    const Scene s = load(withPrimitive(R"({"type": "mesh", "file": "tri.obj", "bsdf": "white", "smooth": true,
        "transform": {"position": [0, 0, 5]}})"));
    ASSERT_EQ(s.geometry.size(), 2u);  // the degenerate face is skipped
    expectVec(s.geometry[0].p0, {0, 0, 5});
    expectVec(s.geometry[0].p1, {1, 0, 5});
    expectVec(s.geometry[0].normal, {0, 0, 1});  // cross(p1 - p0, p2 - p0)
    expectVec(s.geometry[1].normal, {0, 0, -1});
    // "smooth" with a file without normals: each corner takes its face's normal
    EXPECT_TRUE(s.geometry[0].smooth);
    expectVec(s.geometry[0].vertexNormal[2], {0, 0, 1});
    EXPECT_TRUE(s.ignoredKeys.empty());
}

TEST(SceneLoader, SmoothMeshNormalsAreRecomputedOrTakenFromTheFileThroughTheInverseTranspose) {
    // Two faces folded 20 degrees apart along the z axis (within Tungsten's split angle of
    // 0.15 pi): face A (v1 v2 v3) has the area-weighted normal (0, 1, 0), face B (v2 v1 v4) has
    // (t, 1, 0), t = tan 20 degrees. The shared corners get normalize(t, 2, 0), the others their face's.
    const float t = 0.36397f;
    writeFile("fold.obj", fmt::format("v 0 0 0\nv 0 0 1\nv 1 0 0\nv -1 {} 0\nvn 0 1 0\nf 1//1 2//1 3//1\nf 2//1 1//1 4//1\n", t));
    Scene s = load(withPrimitive(R"({"type": "mesh", "file": "fold.obj", "bsdf": "white", "smooth": true,
        "recompute_normals": true})"));
    ASSERT_EQ(s.geometry.size(), 2u);
    expectVec(s.geometry[0].vertexNormal[0], glm::normalize(glm::vec3(t, 2, 0)));  // v1, on the fold
    expectVec(s.geometry[0].vertexNormal[1], glm::normalize(glm::vec3(t, 2, 0)));  // v2, on the fold
    expectVec(s.geometry[0].vertexNormal[2], {0, 1, 0});                           // v3: face A alone
    expectVec(s.geometry[1].vertexNormal[2], glm::normalize(glm::vec3(t, 1, 0)));  // v4: face B alone
    // A fold sharper than the split angle keeps each face's own normal at the shared corners.
    writeFile("sharp.obj", "v 0 0 0\nv 0 0 1\nv 1 0 0\nv -1 -1 0\nf 1 2 3\nf 2 1 4\n");
    s = load(withPrimitive(R"({"type": "mesh", "file": "sharp.obj", "bsdf": "white", "smooth": true,
        "recompute_normals": true})"));
    expectVec(s.geometry[0].vertexNormal[0], {0, 1, 0});
    expectVec(s.geometry[1].vertexNormal[1], s.geometry[1].normal);
    // The file's normals, scaled by (1, 2, 1): the inverse transpose keeps (0, 1, 0) a unit normal.
    s = load(withPrimitive(R"({"type": "mesh", "file": "fold.obj", "bsdf": "white", "smooth": true,
        "transform": {"scale": [1, 2, 1]}})"));
    expectVec(s.geometry[1].vertexNormal[2], {0, 1, 0});
    // recompute_normals without smooth: flat, as Tungsten (which recomputes only smooth meshes)
    s = load(withPrimitive(R"({"type": "mesh", "file": "fold.obj", "bsdf": "white", "recompute_normals": true})"));
    EXPECT_FALSE(s.geometry[0].smooth);
}

TEST(SceneLoader, Wo3MeshWithPerTriangleBsdfs) {
    // Two triangles: material 1 and material 7 (clamped to the last bsdf)
    std::string bytes;
    auto put = [&](const void* p, size_t n) { bytes.append(static_cast<const char*>(p), n); };
    const uint64_t numVerts = 4, numTris = 2;
    put(&numVerts, 8);
    const float verts[4][8] = {{0, 0, 0, 0, 0, 1, 0, 0}, {1, 0, 0, 0, 0, 1, 1, 0}, {0, 1, 0, 0, 0, 1, 0, 1}, {1, 1, 0, 0, 0, 1, 1, 1}};
    put(verts, sizeof(verts));
    put(&numTris, 8);
    const uint32_t tris[2][4] = {{0, 1, 2, 1}, {1, 3, 2, 7}};
    put(tris, sizeof(tris));
    writeFile("square.wo3", bytes);

    const Scene s = load(R"({"bsdfs": [{"name": "a", "type": "lambert"}, {"name": "b", "type": "mirror"}],
        "primitives": [{"type": "mesh", "file": "square.wo3", "bsdf": ["a", "b", {"type": "null"}], "power": 1}]})");
    ASSERT_EQ(s.geometry.size(), 2u);
    EXPECT_EQ(s.materials.size(), 3u);
    EXPECT_EQ(s.materials[s.geometry[0].material].type, BsdfType::Mirror);
    EXPECT_EQ(s.materials[s.geometry[1].material].type, BsdfType::Null);
    expectRelative(s.geometry[0].emission, glm::vec3(1.0f / kPi), 1e-5f);  // total area 1
}

TEST(SceneLoader, DefaultsWithoutCameraIntegratorOrRenderer) {
    const Scene s = load(R"({"primitives": []})");
    EXPECT_TRUE(s.geometry.empty());
    EXPECT_EQ(s.camera.width, 512u);
    EXPECT_FLOAT_EQ(s.camera.fovDegrees, 60.0f);
    expectVec(s.camera.forward, {0, 0, 1});
    expectVec(s.camera.right, glm::cross(s.camera.forward, s.camera.up));
    EXPECT_EQ(s.integrator.maxBounces, 64u);
    EXPECT_EQ(s.renderer.spp, 32u);
}

TEST(SceneLoader, BsdfSharingAndDefaults) {
    const Scene s = load(R"({"bsdfs": [{"name": "glass", "type": "dielectric"}, {"name": "unused", "type": "lambert"}],
        "primitives": [{"type": "quad", "bsdf": "glass"}, {"type": "sphere", "bsdf": "glass"},
                       {"type": "quad", "bsdf": {"type": "mirror", "albedo": [0.1, 0.2, 0.3]}}]})");
    ASSERT_EQ(s.materials.size(), 2u);  // one per bsdf used
    EXPECT_EQ(s.geometry[0].material, s.geometry[1].material);
    const Material& glass = s.materials[s.geometry[0].material];
    EXPECT_EQ(glass.type, BsdfType::Dielectric);
    EXPECT_FLOAT_EQ(glass.ior, 1.5f);
    EXPECT_TRUE(glass.enableRefraction);
    expectVec(glass.albedo, glm::vec3(1.0f));
    expectVec(s.materials[s.geometry[2].material].albedo, {0.1f, 0.2f, 0.3f});
}

TEST(SceneLoader, Conductors) {
    const Scene s = load(R"({"bsdfs": [{"name": "cu", "type": "rough_conductor"},
                                        {"name": "gold", "type": "conductor", "material": "Au", "albedo": 0.5},
                                        {"name": "custom", "type": "rough_conductor", "eta": [1, 2, 3], "k": 4,
                                         "distribution": "beckmann", "roughness": 0.25}],
        "primitives": [{"type": "quad", "bsdf": "cu"}, {"type": "quad", "bsdf": "gold"}, {"type": "quad", "bsdf": "custom"}]})");
    // Tungsten's defaults: copper, GGX, roughness 0.1.
    const Material& cu = s.materials[s.geometry[0].material];
    EXPECT_EQ(cu.type, BsdfType::RoughConductor);
    EXPECT_EQ(cu.distribution, shader::kMicrofacetGGX);
    EXPECT_FLOAT_EQ(cu.roughness, 0.1f);
    expectVec(cu.eta, {0.2004376970f, 0.9240334304f, 1.1022119527f});
    expectVec(cu.k, {3.9129485033f, 2.4528477015f, 2.1421879552f});
    const Material& gold = s.materials[s.geometry[1].material];
    EXPECT_EQ(gold.type, BsdfType::Conductor);
    expectVec(gold.eta, {0.1431189557f, 0.3749570432f, 1.4424785571f});
    expectVec(gold.k, {3.9831604247f, 2.3857207478f, 1.6032152899f});
    expectVec(gold.albedo, glm::vec3(0.5f));
    const Material& custom = s.materials[s.geometry[2].material];
    EXPECT_EQ(custom.distribution, shader::kMicrofacetBeckmann);
    EXPECT_FLOAT_EQ(custom.roughness, 0.25f);
    expectVec(custom.eta, {1, 2, 3});
    expectVec(custom.k, glm::vec3(4.0f));
}

TEST(SceneLoader, PlasticsOrenNayarRoughDielectric) {
    const Scene s = load(R"({"bsdfs": [{"name": "p", "type": "plastic"},
                                        {"name": "rp", "type": "rough_plastic", "ior": 1.3, "thickness": 2, "sigma_a": [0.1, 0.2, 0.3],
                                         "distribution": "beckmann", "roughness": 0.3},
                                        {"name": "on", "type": "oren_nayar"},
                                        {"name": "rd", "type": "rough_dielectric", "enable_refraction": false, "albedo": 0.5}],
        "primitives": [{"type": "quad", "bsdf": "p"}, {"type": "quad", "bsdf": "rp"}, {"type": "quad", "bsdf": "on"},
                       {"type": "quad", "bsdf": "rd"}]})");
    // Tungsten's defaults: ior 1.5, thickness 1, no absorption; rough plastic GGX 0.02; Oren-Nayar 1;
    // rough dielectric GGX 0.1.
    const Material& p = s.materials[s.geometry[0].material];
    EXPECT_EQ(p.type, BsdfType::Plastic);
    EXPECT_FLOAT_EQ(p.ior, 1.5f);
    EXPECT_FLOAT_EQ(p.thickness, 1.0f);
    expectVec(p.sigmaA, glm::vec3(0.0f));
    const Material& rp = s.materials[s.geometry[1].material];
    EXPECT_EQ(rp.type, BsdfType::RoughPlastic);
    EXPECT_FLOAT_EQ(rp.ior, 1.3f);
    EXPECT_FLOAT_EQ(rp.thickness, 2.0f);
    expectVec(rp.sigmaA, {0.1f, 0.2f, 0.3f});
    EXPECT_EQ(rp.distribution, shader::kMicrofacetBeckmann);
    EXPECT_FLOAT_EQ(rp.roughness, 0.3f);
    const Material& on = s.materials[s.geometry[2].material];
    EXPECT_EQ(on.type, BsdfType::OrenNayar);
    EXPECT_FLOAT_EQ(on.roughness, 1.0f);
    const Material& rd = s.materials[s.geometry[3].material];
    EXPECT_EQ(rd.type, BsdfType::RoughDielectric);
    EXPECT_FLOAT_EQ(rd.roughness, 0.1f);
    EXPECT_EQ(rd.distribution, shader::kMicrofacetGGX);
    EXPECT_FALSE(rd.enableRefraction);
    expectVec(rd.albedo, glm::vec3(0.5f));
}

TEST(SceneLoader, ThinSheetMixedTransparency) {
    const Scene s = load(R"({"bsdfs": [{"name": "sheet", "type": "thinsheet"},
                                        {"name": "film", "type": "thinsheet", "ior": 1.33, "thickness": 0.8,
                                         "sigma_a": [0.1, 0.2, 0.3], "enable_interference": true},
                                        {"name": "unused", "type": "rough_conductor"},
                                        {"name": "mix", "type": "mixed", "bsdf0": "sheet",
                                         "bsdf1": {"type": "lambert", "albedo": 0.25}, "ratio": 0.3, "albedo": 0.5},
                                        {"name": "leaf", "type": "transparency", "base": "mix", "alpha": 0.6},
                                        {"name": "default", "type": "transparency"}],
        "primitives": [{"type": "quad", "bsdf": "leaf"}, {"type": "quad", "bsdf": "sheet"}, {"type": "quad", "bsdf": "film"},
                       {"type": "quad", "bsdf": "default"}]})");
    // leaf, mix, sheet, the inline lambert, film, default, its white lambert base; no unused conductor.
    ASSERT_EQ(s.materials.size(), 7u);
    const Material& leaf = s.materials[s.geometry[0].material];
    EXPECT_EQ(leaf.type, BsdfType::Transparency);
    EXPECT_FLOAT_EQ(leaf.alpha, 0.6f);
    const Material& mix = s.materials[leaf.component[0]];
    EXPECT_EQ(mix.type, BsdfType::Mixed);
    EXPECT_FLOAT_EQ(mix.ratio, 0.3f);
    expectVec(mix.albedo, glm::vec3(0.5f));
    // The named component is the same material the second quad uses.
    EXPECT_EQ(mix.component[0], s.geometry[1].material);
    const Material& sheet = s.materials[mix.component[0]];
    EXPECT_EQ(sheet.type, BsdfType::ThinSheet);
    // Tungsten's defaults: ior 1.5, thickness 0.5, no absorption, no interference.
    EXPECT_FLOAT_EQ(sheet.ior, 1.5f);
    EXPECT_FLOAT_EQ(sheet.thickness, 0.5f);
    expectVec(sheet.sigmaA, glm::vec3(0.0f));
    EXPECT_FALSE(sheet.enableInterference);
    const Material& inlined = s.materials[mix.component[1]];
    EXPECT_EQ(inlined.type, BsdfType::Lambert);
    expectVec(inlined.albedo, glm::vec3(0.25f));
    const Material& film = s.materials[s.geometry[2].material];
    EXPECT_FLOAT_EQ(film.ior, 1.33f);
    EXPECT_FLOAT_EQ(film.thickness, 0.8f);
    expectVec(film.sigmaA, {0.1f, 0.2f, 0.3f});
    EXPECT_TRUE(film.enableInterference);
    // Tungsten's transparency defaults: alpha 1 over a white lambert.
    const Material& def = s.materials[s.geometry[3].material];
    EXPECT_FLOAT_EQ(def.alpha, 1.0f);
    EXPECT_EQ(s.materials[def.component[0]].type, BsdfType::Lambert);
    expectVec(s.materials[def.component[0]].albedo, glm::vec3(1.0f));
    for (const Material& m : s.materials) EXPECT_NE(m.type, BsdfType::RoughConductor);
}

TEST(SceneLoader, UnknownKeysAreIgnoredNotErrors) {
    const Scene s = load(R"({"primitives": [], "version": 2, "camera": {"vignette": 1}})");
    EXPECT_TRUE(hasIgnored(s, "version"));
    EXPECT_TRUE(hasIgnored(s, "camera.vignette"));
}

TEST(SceneLoader, DebiasSettings) {
    Scene s = load(R"({"integrator": {"type": "path_tracer", "min_bounces": 1, "max_bounces": 5,
        "enable_light_sampling": false, "debias": {"estimator": "sum", "pmf": {"type": "power_law", "alpha": 0.5}}}})");
    EXPECT_EQ(s.integrator.minBounces, 1u);
    EXPECT_EQ(s.integrator.maxBounces, 5u);
    EXPECT_FALSE(s.integrator.enableLightSampling);
    EXPECT_EQ(s.integrator.debias.estimator, DebiasEstimator::Sum);
    EXPECT_EQ(s.integrator.debias.pmf.type, PmfType::PowerLaw);
    EXPECT_FLOAT_EQ(s.integrator.debias.pmf.alpha, 0.5f);

    s = load(R"({"integrator": {"debias": {"estimator": "single_term"}}})");
    EXPECT_EQ(s.integrator.debias.estimator, DebiasEstimator::SingleTerm);
    EXPECT_EQ(s.integrator.debias.pmf.type, PmfType::Geometric);
    EXPECT_FLOAT_EQ(s.integrator.debias.pmf.r, 0.25f);  // the path-depth default
    EXPECT_NE(s.integrator.debias.pmf.origin.find("default for path depth"), std::string::npos);
    EXPECT_FLOAT_EQ(s.integrator.debias.testPmfWeight, 1.0f);

    // The transmittance default differs (docs/ESTIMATORS.md section 1).
    EXPECT_FLOAT_EQ(s.integrator.transmittance.pmf.r, 0.65f);
    // Debiased marching takes "auto" too (the transmittance pilot), with its own pilot size.
    s = load(R"({"integrator": {"transmittance_estimator": {"type": "debiased_ray_march", "pmf": {"type": "auto"}}}})");
    EXPECT_EQ(s.integrator.transmittance.pmf.type, PmfType::Auto);
    EXPECT_EQ(s.integrator.transmittance.pmf.pilotSpp, 2u);
    EXPECT_EQ(s.integrator.transmittance.pmf.pilotLevels, 5u);
    EXPECT_STREQ(autoPmfKey(s.integrator), "integrator.transmittance_estimator.pmf.type");
    s = load(R"({"integrator": {"debias": {"estimator": "single_term", "pmf": {"type": "auto"}}}})");
    EXPECT_STREQ(autoPmfKey(s.integrator), "integrator.debias.pmf.type");
    s = load(R"({"integrator": {"debias": {"estimator": "single_term", "pmf": {"type": "geometric"}, "test_pmf_weight": 1.07}}})");
    EXPECT_FLOAT_EQ(s.integrator.debias.pmf.r, 0.25f);
    EXPECT_EQ(s.integrator.debias.pmf.origin, "given in the scene");
    EXPECT_FLOAT_EQ(s.integrator.debias.testPmfWeight, 1.07f);
}

TEST(SceneLoader, PhotonMapSettings) {
    Scene s = load(R"({"integrator": {"type": "photon_map", "photon_count": 5000, "gather_radius": 0.25,
        "max_bounces": 7, "kernel": "epanechnikov", "direct_lighting": "photons", "gather_photon_count": 20}})");
    EXPECT_EQ(s.integrator.type, IntegratorType::PhotonMap);
    EXPECT_TRUE(usesPhotons(s.integrator));
    EXPECT_EQ(s.integrator.photon.photonCount, 5000u);
    EXPECT_FLOAT_EQ(s.integrator.photon.gatherRadius, 0.25f);
    EXPECT_EQ(s.integrator.maxBounces, 7u);
    EXPECT_EQ(s.integrator.photon.kernel, PhotonKernel::Epanechnikov);
    EXPECT_EQ(s.integrator.photon.directLighting, DirectLighting::Photons);
    EXPECT_EQ(s.integrator.debias.estimator, DebiasEstimator::None);
    EXPECT_EQ(s.integrator.photon.gatherCount, 20u);  // Tungsten's k nearest, with the kernel given
    EXPECT_TRUE(s.ignoredKeys.empty());
    // Without a kernel a k-nearest gather takes Tungsten's uniform one; without the key, every
    // photon within the radius counts (cone kernel).
    s = load(R"({"integrator": {"type": "progressive_photon_map", "gather_radius": 0.1, "gather_photon_count": 8}})");
    EXPECT_EQ(s.integrator.photon.gatherCount, 8u);
    EXPECT_EQ(s.integrator.photon.kernel, PhotonKernel::Uniform);
    s = load(R"({"integrator": {"type": "progressive_photon_map", "gather_radius": 0.1}})");
    EXPECT_EQ(s.integrator.photon.gatherCount, 0u);
    EXPECT_EQ(s.integrator.photon.kernel, PhotonKernel::Cone);

    // A debias block without a pmf takes the block defaults (docs/PHOTON-MAPPING.md): geometric
    // r = 0.7, s = 1/sqrt(2), m = 3, K = 20 (s^K < 1e-3), uniform schedule.
    s = load(R"({"integrator": {"type": "progressive_photon_map", "gather_radius": 0.1, "alpha": 0.5,
        "debias": {"estimator": "single_term"}}})");
    EXPECT_EQ(s.integrator.type, IntegratorType::ProgressivePhotonMap);
    EXPECT_EQ(s.integrator.photon.kernel, PhotonKernel::Cone);
    EXPECT_EQ(s.integrator.photon.directLighting, DirectLighting::NextEvent);
    EXPECT_EQ(s.integrator.debias.pmf.type, PmfType::Geometric);
    EXPECT_FLOAT_EQ(s.integrator.debias.pmf.r, 0.7f);
    EXPECT_NEAR(s.integrator.debias.photon.areaRatio, 0.70710678f, 1e-6f);
    EXPECT_EQ(s.integrator.debias.photon.photonGrowth, 3u);
    EXPECT_EQ(s.integrator.debias.photon.levelCap, 20u);
    EXPECT_EQ(s.integrator.debias.schedule, LevelSchedule::Uniform);
}

// ---- Overrides ----

// Tungsten's transmittance models: the shader's model type (shared/transmittance.h) and each
// parameter's default, by name; given parameters replace the defaults.
TEST(SceneLoader, TransmittanceModelsByNameWithTungstenDefaults) {
    struct Expected {
        const char* json;
        uint32_t type;
        glm::vec4 params;
    };
    const Expected cases[] = {
        {R"({"type": "exponential"})", 0, {0, 0, 0, 0}},
        {R"({"type": "linear"})", 1, {1, 0, 0, 0}},
        {R"({"type": "quadratic"})", 2, {0.75f, 0, 0, 0}},
        {R"({"type": "double_exponential"})", 3, {0.5f, 10, 0, 0}},
        {R"({"type": "erlang"})", 4, {5, 0, 0, 0}},
        {R"({"type": "davis"})", 5, {1.1f, 0, 0, 0}},
        {R"({"type": "davis_weinstein"})", 6, {0.75f, 1, 0, 0}},
        {R"({"type": "pulse"})", 7, {0, 1, 4, 0}},
        {R"({"type": "pulse", "min": 0.5, "max": 2, "num_pulses": 7})", 7, {0.5f, 2, 7, 0}},
        {R"({"type": "davis_weinstein", "h": 0.6, "c": 3})", 6, {0.6f, 3, 0, 0}},
        {R"({"type": "double_exponential", "sigma_b": 4})", 3, {0.5f, 4, 0, 0}},
    };
    for (const Expected& e : cases) {
        const Scene s = load(std::string(R"({"media": [{"type": "homogeneous", "transmittance": )") + e.json + "}]}");
        const TransmittanceModel& t = s.media.at(0).transmittance;
        EXPECT_EQ(t.type, e.type) << e.json;
        EXPECT_EQ(t.params, e.params) << e.json;
        EXPECT_EQ(t.typeA, e.type) << e.json;
        EXPECT_EQ(t.typeB, e.type) << e.json;
        EXPECT_EQ(t.paramsB, e.params) << e.json;
    }
    // Interpolated: linear (max_t 1) and erlang (rate 5) by default, mixed half and half.
    Scene s = load(R"({"media": [{"type": "homogeneous", "transmittance": {"type": "interpolated"}}]})");
    TransmittanceModel t = s.media.at(0).transmittance;
    EXPECT_EQ(t.type, 8u);
    EXPECT_EQ(t.typeA, 1u);
    EXPECT_EQ(t.params, glm::vec4(1, 0, 0, 0));
    EXPECT_EQ(t.typeB, 4u);
    EXPECT_EQ(t.paramsB, glm::vec4(5, 0, 0, 0));
    EXPECT_EQ(t.ratio, 0.5f);
    s = load(R"({"media": [{"type": "homogeneous", "transmittance": {"type": "interpolated", "ratio": 0.25,
                "tr_a": {"type": "davis", "alpha": 2}, "tr_b": {"type": "quadratic"}}}]})");
    t = s.media.at(0).transmittance;
    EXPECT_EQ(t.typeA, 5u);
    EXPECT_EQ(t.params, glm::vec4(2, 0, 0, 0));
    EXPECT_EQ(t.typeB, 2u);
    EXPECT_EQ(t.paramsB, glm::vec4(0.75f, 0, 0, 0));
    EXPECT_EQ(t.ratio, 0.25f);
    EXPECT_EQ(t.name, "interpolated");
}

TEST(SceneOverrides, ParseSplitsAtTheFirstEquals) {
    const SceneOverride o = parseOverride("renderer.output_file=a=b.png");
    EXPECT_EQ(o.key, "renderer.output_file");
    EXPECT_EQ(o.value, "a=b.png");
}

TEST(SceneOverrides, AppliedBeforeInterpretation) {
    const Scene s = cornellBox({parseOverride("camera.resolution=[64,48]"), parseOverride("integrator.max_bounces=3"),
                                parseOverride(R"(primitives[2].bsdf={"type":"mirror"})"),
                                parseOverride("integrator.debias.estimator=sum"),
                                parseOverride("integrator.debias.pmf.r=0.5"),
                                parseOverride("renderer.output_file=out.png")});
    EXPECT_EQ(s.camera.width, 64u);
    EXPECT_EQ(s.camera.height, 48u);
    EXPECT_EQ(s.integrator.maxBounces, 3u);
    EXPECT_EQ(s.materials[geometryOf(s, "backWall").at(0).material].type, BsdfType::Mirror);
    EXPECT_EQ(s.integrator.debias.estimator, DebiasEstimator::Sum);  // bare string value
    EXPECT_FLOAT_EQ(s.integrator.debias.pmf.r, 0.5f);
    EXPECT_EQ(s.document["camera"]["resolution"], nlohmann::json::parse("[64,48]"));
    EXPECT_EQ(s.document["renderer"]["output_file"], "out.png");
}

TEST(SceneOverrides, ScalarAndBooleanValues) {
    const Scene s = load(R"({"integrator": {}})", {parseOverride("camera.resolution=128"),
                                                    parseOverride("integrator.enable_light_sampling=false")});
    EXPECT_EQ(s.camera.width, 128u);
    EXPECT_EQ(s.camera.height, 128u);
    EXPECT_FALSE(s.integrator.enableLightSampling);
}

// Textures (docs/SCENE-FORMAT.md, "Textures"): Tungsten's value forms and defaults.
TEST(SceneLoader, TexturesOnAlbedoAndRoughness) {
    const Scene s = load(withPrimitive(R"({"type": "quad", "bsdf": {"type": "oren_nayar",
        "albedo": {"type": "checker", "on_color": [1, 0.5, 0], "res_u": 3},
        "roughness": {"type": "checker", "on_color": [0.7, 0.1, 0.1], "off_color": 0.2, "res_v": 5}}},
        {"type": "quad", "bsdf": {"type": "rough_conductor", "albedo": {"type": "constant", "value": 0.25},
                                  "roughness": [0.3, 0.4, 0.5]}},
        {"type": "quad", "bsdf": {"type": "lambert", "albedo": {"type": "checker"}}})"));
    const Material& on = s.materials[s.geometry[0].material];
    ASSERT_EQ(on.albedoTexture, 0);
    ASSERT_EQ(on.roughnessTexture, 1);
    const Texture& albedo = s.textures[0];
    EXPECT_EQ(albedo.type, TextureType::Checker);
    expectVec(albedo.on, {1.0f, 0.5f, 0.0f});
    expectVec(albedo.off, glm::vec3(0.2f));  // Tungsten's defaults: 0.2, res 20
    EXPECT_EQ(albedo.resU, 3u);
    EXPECT_EQ(albedo.resV, 20u);
    // A scalar parameter takes the first channel.
    expectVec(s.textures[1].on, glm::vec3(0.7f));
    expectVec(s.textures[1].off, glm::vec3(0.2f));
    EXPECT_EQ(s.textures[1].resV, 5u);
    // Constants stay constants: no texture.
    const Material& cu = s.materials[s.geometry[1].material];
    EXPECT_EQ(cu.albedoTexture, -1);
    EXPECT_EQ(cu.roughnessTexture, -1);
    expectVec(cu.albedo, glm::vec3(0.25f));
    EXPECT_FLOAT_EQ(cu.roughness, 0.3f);
    const Texture& plain = s.textures[s.materials[s.geometry[2].material].albedoTexture];
    expectVec(plain.on, glm::vec3(0.8f));
    EXPECT_EQ(plain.resU, 20u);
    // Tungsten's quad uv: (0, 1) at the base corner, (1, 1) along the local x edge, (0, 0) along z
    // (the three corners the quad stores, in its own order).
    const Geometry& q = s.geometry[0];
    for (int k = 0; k < 3; ++k) {
        const glm::vec3 p = k == 0 ? q.p0 : k == 1 ? q.p1 : q.p2;
        EXPECT_FLOAT_EQ(q.uv[k].x, p.x + 0.5f) << k;
        EXPECT_FLOAT_EQ(q.uv[k].y, 0.5f - p.z) << k;
    }
}

// ---- Bad input: each error names the file and the offending key path ----

struct BadInput {
    const char* name;
    std::string text;             // the scene
    std::string override_;        // a --set applied to it, if any
    std::string key;              // expected InputError::key()
    std::string message;          // expected in what()
    std::string file = kFile;     // expected InputError::file() ("" = command line)
};

void PrintTo(const BadInput& c, std::ostream* os) { *os << c.name; }

class SceneLoaderBadInput : public testing::TestWithParam<BadInput> {};

TEST_P(SceneLoaderBadInput, NamesFileAndKey) {
    const BadInput& c = GetParam();
    writeFile("garbage.obj", "this is not an obj\nf a b c\n");
    writeFile("oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    writeFile("short.wo3", std::string("\x05\0\0\0\0\0\0\0abc", 11));
    writeFile("garbage.png", "this is not a png\n");
    try {
        std::vector<SceneOverride> overrides;
        if (!c.override_.empty()) overrides.push_back(parseOverride(c.override_));
        load(c.text, overrides);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_EQ(e.file(), c.file);
        EXPECT_EQ(e.key(), c.key);
        EXPECT_NE(what.find(c.file.empty() ? "command line" : c.file), std::string::npos) << what;
        EXPECT_NE(what.find(c.key), std::string::npos) << what;
        EXPECT_NE(what.find(c.message), std::string::npos) << what;
        if (c.file.empty()) {
            EXPECT_NE(what.find(kFile), std::string::npos) << "names the scene: " << what;
        }
    }
}

const std::string kQuad = R"({"type": "quad", "bsdf": "white"})";

INSTANTIATE_TEST_SUITE_P(
    Cases, SceneLoaderBadInput,
    testing::Values(
        BadInput{"MalformedJson", "{\n  \"primitives\": [\n    {\"type\": }\n  ]\n}", "", "", "line 3"},
        BadInput{"TopLevelNotObject", "[1, 2]", "", "", "top level"},
        BadInput{"UnknownPrimitiveType", withPrimitive(R"({"type": "teapot"})"), "", "primitives[0].type", "unknown primitive type 'teapot'"},
        BadInput{"UnsupportedPrimitiveType", withPrimitive(R"({"type": "curves"})"), "", "primitives[0].type", "unsupported primitive type 'curves'"},
        BadInput{"UnsupportedBsdfType", R"({"bsdfs": [{"type": "smooth_coat"}]})", "", "bsdfs[0].type", "unsupported bsdf type 'smooth_coat'"},
        BadInput{"UnknownConductor", R"({"bsdfs": [{"type": "conductor", "material": "Unobtainium"}]})", "", "bsdfs[0].material", "unknown conductor 'Unobtainium'"},
        BadInput{"ConductorEtaWithoutK", R"({"bsdfs": [{"type": "rough_conductor", "eta": 1.2}]})", "", "bsdfs[0].k", "go together"},
        BadInput{"ConductorMaterialAndEta", R"({"bsdfs": [{"type": "conductor", "material": "Au", "eta": 1, "k": 2}]})", "", "bsdfs[0].eta", "not both"},
        BadInput{"UnknownDistribution", R"({"bsdfs": [{"type": "rough_conductor", "distribution": "blinn"}]})", "", "bsdfs[0].distribution", "unknown distribution 'blinn'"},
        BadInput{"MissingRoughnessBitmap", R"({"bsdfs": [{"type": "rough_conductor", "roughness": "r.png"}]})", "", "bsdfs[0].roughness", "cannot open image file"},
        BadInput{"RoughnessTextureBadType", R"({"bsdfs": [{"type": "oren_nayar", "roughness": true}]})", "", "bsdfs[0].roughness", "expected a number, a colour"},
        BadInput{"NegativeRoughness", R"({"bsdfs": [{"type": "rough_conductor", "roughness": -0.1}]})", "", "bsdfs[0].roughness", "must not be negative"},
        BadInput{"PlasticNegativeThickness", R"({"bsdfs": [{"type": "plastic", "thickness": -1}]})", "", "bsdfs[0].thickness", "must not be negative"},
        BadInput{"RoughDielectricZeroIor", R"({"bsdfs": [{"type": "rough_dielectric", "ior": 0}]})", "", "bsdfs[0].ior", "must be positive"},
        BadInput{"OrenNayarRoughnessCheckerFractionalRes", R"({"bsdfs": [{"type": "oren_nayar", "roughness": {"type": "checker", "res_v": 2.5}}]})", "", "bsdfs[0].roughness.res_v", "expected an integer"},
        BadInput{"MixedTexturedRatio", R"({"bsdfs": [{"name": "a", "type": "lambert"}, {"type": "mixed", "bsdf0": "a", "bsdf1": "a", "ratio": "r.png"}]})", "", "bsdfs[1].ratio", "a textured ratio is not supported"},
        BadInput{"MixedRatioAboveOne", R"({"bsdfs": [{"name": "a", "type": "lambert"}, {"type": "mixed", "bsdf0": "a", "bsdf1": "a", "ratio": 1.5}]})", "", "bsdfs[1].ratio", "must be in [0, 1]"},
        BadInput{"MixedWithoutBsdf1", R"({"bsdfs": [{"name": "a", "type": "lambert"}, {"type": "mixed", "bsdf0": "a"}]})", "", "bsdfs[1].bsdf1", "needs"},
        BadInput{"MixedComponentDefinedLater", R"({"bsdfs": [{"name": "m", "type": "mixed", "bsdf0": "b", "bsdf1": "b"}, {"name": "b", "type": "lambert"}]})", "", "bsdfs[0].bsdf0", "unknown bsdf 'b'"},
        BadInput{"MixedOfItself", R"({"bsdfs": [{"name": "m", "type": "mixed", "bsdf0": "m", "bsdf1": {"type": "lambert"}}]})", "", "bsdfs[0].bsdf0", "unknown bsdf 'm'"},
        BadInput{"MixedInlineComponentError", R"({"bsdfs": [{"type": "mixed", "bsdf0": {"type": "lambert"}, "bsdf1": {"type": "velvet"}}]})", "", "bsdfs[0].bsdf1.type", "unknown bsdf type 'velvet'"},
        BadInput{"TransparencyTexturedAlpha", R"({"bsdfs": [{"type": "transparency", "alpha": {"type": "bitmap", "file": "leaf.png"}}]})", "", "bsdfs[0].alpha", "a textured alpha is not supported"},
        BadInput{"TransparencyNegativeAlpha", R"({"bsdfs": [{"type": "transparency", "alpha": -0.1}]})", "", "bsdfs[0].alpha", "must be in [0, 1]"},
        BadInput{"ThinSheetNegativeSigmaA", R"({"bsdfs": [{"type": "thinsheet", "sigma_a": [0, -1, 0]}]})", "", "bsdfs[0].sigma_a", "non-negative"},
        BadInput{"ThinSheetTexturedThickness", R"({"bsdfs": [{"type": "thinsheet", "thickness": "t.png"}]})", "", "bsdfs[0].thickness", "textured thickness"},
        BadInput{"NestedTooDeep", withPrimitive(R"({"type": "quad", "bsdf": )" + [] {
            std::string b = R"({"type": "lambert"})";
            for (int i = 0; i < 9; ++i) b = R"({"type": "transparency", "alpha": 0.5, "base": )" + b + "}";
            return b;
        }() + "}"), "", "primitives[0].bsdf", "nest at most 8 deep"},
        BadInput{"UnknownBsdfType", R"({"bsdfs": [{"type": "velvet"}]})", "", "bsdfs[0].type", "unknown bsdf type 'velvet'"},
        BadInput{"UnknownBsdfName", withPrimitive(kQuad + "," + R"({"type": "quad", "bsdf": "black"})"), "", "primitives[1].bsdf", "unknown bsdf 'black'"},
        BadInput{"MissingBsdf", withPrimitive(R"({"type": "sphere"})"), "", "primitives[0]", "missing 'bsdf'"},
        BadInput{"AlbedoWrongType", R"({"bsdfs": [{"type": "lambert", "albedo": true}]})", "", "bsdfs[0].albedo", "expected a number"},
        BadInput{"AlbedoNegative", R"({"bsdfs": [{"type": "lambert", "albedo": [1, -1, 1]}]})", "", "bsdfs[0].albedo", "non-negative"},
        BadInput{"MissingBitmap", R"({"bsdfs": [{"type": "lambert", "albedo": "wood.png"}]})", "", "bsdfs[0].albedo", "cannot open image file"},
        BadInput{"UnreadableBitmap", R"({"bsdfs": [{"type": "lambert", "albedo": {"type": "bitmap", "file": "garbage.png"}}]})", "", "bsdfs[0].albedo.file", "cannot read image"},
        BadInput{"BitmapWithoutFile", R"({"bsdfs": [{"type": "lambert", "albedo": {"type": "bitmap"}}]})", "", "bsdfs[0].albedo", "needs a \"file\""},
        BadInput{"UnknownTextureType", R"({"bsdfs": [{"type": "lambert", "albedo": {"type": "wood"}}]})", "", "bsdfs[0].albedo.type", "unknown texture type 'wood'"},
        BadInput{"UnsupportedTextureType", R"({"bsdfs": [{"type": "lambert", "albedo": {"type": "ies"}}]})", "", "bsdfs[0].albedo.type", "unsupported texture type 'ies'"},
        BadInput{"CheckerZeroResU", R"({"bsdfs": [{"type": "lambert", "albedo": {"type": "checker", "res_u": 0}}]})", "", "bsdfs[0].albedo.res_u", "expected an integer"},
        BadInput{"CheckerNegativeColour", R"({"bsdfs": [{"type": "lambert", "albedo": {"type": "checker", "off_color": -1}}]})", "", "bsdfs[0].albedo.off_color", "non-negative"},
        BadInput{"StratifiedSampler", R"({"renderer": {"stratified_sampler": true}})", "", "renderer.stratified_sampler", "true is not supported"},
        BadInput{"ResumeRender", R"({"renderer": {"enable_resume_render": true}})", "", "renderer.enable_resume_render", "--resume"},
        BadInput{"RendererTimeout", R"({"renderer": {"timeout": "1h"}})", "", "renderer.timeout", "--time"},
        BadInput{"CheckpointInterval", R"({"renderer": {"checkpoint_interval": 60}})", "", "renderer.checkpoint_interval", "--checkpoint-every"},
        BadInput{"ConsistencyChecks", R"({"integrator": {"enable_consistency_checks": true}})", "", "integrator.enable_consistency_checks", "true is not supported"},
        BadInput{"NoVolumeLightSampling", R"({"integrator": {"enable_volume_light_sampling": false}})", "", "integrator.enable_volume_light_sampling", "false is not supported"},
        BadInput{"NearestGatherDebiased", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "gather_photon_count": 20, "debias": {"estimator": "single_term"}}})", "", "integrator.gather_photon_count", "cannot be debiased"},
        BadInput{"NearestGatherTooMany", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "gather_photon_count": 65}})", "", "integrator.gather_photon_count", ""},
        BadInput{"NearestGatherNegative", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "gather_photon_count": -1}})", "", "integrator.gather_photon_count", ""},
        BadInput{"EnvironmentImageMissing", withPrimitive(R"({"type": "infinite_sphere", "emission": "sky.hdr"})"), "", "primitives[0].emission", "cannot read image"},
        BadInput{"EnvironmentImageNotAnImage", withPrimitive(R"({"type": "infinite_sphere", "emission": "garbage.obj"})"), "", "primitives[0].emission", "cannot read image"},
        BadInput{"EnvironmentImageNoFile", withPrimitive(R"({"type": "infinite_sphere", "emission": {"type": "bitmap"}})"), "", "primitives[0].emission", "missing 'file'"},
        BadInput{"EnvironmentTextureType", withPrimitive(R"({"type": "infinite_sphere", "emission": {"type": "checker"}})"), "", "primitives[0].emission.type", "unsupported texture type 'checker'"},
        BadInput{"EnvironmentImageScale", withPrimitive(R"({"type": "infinite_sphere", "emission": {"type": "bitmap", "file": "sky.hdr", "scale": -1}})"), "", "primitives[0].emission.scale", "non-negative"},
        BadInput{"BitmapEmissionOnAQuad", withPrimitive(R"({"type": "quad", "bsdf": "white", "emission": "sky.hdr"})"), "", "primitives[0].emission", "textures are not supported"},
        BadInput{"ScaleWrongLength", withPrimitive(R"({"type": "quad", "bsdf": "white", "transform": {"scale": [1, 2]}})"), "", "primitives[0].transform.scale", "3 numbers"},
        BadInput{"ScaleComponentString", withPrimitive(R"({"type": "quad", "bsdf": "white", "transform": {"scale": [1, "2", 3]}})"), "", "primitives[0].transform.scale[1]", "expected a number"},
        BadInput{"MatrixWrongLength", withPrimitive(R"({"type": "quad", "bsdf": "white", "transform": [1, 0, 0]})"), "", "primitives[0].transform", "16"},
        BadInput{"LookAtEqualsPosition", R"({"camera": {"transform": {"position": [1, 1, 1], "look_at": [1, 1, 1]}}})", "", "camera.transform.look_at", "look_at equals position"},
        BadInput{"NumberOverflow", R"({"camera": {"fov": 1e999}})", "", "", "number overflow"},
        BadInput{"NumberTooLargeForFloat", R"({"camera": {"fov": 1e39}})", "", "camera.fov", "too large"},
        BadInput{"FovString", R"({"camera": {"fov": "wide"}})", "", "camera.fov", "expected a number"},
        BadInput{"NegativeResolution", R"({"camera": {"resolution": [-64, 64]}})", "", "camera.resolution[0]", "expected an integer in [1, 16384]"},
        BadInput{"HugeResolution", R"({"camera": {"resolution": 20000}})", "", "camera.resolution", "expected an integer in [1, 16384]"},
        BadInput{"ResolutionWrongLength", R"({"camera": {"resolution": [1, 2, 3]}})", "", "camera.resolution", "[width, height]"},
        BadInput{"CameraThinlens", R"({"camera": {"type": "thinlens"}})", "", "camera.type", "unsupported camera type 'thinlens'"},
        BadInput{"UnknownFilter", R"({"camera": {"reconstruction_filter": "sinc"}})", "", "camera.reconstruction_filter", "unknown reconstruction filter"},
        BadInput{"ZeroSpp", R"({"renderer": {"spp": 0}})", "", "renderer.spp", "expected an integer"},
        BadInput{"AdaptiveSampling", R"({"renderer": {"adaptive_sampling": true}})", "", "renderer.adaptive_sampling", "same number of samples"},
        BadInput{"BumpMap", withPrimitive(R"({"type": "quad", "bsdf": {"type": "lambert", "bump": "b.png"}})"), "", "primitives[0].bsdf.bump", "bump maps are not supported"},
        BadInput{"DiskConeAngle", withPrimitive(R"({"type": "disk", "bsdf": "white", "emission": 1, "cone_angle": 30})"), "", "primitives[0].cone_angle", "only 90"},
        BadInput{"FractionalSpp", R"({"renderer": {"spp": 1.5}})", "", "renderer.spp", "expected an integer"},
        BadInput{"MaxBouncesNegative", R"({"integrator": {"max_bounces": -1}})", "", "integrator.max_bounces", "expected an integer in [0, 1024]"},
        BadInput{"MaxBouncesString", R"({"integrator": {"max_bounces": "64"}})", "", "integrator.max_bounces", "expected an integer"},
        BadInput{"MaxBouncesTooLarge", R"({"integrator": {"max_bounces": 5000}})", "", "integrator.max_bounces", "expected an integer in [0, 1024]"},
        BadInput{"LightSamplingNotBool", R"({"integrator": {"enable_light_sampling": 1}})", "", "integrator.enable_light_sampling", "true or false"},
        BadInput{"MaxBouncesZero", R"({"integrator": {"max_bounces": 0}})", "", "integrator.max_bounces", "counts the light connection"},
        BadInput{"LowOrderScatteringOff", R"({"integrator": {"low_order_scattering": false}})", "", "integrator.low_order_scattering", "false is not supported"},
        BadInput{"IncludeSurfacesOff", R"({"integrator": {"include_surfaces": false}})", "", "integrator.include_surfaces", "false is not supported"},
        BadInput{"MediumMaxBouncesNegative", R"({"media": [{"name": "m", "type": "homogeneous", "max_bounces": -1}]})", "", "media[0].max_bounces", "expected an integer"},
        BadInput{"UnsupportedIntegrator", R"({"integrator": {"type": "light_tracer"}})", "", "integrator.type", "unsupported integrator type 'light_tracer'"},
        BadInput{"PhotonMapWithoutRadius", R"({"integrator": {"type": "photon_map"}})", "", "integrator.gather_radius", "missing"},
        BadInput{"PhotonRadiusNegative", R"({"integrator": {"type": "photon_map", "gather_radius": -1}})", "", "integrator.gather_radius", "must be positive"},
        BadInput{"PhotonCountZero", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "photon_count": 0}})", "", "integrator.photon_count", "expected an integer"},
        BadInput{"PhotonCountHuge", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "photon_count": 1e10}})", "", "integrator.photon_count", "expected an integer"},
        BadInput{"PhotonAlphaOutOfRange", R"({"integrator": {"type": "progressive_photon_map", "gather_radius": 0.1, "alpha": 1.5}})", "", "integrator.alpha", "(0, 1)"},
        BadInput{"PhotonUnknownKernel", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "kernel": "gauss"}})", "", "integrator.kernel", "unknown kernel 'gauss'"},
        BadInput{"PhotonUnknownDirectLighting", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "direct_lighting": "mis"}})", "", "integrator.direct_lighting", "unknown direct lighting"},
        BadInput{"PhotonSumEstimator", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "debias": {"estimator": "sum"}}})", "", "integrator.debias.estimator", "single_term"},
        BadInput{"PhotonAutoPmf", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "debias": {"estimator": "single_term", "pmf": {"type": "auto"}}}})", "", "integrator.debias.pmf.type", "auto"},
        BadInput{"PhotonMinBounces", R"({"integrator": {"type": "photon_map", "gather_radius": 0.1, "min_bounces": 2}})", "", "integrator.min_bounces", "min_bounces = 0"},
        BadInput{"PmfROutOfRange", R"({"integrator": {"debias": {"estimator": "sum", "pmf": {"type": "geometric", "r": 1.0}}}})", "", "integrator.debias.pmf.r", "(0, 1)"},
        BadInput{"PmfAlphaOutOfRange", R"({"integrator": {"debias": {"estimator": "sum", "pmf": {"type": "power_law", "alpha": 0}}}})", "", "integrator.debias.pmf.alpha", "(0, 1)"},
        BadInput{"PmfKeyOfOtherType", R"({"integrator": {"debias": {"estimator": "sum", "pmf": {"type": "geometric", "alpha": 0.5}}}})", "", "integrator.debias.pmf.alpha", "unknown key"},
        BadInput{"UnknownPmfType", R"({"integrator": {"debias": {"estimator": "sum", "pmf": {"type": "poisson"}}}})", "", "integrator.debias.pmf.type", "unknown pmf type"},
        BadInput{"UnknownDebiasEstimator", R"({"integrator": {"debias": {"estimator": "roulette"}}})", "", "integrator.debias.estimator", "unknown debias estimator 'roulette'"},
        BadInput{"MissingDebiasEstimator", R"({"integrator": {"debias": {}}})", "", "integrator.debias.estimator", "missing"},
        BadInput{"UnknownKeyInDebias", R"({"integrator": {"debias": {"estimator": "sum", "levels": 3}}})", "", "integrator.debias.levels", "unknown key 'levels'"},
        BadInput{"MissingMeshFile", withPrimitive(R"({"type": "mesh", "bsdf": "white", "file": "nowhere.obj"})"), "", "primitives[0].file", "cannot open mesh file"},
        BadInput{"MalformedObj", withPrimitive(R"({"type": "mesh", "bsdf": "white", "file": "garbage.obj"})"), "", "primitives[0].file", "malformed .obj"},
        BadInput{"ObjIndexOutOfRange", withPrimitive(R"({"type": "mesh", "bsdf": "white", "file": "oob.obj"})"), "", "primitives[0].file", "uses vertex 9 of 3"},
        BadInput{"TruncatedWo3", withPrimitive(R"({"type": "mesh", "bsdf": "white", "file": "short.wo3"})"), "", "primitives[0].file", "malformed .wo3"},
        BadInput{"UnsupportedMeshFormat", withPrimitive(R"({"type": "mesh", "bsdf": "white", "file": "bunny.ply"})"), "", "primitives[0].file", "unsupported mesh format"},
        BadInput{"PowerOnZeroArea", withPrimitive(R"({"type": "quad", "bsdf": "white", "power": 1, "transform": {"scale": 0}})"), "", "primitives[0].power", "zero area"},
        BadInput{"UnknownMediumType", R"({"media": [{"type": "fog"}]})", "", "media[0].type", "unknown medium type 'fog'"},
        BadInput{"MediumReference", withPrimitive(R"({"type": "sphere", "bsdf": "white", "int_medium": "fog"})"), "", "primitives[0].int_medium", "unknown medium 'fog'"},
        BadInput{"NegativeSigma", R"({"media": [{"type": "homogeneous", "sigma_a": -1}]})", "", "media[0].sigma_a", "non-negative"},
        BadInput{"VdbGridMissingFile", R"({"media": [{"type": "voxel", "grid": {"type": "vdb", "file": "cloud.vdb"}}]})", "", "media[0].grid.file", "cannot open VDB file"},
        BadInput{"VoxelWithoutGrid", R"({"media": [{"type": "voxel"}]})", "", "media[0]", "missing 'grid'"},
        BadInput{"UnknownTransmittance", R"({"media": [{"type": "homogeneous", "transmittance": {"type": "gamma"}}]})", "", "media[0].transmittance.type", "unknown transmittance type 'gamma'"},
        BadInput{"PmfOnATracker", R"({"integrator": {"transmittance_estimator": {"type": "ratio_tracking", "pmf": {"type": "geometric", "r": 0.5}}}})", "", "integrator.transmittance_estimator.pmf", "only the 'debiased_ray_march' estimator"},
        BadInput{"UnknownTransmittanceEstimator", R"({"integrator": {"transmittance_estimator": {"type": "woodcock"}}})", "", "integrator.transmittance_estimator.type", "unknown transmittance estimator 'woodcock'"},
        BadInput{"TaylorOnLinearMedium", R"({"media": [{"type": "homogeneous", "name": "slab", "transmittance": {"type": "linear"}}], "integrator": {"transmittance_estimator": {"type": "taylor"}}})", "", "integrator.transmittance_estimator.type", "taylor needs a transmittance that is a power series"},
        BadInput{"TaylorOnInterpolatedWithPulse", R"({"media": [{"type": "homogeneous", "transmittance": {"type": "interpolated", "tr_a": {"type": "davis"}, "tr_b": {"type": "pulse"}}}], "integrator": {"transmittance_estimator": {"type": "taylor"}}})", "", "integrator.transmittance_estimator.type", "taylor needs"},
        BadInput{"TermsOnAnotherEstimator", R"({"integrator": {"transmittance_estimator": {"type": "debiased_ray_march", "terms": 2}}})", "", "integrator.transmittance_estimator.terms", "only the 'taylor' estimator"},
        BadInput{"TaylorPointsOutOfRange", R"({"integrator": {"transmittance_estimator": {"type": "taylor", "points": 100000}}})", "", "integrator.transmittance_estimator.points", ""},
        BadInput{"TrackerOnDavisMedium", R"({"media": [{"type": "homogeneous", "name": "cloud", "transmittance": {"type": "davis"}}], "integrator": {"transmittance_estimator": {"type": "ratio_tracking"}}})", "", "integrator.transmittance_estimator.type", "exponential media only"},
        BadInput{"PrimitivesNotArray", R"({"primitives": {}})", "", "primitives", "expected an array"},
        BadInput{"OverrideIndexOutOfRange", withPrimitive(kQuad), "primitives[5].bsdf=\"white\"", "primitives[5].bsdf", "out of range", ""},
        BadInput{"OverrideThroughNonObject", R"({"camera": {"fov": 40}})", "camera.fov.degrees=3", "camera.fov.degrees", "not an object", ""},
        BadInput{"OverrideBadIndex", withPrimitive(kQuad), "primitives[x].bsdf=1", "primitives[x].bsdf", "malformed", ""},
        BadInput{"OverrideWrongValue", R"({})", "renderer.spp=lots", "renderer.spp", "expected an integer"}),
    [](const testing::TestParamInfo<BadInput>& info) { return std::string(info.param.name); });

// Every Tungsten example scene in scenes/tungsten/ loads, or fails with one message naming the
// file and the key (scenes/tungsten/README.md).
std::string tungstenScene(const std::string& name) {
    return std::string(TELESCOPE_SOURCE_DIR) + "/scenes/tungsten/" + name + "/scene.json";
}

InputError tungstenSceneError(const std::string& name, const std::vector<SceneOverride>& overrides = {}) {
    try {
        loadScene(tungstenScene(name), overrides);
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), tungstenScene(name)) << name;
        return e;
    }
    ADD_FAILURE() << name << " loads: expected an InputError";
    return InputError("", "", "");
}

TEST(TungstenExampleScenes, NonExponentialLoadsWithItsFourModels) {
    // Its adaptive_sampling true is refused, naming the key and the override that renders it.
    const InputError e = tungstenSceneError("non-exponential");
    EXPECT_EQ(e.key(), "renderer.adaptive_sampling");
    EXPECT_NE(std::string(e.what()).find("--set renderer.adaptive_sampling=false"), std::string::npos) << e.what();
    const Scene s = loadScene(tungstenScene("non-exponential"), {{"renderer.adaptive_sampling", "false"}});
    ASSERT_EQ(s.media.size(), 4u);
    EXPECT_EQ(s.media[0].transmittance.type, shader::kTrLinear);
    EXPECT_FLOAT_EQ(s.media[0].transmittance.params.x, 0.75f);
    EXPECT_EQ(s.media[1].transmittance.type, shader::kTrQuadratic);
    EXPECT_EQ(s.media[2].transmittance.type, shader::kTrDoubleExponential);
    EXPECT_FLOAT_EQ(s.media[2].transmittance.params.x, 1.0f);  // the scene's sigma_a, not the default 0.5
    EXPECT_EQ(s.media[3].transmittance.type, shader::kTrPulse);
    EXPECT_EQ(s.media[0].maxBounces, 1024u);
    EXPECT_EQ(s.camera.width, 512u);  // "resolution": 512.0, a square
    EXPECT_EQ(s.camera.height, 512u);
    EXPECT_EQ(s.integrator.maxBounces, 3u);
    EXPECT_EQ(pathDepthK(s.integrator), 2u);
    EXPECT_EQ(std::find(s.ignoredKeys.begin(), s.ignoredKeys.end(), "renderer.adaptive_sampling"), s.ignoredKeys.end());
}

TEST(TungstenExampleScenes, VolumetricCausticAsksForBdptAndLoadsPathTraced) {
    const InputError e = tungstenSceneError("volumetric-caustic");
    EXPECT_EQ(e.key(), "integrator.type");
    EXPECT_NE(std::string(e.what()).find("--set integrator.type=\"path_tracer\""), std::string::npos) << e.what();
    const Scene s = loadScene(tungstenScene("volumetric-caustic"), {parseOverride("integrator.type=\"path_tracer\"")});
    EXPECT_EQ(s.integrator.maxBounces, 6u);
    EXPECT_EQ(s.media.size(), 1u);
}

TEST(TungstenExampleScenes, WaterCausticLoadsWithItsSmoothWaterAndNearestGather) {
    // Tungsten's water.wo3 and front.wo3 ship next to the scene (zlib licence, byte for byte).
    const Scene s = loadScene(tungstenScene("water-caustic"));
    EXPECT_EQ(s.integrator.type, IntegratorType::ProgressivePhotonMap);
    EXPECT_EQ(s.integrator.photon.gatherCount, 20u);
    EXPECT_EQ(s.integrator.photon.kernel, PhotonKernel::Uniform);
    size_t smooth = 0;
    for (const Geometry& g : s.geometry) smooth += g.smooth;
    EXPECT_GT(smooth, 100000u);  // the water surface (front.wo3 is flat)
    for (const std::string& key : s.ignoredKeys) {
        EXPECT_EQ(key.find("primitives["), std::string::npos) << key;
        EXPECT_NE(key, "integrator.gather_photon_count");
    }
}

TEST(TungstenExampleScenes, VoxelMediumAndHairFailClearly) {
    const InputError voxel = tungstenSceneError("voxel-medium");
    EXPECT_EQ(voxel.key().rfind("media[0].grid", 0), 0u) << voxel.what();
    const InputError hair = tungstenSceneError("hair");
    EXPECT_EQ(hair.key(), "bsdfs[0].type");
    EXPECT_NE(std::string(hair.what()).find("hair"), std::string::npos) << hair.what();
}

TEST(SceneLoaderErrors, MissingSceneFile) {
    const std::string path = (scratchDir() / "no-such-scene.json").string();
    try {
        loadScene(path);
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), path);
        EXPECT_NE(std::string(e.what()).find("no-such-scene.json"), std::string::npos) << e.what();
    }
}

TEST(SceneLoaderErrors, OverrideWithoutEquals) {
    try {
        parseOverride("camera.resolution");
        FAIL() << "expected an InputError";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "");
        EXPECT_NE(std::string(e.what()).find("command line"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("camera.resolution"), std::string::npos) << e.what();
    }
    EXPECT_THROW(parseOverride("=3"), InputError);
}

}  // namespace
}  // namespace telescope
