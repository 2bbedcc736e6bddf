// Level scheduling (debias "level_schedule"): the queued schedule reorders work by level but is
// the per-pixel estimator sample for sample; the uniform schedule shares one level per sample
// index across pixels and must stay unbiased per pixel.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;

namespace {

Scene cornell(const std::string& schedule, const std::string& resolution = "[24,20]") {
    return loadTestScene("scenes/cornell-box.json",
                         {{"camera.resolution", resolution},
                          {"integrator.max_bounces", "2"},
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

namespace {
// Means over the 8x8 furnace image of independent batches of `spp` sample indices. Under the
// uniform schedule all pixels of a sample index share its level, so pixels are correlated and only
// sample indices are independent: each batch mean is one independent sample.
std::vector<glm::dvec3> uniformBatchMeans(const std::string& debias, uint32_t batches, uint64_t spp, uint32_t seed) {
    Scene scene = loadTestScene("scenes/furnace.json", {{"camera.resolution", "[8,8]"},
                                                        {"integrator.max_bounces", "2"},
                                                        {"integrator.debias", debias}});
    Renderer renderer(sharedContext(), resolved(scene), seed);
    std::vector<glm::dvec3> means;
    glm::dvec3 previous(0.0);
    RenderRequest request;
    request.spp = spp;
    for (uint32_t b = 0; b < batches; ++b) {
        renderer.render(request);
        const Film film = renderer.film();
        glm::dvec3 total(0.0);
        for (const glm::dvec4& s : film.sums(shader::kChannelEstimate)) total += glm::dvec3(s);
        means.push_back((total - previous) / double(spp * film.pixelCount()));
        previous = total;
    }
    return means;
}

// Student t-test of the batch means against `value`, per channel, Sidak over the 3 channels at
// 1e-3: returns the largest |t| and sets *threshold.
double batchT(const std::vector<glm::dvec3>& means, double value, double* threshold) {
    const double n = double(means.size());
    glm::dvec3 mean(0.0), var(0.0);
    for (const auto& m : means) mean += m / n;
    for (const auto& m : means) var += (m - mean) * (m - mean) / (n - 1.0);
    *threshold = sidakThresholdT(1e-3, 3, n - 1.0);
    double worst = 0.0;
    for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(mean[c] - value) / std::sqrt(var[c] / n));
    return worst;
}
}  // namespace

TEST_F(LevelScheduling, UniformLevelsStayUnbiasedInTheFurnace) {
    // Furnace (docs/ESTIMATORS.md section 6): Le = 1, albedo 0.5, limit 2. 64 batches of 64 sample
    // indices, t-test with 63 degrees of freedom (the batch means are means of 64 bounded,
    // independent estimates: finite variance). Positive control: the same estimator with every
    // 1 / p(j) scaled by 1.1 (bias 0.05) fails the same test.
    double t;
    const double z = batchT(uniformBatchMeans(R"({"estimator":"single_term","level_schedule":"uniform"})", 64, 64, 1000), 2.0, &t);
    EXPECT_LT(z, t) << "uniform schedule: |t| = " << z;
    const double zc = batchT(
        uniformBatchMeans(R"({"estimator":"single_term","level_schedule":"uniform","test_pmf_weight":1.1})", 64, 64, 2000), 2.0, &t);
    std::printf("uniform schedule: |t| = %.2f; mis-weighted control: |t| = %.2f (threshold %.2f)\n", z, zc, t);
    EXPECT_GT(zc, t) << "the mis-weighted control passes";
}

TEST(RegionStats, StudentQuantilesMatchTables) {
    // Two-sided 5% and 0.1% quantiles of Student's t (tables), and the normal limit.
    EXPECT_NEAR(sidakThresholdT(0.05, 1, 23.0), 2.0687, 1e-3);
    EXPECT_NEAR(sidakThresholdT(0.001, 1, 10.0), 4.5869, 2e-3);
    EXPECT_NEAR(sidakThresholdT(0.001, 1, 60.0), 3.4602, 2e-3);
    EXPECT_NEAR(sidakThresholdT(0.01, 1, 5.0), 4.0321, 2e-3);
    EXPECT_NEAR(sidakThresholdT(0.001, 1, 1e6), sidakThreshold(0.001, 1), 2e-3);
}
