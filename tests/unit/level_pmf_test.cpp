// The level pmf (shaders/shared/level_pmf.h), run on the CPU exactly as the shaders run it.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "shared/level_pmf.h"
#include "shared/rng.h"

using namespace telescope::shader;

namespace {

LevelPmf geometric(float r) { return LevelPmf{kPmfGeometric, r, 0.0f}; }
LevelPmf powerLaw(float alpha) { return LevelPmf{kPmfPowerLaw, 0.0f, alpha}; }

// Upper quantile of chi-square with k degrees of freedom (Wilson-Hilferty), z = normal quantile.
double chiSquareQuantile(double k, double z) {
    double h = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - h + z * std::sqrt(h), 3.0);
}

// Chi-square statistic of `samples` draws of `sampler` against `pmf`; bins 0..B-1 plus a tail.
double chiSquare(const LevelPmf& sampler, const LevelPmf& pmf, int samples, int bins, uint32_t seed) {
    std::vector<double> counts(bins + 1, 0.0);
    Rng rng = rngCreate(7, 11, seed);
    for (int i = 0; i < samples; ++i) {
        uint m = levelSample(sampler, rngNext(rng));
        counts[std::min<uint>(m, uint(bins))] += 1.0;
    }
    double chi2 = 0.0;
    for (int b = 0; b <= bins; ++b) {
        double p = b < bins ? levelProbability(pmf, uint(b)) : levelTail(pmf, uint(bins));
        double expected = p * samples;
        chi2 += (counts[b] - expected) * (counts[b] - expected) / expected;
    }
    return chi2;
}

}  // namespace

TEST(LevelPmf, GeometricIsNormalisedAndMatchesItsTail) {
    for (float r : {0.2f, 0.5f, 0.65f, 0.9f}) {
        LevelPmf pmf = geometric(r);
        double sum = 0.0;
        for (uint m = 0; m < 400; ++m) {
            sum += levelProbability(pmf, m);
            if (levelTail(pmf, m) < 1e-30f) continue;  // float denormals: no relative accuracy left
            EXPECT_NEAR(levelProbability(pmf, m), levelTail(pmf, m) - levelTail(pmf, m + 1), 1e-5 * levelTail(pmf, m));
        }
        EXPECT_NEAR(sum, 1.0, 1e-5) << "r = " << r;
    }
}

TEST(LevelPmf, PowerLawIsNormalisedAndStableFarOut) {
    for (float alpha : {0.3f, 2.0f / 3.0f, 0.9f}) {
        LevelPmf pmf = powerLaw(alpha);
        double sum = 0.0;
        const uint M = 100000;
        for (uint m = 0; m < M; ++m) sum += levelProbability(pmf, m);
        EXPECT_NEAR(sum + levelTail(pmf, M), 1.0, 1e-4) << "alpha = " << alpha;
        // Far levels: p(m) positive and finite, relative agreement with the derivative of the tail.
        for (uint m : {1000u, 100000u, 10000000u, 2000000000u}) {
            double p = levelProbability(pmf, m);
            double analytic = (1.0 - alpha) * std::pow(double(m) + 1.5, double(alpha) - 2.0);
            EXPECT_TRUE(std::isfinite(1.0 / p)) << m;
            EXPECT_NEAR(p / analytic, 1.0, 2e-3) << "alpha = " << alpha << " m = " << m;
        }
    }
}

TEST(LevelPmf, SamplerPassesChiSquare) {
    const int samples = 200000, bins = 12;
    const double critical = chiSquareQuantile(bins, 3.09);  // 0.1% level
    EXPECT_LT(chiSquare(geometric(0.65f), geometric(0.65f), samples, bins, 1), critical);
    EXPECT_LT(chiSquare(geometric(0.3f), geometric(0.3f), samples, bins, 2), critical);
    EXPECT_LT(chiSquare(powerLaw(2.0f / 3.0f), powerLaw(2.0f / 3.0f), samples, bins, 3), critical);
    EXPECT_LT(chiSquare(powerLaw(0.4f), powerLaw(0.4f), samples, bins, 4), critical);
}

TEST(LevelPmf, ChiSquareDetectsAWrongSampler) {
    // The same test must fail for a sampler that is slightly off.
    const int samples = 200000, bins = 12;
    const double critical = chiSquareQuantile(bins, 3.09);
    EXPECT_GT(chiSquare(geometric(0.62f), geometric(0.65f), samples, bins, 5), critical);
    EXPECT_GT(chiSquare(powerLaw(0.62f), powerLaw(2.0f / 3.0f), samples, bins, 6), critical);
}

TEST(LevelPmf, SamplesStayFiniteAtTheEdgeOfTheUnitInterval) {
    const float largest = 1.0f - 1.0f / 16777216.0f;  // the largest value rngNext returns
    EXPECT_LT(levelSample(geometric(0.65f), largest), 30u);
    uint m = levelSample(powerLaw(2.0f / 3.0f), largest);
    EXPECT_EQ(m, kMaxLevel);
    EXPECT_TRUE(std::isfinite(1.0f / levelProbability(powerLaw(2.0f / 3.0f), m)));
    EXPECT_EQ(levelSample(geometric(0.65f), 0.0f), 0u);
    EXPECT_EQ(levelSample(powerLaw(2.0f / 3.0f), 0.0f), 0u);
}

// Stability: for every pmf a user can ask for, every level the sampler can return has a finite,
// positive 1 / p(j) and 1 / P(N >= j), so a correction divided by them is never inf or NaN.
TEST(LevelPmf, InverseProbabilitiesStayFiniteForExtremePmfs) {
    std::vector<LevelPmf> pmfs;
    for (float r : {1e-7f, 1e-3f, 0.3f, 0.65f, 0.99f, 0.999999f}) pmfs.push_back(geometric(r));
    for (float a : {1e-4f, 0.01f, 0.5f, 2.0f / 3.0f, 0.99f, 0.9999f}) pmfs.push_back(powerLaw(a));
    std::vector<float> us = {0.0f, 1e-30f, 1e-7f, 0.5f, 0.9f, 0.999f, 1.0f - 1.0f / 16777216.0f};
    for (uint32_t i = 1; i < 4096; ++i) us.push_back(float(i) / 4096.0f);
    for (const LevelPmf& pmf : pmfs) {
        for (float u : us) {
            const uint m = levelSample(pmf, u);
            const float p = levelProbability(pmf, m), tail = levelTail(pmf, m);
            ASSERT_TRUE(std::isfinite(1.0f / p) && p > 0.0f)
                << "type " << pmf.type << " r " << pmf.r << " alpha " << pmf.alpha << " u " << u << " m " << m;
            ASSERT_TRUE(std::isfinite(1.0f / tail) && tail > 0.0f) << "type " << pmf.type << " m " << m;
        }
    }
}
