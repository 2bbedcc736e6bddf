// Photons from lights at infinity (scenes/sky-photon-plate.json): a checkered ground, a rough gold
// ball and a green wall under Tungsten-style environment image (rotated 40 degrees about y), all
// light carried by photons (direct_lighting: photons), so the image is the emission's
// normalisation seen directly: photons leave the disk of the scene's bounding sphere facing a
// direction drawn by the environment's own sampling, each carrying L(w) pi R^2 / p(w). The path
// tracer (environment sampling with MIS) is the independent answer.
//
// Positive control, rejected by the same test at the same sample count: the path tracer's render
// of the sky without its rotation, which is what photons emitted in the image's own frame (the
// rotation forgotten on the photon side) would converge to. The same for an infinite_sphere_cap.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;

namespace {

const char* kScene = "scenes/sky-photon-plate.json";
constexpr uint32_t kBlock = 4;   // 16 regions of 4x4 pixels
constexpr double kAlpha = 1e-3;  // family-wise false-failure rate

Scene plate(std::vector<SceneOverride> more = {}) {
    more.push_back({"camera.resolution", "[16, 16]"});
    return loadTestScene(kScene, more);
}

std::vector<RegionMean> pathTraced(const char* rotation) {
    return blockMeans(renderFilm(plate({{"integrator", R"({"type": "path_tracer", "max_bounces": 8})"},
                                        {"primitives[3].transform.rotation", rotation}}),
                                 4096, 23),
                      kBlock);
}

class PhotonSky : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

}  // namespace

TEST_F(PhotonSky, UnbiasedBlocksUnderAnEnvironmentImageMatchThePathTracer) {
    const std::vector<std::vector<glm::dvec3>> batches = regionBatchMeans(plate(), kBlock, 24, 4, 13);
    const BatchVerdict right = compareBatchMeans(batches, pathTraced("[0, 40, 0]"), 3, kAlpha, "photons");
    EXPECT_EQ(right.failures, 0u);
    const BatchVerdict unrotated = compareBatchMeans(batches, pathTraced("[0, 0, 0]"), 3, kAlpha, "sky unrotated (control)");
    EXPECT_GE(unrotated.failures, 6u) << "the control must fail in several regions";
}

TEST_F(PhotonSky, UnbiasedBlocksUnderASunCapMatchThePathTracer) {
    // The same with the sky replaced by an infinite_sphere_cap (a 20-degree sun tilted by (30, 0,
    // 20) degrees): uniform directions in the cap. Control: the cap's axis without its tilt.
    const auto sun = [](const char* rotation) {
        return std::string(R"({"name": "sun", "type": "infinite_sphere_cap", "cap_angle": 20, "power": 3.0,
            "transform": {"rotation": )") + rotation + "}}";
    };
    const std::vector<std::vector<glm::dvec3>> batches =
        regionBatchMeans(plate({{"primitives[3]", sun("[30, 0, 20]")}}), kBlock, 24, 4, 13);
    const auto reference = [&](const char* rotation) {
        return blockMeans(renderFilm(plate({{"integrator", R"({"type": "path_tracer", "max_bounces": 8})"},
                                            {"primitives[3]", sun(rotation)}}),
                                     4096, 23),
                          kBlock);
    };
    const BatchVerdict right = compareBatchMeans(batches, reference("[30, 0, 20]"), 3, kAlpha, "photons");
    EXPECT_EQ(right.failures, 0u);
    const BatchVerdict untilted = compareBatchMeans(batches, reference("[0, 0, 0]"), 3, kAlpha, "sun untilted (control)");
    EXPECT_GE(untilted.failures, 6u) << "the control must fail in several regions";
}
