// Level scheduling (debias "level_schedule"): the queued schedule reorders work by level but is
// the per-pixel estimator sample for sample; the uniform schedule shares one level per sample
// index across pixels and must stay unbiased per pixel.
#include <gtest/gtest.h>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;

namespace {

Scene cornell(const std::string& schedule, const std::string& resolution = "[24,20]") {
    return loadTestScene("scenes/cornell-box.json",
                         {{"camera.resolution", resolution},
                          {"integrator.max_bounces", "1"},
                          {"integrator.debias", R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.4},)"
                                                R"("level_schedule":")" + schedule + R"("})"}});
}

class LevelScheduling : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

}  // namespace

TEST_F(LevelScheduling, QueuedEqualsPerPixelSampleForSample) {
    // 40 spp: three dispatches of 16, 16 and 8 samples, so a partial last dispatch is covered.
    const Film a = renderFilm(cornell("per_pixel"), 40, 77);
    const Film b = renderFilm(cornell("queued"), 40, 77);
    ASSERT_EQ(a.pixelCount(), b.pixelCount());
    size_t differing = 0;
    double worst = 0.0;
    for (uint32_t c = 0; c < shader::kChannelCount; ++c) {
        for (size_t i = 0; i < a.pixelCount(); ++i) {
            const glm::dvec4 d = glm::abs(a.sums(c)[i] - b.sums(c)[i]);
            const glm::dvec4 m = glm::max(glm::abs(a.sums(c)[i]), glm::dvec4(1.0));
            const glm::dvec4 r = d / m;
            const double rel = std::max(std::max(r.x, r.y), std::max(r.z, r.w));
            worst = std::max(worst, rel);
            if (rel > 1e-5) ++differing;  // the two shaders may contract a * b + c differently
        }
    }
    EXPECT_EQ(differing, 0u) << "worst relative difference " << worst;
}

TEST_F(LevelScheduling, QueuedIsRepeatable) {
    const Film a = renderFilm(cornell("queued", "[9,7]"), 24, 5);
    const Film b = renderFilm(cornell("queued", "[9,7]"), 24, 5);
    for (uint32_t c = 0; c < shader::kChannelCount; ++c) EXPECT_EQ(a.sums(c), b.sums(c)) << "channel " << c;
}

TEST_F(LevelScheduling, UniformLevelsStayUnbiasedInTheFurnace) {
    // Furnace (ESTIMATORS.md section 6): Le = 1, albedo 0.5, limit 2. The levels of different
    // pixels are correlated, so the test uses independent seeds per block row instead of blocks
    // of one image: each 8x8 image is one independent sample of the block mean.
    std::vector<RegionMean> regions;
    for (uint32_t seed = 0; seed < 24; ++seed) {
        Scene scene = loadTestScene("scenes/furnace.json",
                                    {{"camera.resolution", "[8,8]"}, {"integrator.max_bounces", "1"},
                                     {"integrator.debias", R"({"estimator":"single_term","level_schedule":"uniform"})"}});
        const Film film = renderFilm(scene, 16, 1000 + seed);
        auto m = blockMeans(film, 8);
        regions.push_back(m[0]);
    }
    // Batch means: the spread of the 24 image means gives the variance of each.
    glm::dvec3 mean(0.0), var(0.0);
    for (const auto& r : regions) mean += r.mean / double(regions.size());
    for (const auto& r : regions) var += (r.mean - mean) * (r.mean - mean) / double(regions.size() - 1);
    const double t = sidakThreshold(1e-3, 3);
    for (int c = 0; c < 3; ++c) {
        const double z = (mean[c] - 2.0) / std::sqrt(var[c] / double(regions.size()));
        EXPECT_LT(std::abs(z), t) << "channel " << c << ": mean " << mean[c];
    }
}
