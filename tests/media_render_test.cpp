// Participating media on the device (ESTIMATORS.md sections 4 and 6).
//
// Absorbing slab before an emitter (scenes/absorbing-slab.json): the top half of the frame looks
// through a slab of constant density, the bottom half through Tungsten's exponential medium
// falling off across the slab; with the dirac filter every pixel has one direction and the
// closed form L = Le g(tau / cos). Every unbiased estimator matches it per 8x8 region within its
// own statistical bound, for the exponential and the Davis model; biased marching at a small
// level fails the same test. A constant grid renders like the homogeneous medium, and the Davis
// cloud rendered with debiased marching agrees with a very-high-level marching reference where
// low-level marching does not.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "region_stats.h"
#include "render_harness.h"
#include "shared/transmittance.h"

using namespace telescope;
using namespace telescope::test;

namespace {

const char* kSlab = "scenes/absorbing-slab.json";
constexpr uint32_t kBlock = 8;
constexpr double kAlpha = 1e-3;

// Optical depths along the slab normal (thickness 1): constant density 1.2; falloff
// 3 exp(-3 (z + 1/2)) integrated over z in [-1/2, 1/2].
const double kTauConstant = 1.2;
const double kTauFalloff = 3.0 * (1.0 - std::exp(-3.0)) / 3.0;

struct SlabModel {
    std::string json;       // the "transmittance" object of both media
    shader::TrModel model;  // the same, for the closed form
};

SlabModel exponentialModel() { return {R"({"type":"exponential"})", shader::trSimple(shader::kTrExponential, glm::vec4(0))}; }
SlabModel davisModel() {
    return {R"({"type":"davis","alpha":1.5625})", shader::trSimple(shader::kTrDavis, glm::vec4(1.5625f, 0, 0, 0))};  // c = 0.8
}

Scene slabScene(const SlabModel& model, const std::string& estimator) {
    return loadTestScene(kSlab, {{"media[0].transmittance", model.json},
                                 {"media[1].transmittance", model.json},
                                 {"integrator.transmittance_estimator", estimator}});
}

// Closed form per pixel: the camera of absorbing-slab.json looks along +z, dirac filter.
std::vector<RegionMean> slabClosedForm(const Scene& scene, const shader::TrModel& model) {
    const Camera& cam = scene.camera;
    const double w = cam.width, h = cam.height;
    const double plane = 1.0 / std::tan(0.5 * cam.fovDegrees * 3.14159265358979323846 / 180.0);
    Film film(cam.width, cam.height);
    film.setSamplesPerPixel(1);
    for (uint32_t y = 0; y < cam.height; ++y)
        for (uint32_t x = 0; x < cam.width; ++x) {
            double lx = -1.0 + 2.0 * (x + 0.5) / w, ly = h / w - 2.0 * (y + 0.5) / w;
            double cosZ = plane / std::sqrt(lx * lx + ly * ly + plane * plane);
            double tau = (ly > 0 ? kTauConstant : kTauFalloff) / cosZ;
            double value = shader::trForm(model, shader::kFormSurfaceSurface, float(tau));
            film.sums(shader::kChannelEstimate)[size_t(y) * cam.width + x] = glm::dvec4(value, value, value, 0.0);
            film.sums(shader::kChannelEstimateSq)[size_t(y) * cam.width + x] = glm::dvec4(value * value);
        }
    return blockMeans(film, kBlock);
}

// Z-tests of the render's regions against the closed form. The closed form gets a standard
// deviation of 2e-5 of its value: ray offsets at the slab faces (1e-5 of the scene size) shorten
// every segment, which zero-variance estimators on constant density resolve.
ZSummary compareToClosedForm(const std::vector<RegionMean>& render, const std::vector<RegionMean>& exact) {
    std::vector<RegionMean> rounded = exact;
    for (RegionMean& r : rounded) r.variance = glm::dvec3(2e-5 * r.mean) * glm::dvec3(2e-5 * r.mean);
    return compareRegions(render, rounded, sidakThreshold(kAlpha, render.size() * 3));
}

class MediaRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }

    void expectMatchesClosedForm(const SlabModel& model, const std::string& estimator, uint64_t spp, uint32_t seed) {
        Scene scene = slabScene(model, estimator);
        Film film = renderFilm(scene, spp, seed);
        ZSummary z = compareToClosedForm(blockMeans(film, kBlock), slabClosedForm(scene, model.model));
        EXPECT_EQ(z.failing, 0u) << estimator << ": " << z.worst << " (" << z.tests << " tests)";
        EXPECT_EQ(film.nonFiniteSamples(), 0u);
    }
};

}  // namespace

// One test per group of renders: every test is its own process under CTest (Vulkan start-up and
// pipeline compilation dominate on lavapipe).
TEST_F(MediaRender, EveryUnbiasedEstimatorMatchesTheSlab) {
    struct Case {
        SlabModel model;
        std::string estimator;
        uint64_t spp;
    };
    const Case cases[] = {
        {exponentialModel(), R"({"type":"debiased_ray_march","level":1})", 64},
        {davisModel(), R"({"type":"debiased_ray_march","level":1})", 64},
        {exponentialModel(), R"({"type":"delta_tracking"})", 256},
        {exponentialModel(), R"({"type":"ratio_tracking"})", 256},
        {exponentialModel(), R"({"type":"residual_ratio_tracking"})", 128},
        {exponentialModel(), R"({"type":"unbiased_ray_march"})", 64},
    };
    uint32_t seed = 11;
    for (const Case& c : cases) {
        SCOPED_TRACE(c.model.json + " " + c.estimator);
        expectMatchesClosedForm(c.model, c.estimator, c.spp, seed++);
    }
}

TEST_F(MediaRender, BiasedMarchingAtLevel0FailsTheSlab) {
    for (const SlabModel& model : {exponentialModel(), davisModel()}) {
        Scene scene = slabScene(model, R"({"type":"ray_march","level":0})");
        Film film = renderFilm(scene, 64, 17);
        ZSummary z = compareToClosedForm(blockMeans(film, kBlock), slabClosedForm(scene, model.model));
        // The falloff half (bottom 2 block rows x 4 x 3 channels = 24 tests) is biased.
        EXPECT_GE(z.failing, 24u) << model.json << ": " << z.worst;
    }
}

// ---- The Davis cloud (procedural grid, Davis transmittance, multiple scattering) ----
namespace {
Scene cloudScene(const std::string& estimator) {
    return loadTestScene("scenes/davis-cloud.json",
                         {{"camera.resolution", "[24,16]"}, {"integrator.transmittance_estimator", estimator}});
}

}  // namespace

TEST_F(MediaRender, DavisCloudDebiasedAgreesWithHighLevelMarchingAndLowLevelDoesNot) {
    // Reference: biased marching at a very high level, 2^6 points per segment.
    const auto reference = blockMeans(renderFilm(cloudScene(R"({"type":"ray_march","level":6})"), 1024, 31), 4);
    Film film = renderFilm(cloudScene(R"({"type":"debiased_ray_march","level":1})"), 1024, 32);
    auto regions = blockMeans(film, 4);
    const double threshold = sidakThreshold(kAlpha, regions.size() * 3);
    ZSummary z = compareRegions(regions, reference, threshold);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (" << z.tests << " tests)";
    EXPECT_EQ(film.nonFiniteSamples(), 0u);

    auto biased = blockMeans(renderFilm(cloudScene(R"({"type":"ray_march","level":0})"), 1024, 33), 4);
    ZSummary zb = compareRegions(biased, reference, threshold);
    std::printf("low-level marching: %zu of %zu region tests fail (worst %s)\n", zb.failing, zb.tests, zb.worst.c_str());
    EXPECT_GE(zb.failing, zb.tests / 4) << zb.worst;
}

TEST_F(MediaRender, ConstantAndLinearGridsMatchTheSlabClosedForm) {
    {
        // The top slab's medium as a voxel grid of the same density over the same box.
        Scene scene = loadTestScene(
            kSlab, {{"media[0]", R"({"name":"constant","type":"voxel","sigma_a":1.0,"sigma_s":0.0,"density":1.2,
                                     "grid":{"type":"constant","resolution":[4,4,3],"value":1.0,
                                             "transform":{"position":[0,1,0],"scale":[4,2,1]}}})"},
                    {"integrator.transmittance_estimator", R"({"type":"ratio_tracking"})"}});
        Film film = renderFilm(scene, 256, 18);
        ZSummary z = compareToClosedForm(blockMeans(film, kBlock), slabClosedForm(scene, exponentialModel().model));
        EXPECT_EQ(z.failing, 0u) << z.worst;
    }
    // Linearly varying density across the top slab: 0.4 at its front face to 2.0 at its back (grid
    // layer centres at z = -0.5, 0, 0.5), optical depth 1.2 along the normal as the constant slab.
    Scene scene = loadTestScene(
        kSlab, {{"media[0]", R"({"name":"constant","type":"voxel","sigma_a":1.0,"sigma_s":0.0,
                                 "grid":{"type":"linear","resolution":[1,1,3],"from":0.4,"to":2.0,
                                         "transform":{"position":[0,1,0],"scale":[4,2,1.5]}}})"},
                {"integrator.transmittance_estimator", R"({"type":"debiased_ray_march","level":1})"}});
    Film film = renderFilm(scene, 64, 19);
    ZSummary z = compareToClosedForm(blockMeans(film, kBlock), slabClosedForm(scene, exponentialModel().model));
    EXPECT_EQ(z.failing, 0u) << z.worst;
    Scene biased = scene;
    biased.integrator.transmittance.type = TransmittanceEstimatorType::RayMarch;
    biased.integrator.transmittance.level = 0;
    Film b = renderFilm(biased, 64, 20);
    ZSummary zb = compareToClosedForm(blockMeans(b, kBlock), slabClosedForm(scene, exponentialModel().model));
    EXPECT_GE(zb.failing, 40u) << "1-point marching is biased on both halves: " << zb.worst;
}
