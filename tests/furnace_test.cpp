// Analytic furnace (ESTIMATORS.md section 6): inside a closed box whose walls emit Le and reflect
// with albedo a, L(d) = Le (1 - a^(d+1)) / (1 - a) with at most d bounces and Le / (1 - a) in
// the limit. scenes/furnace.json: Le = 1, a = 0.5.
#include <gtest/gtest.h>

#include <cmath>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;

namespace {

constexpr double kLe = 1.0, kAlbedo = 0.5;
double radianceAtDepth(double d) { return kLe * (1.0 - std::pow(kAlbedo, d + 1.0)) / (1.0 - kAlbedo); }
constexpr double kLimit = kLe / (1.0 - kAlbedo);

class Furnace : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }

    static ZSummary check(uint32_t k, const std::string& debias, double expected, uint64_t spp, uint32_t seed,
                          double* threshold = nullptr) {
        std::vector<SceneOverride> o = {{"camera.resolution", "[32,32]"},
                                        {"integrator.max_bounces", std::to_string(k)}};
        if (!debias.empty()) o.push_back({"integrator.debias", debias});
        Film film = renderFilm(loadTestScene("scenes/furnace.json", o), spp, seed);
        EXPECT_EQ(film.nonFiniteSamples(), 0u);
        auto regions = blockMeans(film, 8);
        double t = sidakThreshold(1e-3, regions.size() * 3);
        if (threshold) *threshold = t;
        return compareToValue(regions, glm::dvec3(expected), t);
    }
};

}  // namespace

TEST_F(Furnace, BiasedDepthMatchesTruncatedSeries) {
    for (uint32_t d : {0u, 1u, 3u}) {
        double t;
        ZSummary z = check(d, "", radianceAtDepth(d), 64, 10 + d, &t);
        EXPECT_EQ(z.failing, 0u) << "d = " << d << ": " << z.worst << " (threshold " << t << ")";
    }
}

TEST_F(Furnace, DebiasedK1ReachesTheLimit) {
    for (const char* debias : {R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.65}})",
                               R"({"estimator":"sum","pmf":{"type":"geometric","r":0.65}})",
                               R"({"estimator":"single_term","pmf":{"type":"power_law","alpha":0.5}})"}) {
        double t;
        ZSummary z = check(1, debias, kLimit, 128, 20, &t);
        EXPECT_EQ(z.failing, 0u) << debias << ": " << z.worst << " (threshold " << t << ")";
    }
}

TEST_F(Furnace, BiasedK1MissesTheLimit) {
    ZSummary z = check(1, "", kLimit, 128, 30);
    EXPECT_EQ(z.failing, z.tests) << "every region of I(1) should be rejected against the limit";
}
