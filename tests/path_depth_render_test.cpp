// Debiased path depth on the device: the debiased estimator at k = 1 agrees with a deep
// (64-bounce) render of Tungsten's Cornell box within its statistical bound, and the biased
// I(1) fails the same test.
#include <gtest/gtest.h>

#include <cmath>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;

namespace {

const char* kCornell = "scenes/tungsten/cornell-box/scene.json";

class PathDepthRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }

    static Scene cornell(uint32_t k, const std::string& debias = "") {
        std::vector<SceneOverride> o = {{"camera.resolution", "[64,48]"},
                                        {"integrator.max_bounces", std::to_string(k)}};
        if (!debias.empty()) o.push_back({"integrator.debias", debias});
        return loadTestScene(kCornell, o);
    }

    // The 64-bounce reference, rendered once for every test of this suite.
    static const std::vector<RegionMean>& deep() {
        static std::vector<RegionMean> regions = blockMeans(renderFilm(cornell(64), 512, 1001), 8);
        return regions;
    }
};

constexpr uint32_t kBlock = 8;
constexpr double kAlpha = 1e-3;  // family-wise false-failure rate of each comparison

}  // namespace

TEST_F(PathDepthRender, SingleTermAtK1MatchesDeepRender) {
    Film film = renderFilm(cornell(1, R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.5}})"), 512, 2002);
    auto regions = blockMeans(film, kBlock);
    double threshold = sidakThreshold(kAlpha, regions.size() * 3);
    ZSummary z = compareRegions(regions, deep(), threshold);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (threshold " << threshold << ", " << z.tests << " tests)";
    EXPECT_EQ(film.nonFiniteSamples(), 0u);
}

TEST_F(PathDepthRender, SumEstimatorAtK1MatchesDeepRender) {
    Film film = renderFilm(cornell(1, R"({"estimator":"sum","pmf":{"type":"geometric","r":0.65}})"), 512, 3003);
    auto regions = blockMeans(film, kBlock);
    double threshold = sidakThreshold(kAlpha, regions.size() * 3);
    ZSummary z = compareRegions(regions, deep(), threshold);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (threshold " << threshold << ", " << z.tests << " tests)";
}

TEST_F(PathDepthRender, BiasedK1FailsTheSameTest) {
    Film film = renderFilm(cornell(1), 512, 4004);
    auto regions = blockMeans(film, kBlock);
    double threshold = sidakThreshold(kAlpha, regions.size() * 3);
    ZSummary z = compareRegions(regions, deep(), threshold);
    EXPECT_GT(z.failing, regions.size()) << "biased I(1) should be far from the deep render";
}

TEST_F(PathDepthRender, BaseAndCorrectionAddUpToTheEstimate) {
    Film film = renderFilm(cornell(1, R"({"estimator":"single_term"})"), 16, 5005);
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        glm::dvec3 sum = film.mean(shader::kChannelBase, i) + film.mean(shader::kChannelCorrection, i);
        glm::dvec3 est = film.mean(shader::kChannelEstimate, i);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(sum[c], est[c], 1e-5 * (1.0 + std::abs(est[c]))) << "pixel " << i;
    }
}

TEST_F(PathDepthRender, FixedSeedIsRepeatable) {
    Scene scene = cornell(3, R"({"estimator":"single_term"})");
    Film a = renderFilm(scene, 8, 77), b = renderFilm(scene, 8, 77), c = renderFilm(scene, 8, 78);
    size_t differ = 0, lit = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i) {
        ASSERT_EQ(a.sums(0)[i], b.sums(0)[i]) << "pixel " << i;
        if (a.sums(0)[i] == glm::dvec4(0.0)) continue;  // pixels that see nothing
        ++lit;
        differ += a.sums(0)[i] != c.sums(0)[i];
    }
    EXPECT_GT(lit, a.pixelCount() / 4) << "the box covers about 40% of this 4:3 frame";
    EXPECT_GT(differ, lit * 9 / 10) << "another seed should give another image";
}

TEST_F(PathDepthRender, ExtendingARenderEqualsOneLongRender) {
    // Samples depend only on pixel, global sample index and seed: 8 + 8 spp == 16 spp.
    Scene scene = cornell(2);
    Renderer split(sharedContext(), scene, 9);
    RenderRequest r;
    r.spp = 8;
    split.render(r);
    split.render(r);
    Film a = split.film();
    Film b = renderFilm(scene, 16, 9);
    for (size_t i = 0; i < a.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(a.sums(0)[i][c], b.sums(0)[i][c], 1e-4 * (1.0 + std::abs(b.sums(0)[i][c])));
}
