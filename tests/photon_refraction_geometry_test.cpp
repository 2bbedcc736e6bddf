// Photon mapping through closed dielectrics, against independent answers: a family of small
// refraction geometries rendered by unbiased photon blocks and by the path tracer (the unbiased
// estimator), and one closed form.
//
// scenes/pool-gaps.json is Tungsten's Cornell box emptied, with a water cube (ior 1.33) standing on
// the floor and 2 cm of air between it and each wall. Its bottom face lies in the floor's plane:
// which of the two a ray meets used to depend on the order a walk met them, and the BVH walk
// (the gather) and the brute-force loop (the path tracer, the photon tracer) disagreed: a camera
// chain in the water that met the water's bottom left the water below the floor and was lost, and
// the photon-mapped pool floor was 25-40% dark against the path tracer (issue: "a water volume with
// air around it"). The rule now (shared/intersect.h "Coincident surfaces") is the same in every
// walk: the interface yields to the surface it touches. The positive control of the geometries
// with such contacts is the old rule in the photon passes (integrator.test_coincident_surfaces:
// false); of the others, the camera chain without its 1/eta^2 (test_radiance_scaling: false).
//
// Statistics: the path tracer's region means have finite variance (bounded emission, Russian
// roulette with throughput <= 1), so its variance of the mean is the sample variance's; unbiased
// photon blocks are heavy-tailed (tail index 1.45: finite mean, infinite variance), so they are
// compared by batch means (region_stats.h compareBatchMeans: a t-test on 16 batches per region,
// Sidak over the regions at family-wise rate 1e-3), conservative for heavy tails.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "region_stats.h"
#include "render/renderer.h"
#include "render_harness.h"
#include "scene/scene_loader.h"

using namespace telescope;
using namespace telescope::test;

namespace {

constexpr uint32_t kRes = 16;
constexpr uint32_t kBlock = 4;   // 16 regions of 4x4 pixels
constexpr double kAlpha = 1e-3;  // family-wise false-failure rate

// A geometry: scenes/pool-gaps.json with these overrides and, if given, one more primitive; and the
// control that must fail.
struct Geometry {
    const char* name;
    std::vector<SceneOverride> overrides;
    const char* control;    // the integrator keys of the positive control
    const char* added = "";  // a primitive appended to the scene's (JSON)
};

const char* kTieControl = R"(, "test_coincident_surfaces": false)";
const char* kScalingControl = R"(, "test_radiance_scaling": false)";

Scene pool(const Geometry& g, const std::string& integrator) {
    std::vector<SceneOverride> o = g.overrides;
    o.push_back({"camera.resolution", fmt::format("[{},{}]", kRes, kRes)});
    o.push_back({"integrator", integrator});
    if (*g.added == '\0') return loadTestScene("scenes/pool-gaps.json", o);
    // (--set cannot append to an array)
    nlohmann::json scene = nlohmann::json::parse(std::ifstream(sourcePath("scenes/pool-gaps.json")));
    scene["primitives"].push_back(nlohmann::json::parse(g.added));
    return loadSceneFromString(scene.dump(), fmt::format("pool-gaps.json + {}", g.name), sourcePath("scenes"), o);
}

// Unbiased photon blocks, wide base radius (the blocks remove its bias), 20000 paths a pass.
std::string blocks(const char* extra = "") {
    return fmt::format(R"({{"type": "photon_map", "photon_count": 20000, "gather_radius": 0.15, "max_bounces": 64,
        "debias": {{"estimator": "single_term", "level_schedule": "uniform"}}{}}})",
                       extra);
}

// The control renders g.control's integrator keys, or, given controlOverrides, the scene changed so.
void checkGeometry(const Geometry& g, uint32_t referenceSpp, uint32_t blocksPerBatch, uint32_t minControlFailures,
                   const std::vector<SceneOverride>& controlOverrides = {}) {
    SCOPED_TRACE(g.name);
    const std::vector<RegionMean> reference =
        blockMeans(renderFilm(pool(g, R"({"type": "path_tracer", "max_bounces": 64})"), referenceSpp, 21), kBlock);
    const BatchVerdict right = compareBatchMeans(regionBatchMeans(pool(g, blocks()), kBlock, 16, blocksPerBatch, 5),
                                                 reference, 1, kAlpha, g.name);
    EXPECT_EQ(right.failures, 0u);
    const std::string control = fmt::format("{} (control)", g.name);
    Geometry wrongGeometry = g;
    wrongGeometry.overrides.insert(wrongGeometry.overrides.end(), controlOverrides.begin(), controlOverrides.end());
    const BatchVerdict wrong = compareBatchMeans(regionBatchMeans(pool(wrongGeometry, blocks(g.control)), kBlock, 16,
                                                                  blocksPerBatch, 5),
                                                 reference, 1, kAlpha, control.c_str());
    EXPECT_GE(wrong.failures, minControlFailures) << "the control must fail";
}

class PhotonRefractionGeometry : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

}  // namespace

// The repro as reported: the pool floor seen from above through the flat surface.
TEST_F(PhotonRefractionGeometry, WaterCubeWithAirAroundItSeenFromAbove) {
    checkGeometry({"from above", {}, kTieControl}, 2048, 2, 8);
}

// The same pool with a rough surface (GGX, roughness 0.3) on every face: the camera chain ends at
// the water's top and gathers photons from both sides there (docs/PHOTON-MAPPING.md "Rough
// dielectrics"), those that came up from the floor refracted out of the water.
TEST_F(PhotonRefractionGeometry, RoughWaterCubeWithAirAroundIt) {
    checkGeometry({"rough water", {{"bsdfs[8].type", "\"rough_dielectric\""}, {"bsdfs[8].roughness", "0.3"}}, kTieControl},
                  2048, 2, 1);
}

// The camera low in front of the pool, looking across it: the front face nearly head-on, the
// side faces at grazing angles, the floor and back wall seen through two vertical faces.
TEST_F(PhotonRefractionGeometry, WaterCubeSeenThroughItsVerticalFaces) {
    checkGeometry({"through the faces",
                   {{"camera.transform.position", "[0.6, 0.45, 2.6]"}, {"camera.transform.look_at", "[-0.2, 0.25, 0]"}},
                   kTieControl},
                  2048, 2, 4);
}

// A diffuse box standing in the pool, half out of the water (its bottom on the floor, the water's
// surface crossing its sides), lit from above.
TEST_F(PhotonRefractionGeometry, DiffuseBoxPartlySubmerged) {
    checkGeometry({"submerged box", {}, kTieControl,
                   R"({"name": "box", "type": "cube", "bsdf": "shortBox",
                       "transform": {"position": [0.25, 0.45, -0.2], "scale": [0.5, 0.9, 0.5], "rotation": [0, 30, 0]}})"},
                  2048, 2, 4);
}

// The ceiling light off, a small panel on the pool floor shining up: its photons leave the water
// (or stay in it by total internal reflection) and come back in from the ceiling and walls; the
// camera, above the water, sees the panel, the pool floor it lights through the surface, and the
// lit walls.
TEST_F(PhotonRefractionGeometry, LightUnderWaterShiningOut) {
    checkGeometry({"light under water",
                   {{"primitives[5].emission", "[0, 0, 0]"},
                    {"camera.transform.position", "[0, 1.6, 1.9]"}, {"camera.transform.look_at", "[0, 0.5, 0]"}},
                   kScalingControl,
                   R"({"name": "lamp", "type": "quad", "bsdf": "light", "emission": [40, 40, 40],
                       "transform": {"position": [0.3, 0.05, -0.3], "scale": [0.2, 1, 0.2]}})"},
                  2048, 2, 4);
}

// The camera in the water looking up and out: the room through the Snell window, the pool's
// floor and sides by total internal reflection beyond it. The camera chain starts in water, so its
// radiance gains eta^2 leaving it; the control drops that.
TEST_F(PhotonRefractionGeometry, CameraUnderWaterLookingOut) {
    checkGeometry({"camera under water",
                   {{"camera.transform.position", "[0, 0.3, 0.6]"}, {"camera.transform.look_at", "[0, 1.2, -0.4]"},
                    {"camera.fov", "70"}},
                   kScalingControl},
                  2048, 2, 4);
}

// A glass ball (ior 1.5) in place of the pool, under the ceiling light and off centre: the camera
// sees the floor through the ball and the ball's caustic on the floor. Every camera chain and
// photon that enters the ball leaves it again, so neither radiance scaling changes the image (the
// factors cancel): the control is a wrong index on the photon-mapped side (1.33), which moves the
// caustic and bends the floor seen through the ball.
TEST_F(PhotonRefractionGeometry, GlassBallCausticAndTheFloorSeenThroughIt) {
    checkGeometry({"glass ball",
                   {{"bsdfs[8].ior", "1.5"},
                    {"primitives[6]", R"({"name": "ball", "type": "sphere", "bsdf": "water",
                        "transform": {"position": [0.2, 0.35, -0.1], "scale": 0.35}})"},
                    {"camera.transform.position", "[0, 1.2, 1.6]"}, {"camera.transform.look_at", "[0.1, 0.2, -0.1]"}},
                   "", ""},
                  2048, 2, 1, {{"bsdfs[8].ior", "1.33"}});
}

// ---- A closed form: a point light over a water layer, the camera above ----
//
// scenes/point-water-photon.json: a Lambertian floor (albedo rho = 0.5) under a water layer of depth
// d = 0.5 (ior n = 1.33, a wide cube whose bottom face lies on the floor), a point light of
// intensity I = 1 at height h = 1 above the surface, the camera straight above looking down with a
// 4 degree field of view. max_bounces 4 keeps the paths of three scattering vertices: light ->
// surface -> floor -> surface -> camera (a path with one more vertex has an internal reflection;
// next-event rays from the floor are blocked by the surface, so all of it comes from photons).
//
// Irradiance on the floor's axis: light leaving at a small angle a from the vertical meets the
// surface at radius h a, refracts to a / n and reaches the floor at r = a (h + d / n). The flux
// I (1 - F0) dw with dw = a da dphi lands on dA = r dr dphi, so
//   E(0) = I (1 - F0) / (h + d / n)^2,      F0 = ((n - 1) / (n + 1))^2.
// The floor's radiance in the water is rho E / pi; the camera ray enters at normal incidence
// (transmitted with probability 1 - F0) and the radiance it carries out of the water is scaled by
// 1 / n^2 (docs/PHOTON-MAPPING.md "Refraction"), so at the centre
//   L = (1 - F0)^2 rho I / (pi n^2 (h + d / n)^2)  = 0.045640.
// The centre's 4x4 pixels see a floor disk of radius 0.025 around the axis, over which E falls by
// (r / (h + d/n))^2 ~ 3e-4 at most: the closed form holds there to 0.05%.
TEST_F(PhotonRefractionGeometry, PointLightOverAWaterLayerMatchesTheClosedForm) {
    const double n = 1.33, rho = 0.5, intensity = 1.0, d = 0.5, h = 1.0;
    const double f0 = (n - 1.0) * (n - 1.0) / ((n + 1.0) * (n + 1.0));
    const double want = (1.0 - f0) * (1.0 - f0) * rho * intensity / (M_PI * n * n * (h + d / n) * (h + d / n));
    auto centreBatches = [&](const char* extra) {
        const Scene scene = loadTestScene("scenes/point-water-photon.json",
                                          {{"integrator", fmt::format(R"({{"type": "photon_map", "photon_count": 20000,
                                              "gather_radius": 0.1, "max_bounces": 4,
                                              "debias": {{"estimator": "single_term", "level_schedule": "uniform"}}{}}})",
                                                                      extra)}});
        // The centre's 4x4 pixels: the four 2x2 blocks around the image's centre (of 8x8 blocks).
        std::vector<std::vector<glm::dvec3>> b = regionBatchMeans(scene, 2, 16, 4, 9);
        std::vector<std::vector<glm::dvec3>> out(1);
        for (size_t k = 0; k < b[0].size(); ++k) {
            glm::dvec3 s(0.0);
            for (uint32_t by : {3u, 4u})
                for (uint32_t bx : {3u, 4u}) s += b[by * 8 + bx][k];
            out[0].push_back(s / 4.0);
        }
        return out;
    };
    const std::vector<RegionMean> reference(1, RegionMean{glm::dvec3(want), glm::dvec3(0.0)});
    const BatchVerdict right = compareBatchMeans(centreBatches(""), reference, 1, kAlpha, "closed form");
    EXPECT_EQ(right.failures, 0u);
    const BatchVerdict wrong = compareBatchMeans(centreBatches(kScalingControl), reference, 1, kAlpha, "closed form, unscaled (control)");
    EXPECT_EQ(wrong.failures, 1u) << "the control (1.77 times too bright) must fail";
}
