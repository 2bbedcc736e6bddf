// The Taylor-series transmittance estimator (shared/transmittance_estimators.h, trTaylor), on the
// CPU through the same code the shaders run: its series against a numerical expansion, its
// zero variance on constant density, its mean against closed forms with three positive controls,
// and finite answers at the extremes of optical depth and of Davis's tail.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "shared/density_profiles.h"
#include "shared/transmittance_estimators.h"

using namespace telescope::shader;

namespace {

TrEstimator taylor(uint32_t level = 1, uint32_t terms = 1, uint32_t points = 0) {
    return TrEstimator{kTrEstTaylor, level, LevelPmf{kPmfGeometric, 0.65f, 0.0f}, terms, points};
}

TrModel davis(float alpha) { return trSimple(kTrDavis, glm::vec4(alpha, 0, 0, 0)); }

TrSegment segment(DensityProfile p, float length = 1.0f) {
    TrSegment s{};
    s.profile = p;
    s.sigmaT = glm::vec3(1.0f);
    s.len = length;
    const glm::vec2 bounds = profileBounds(p, 0.0f, length);
    s.densityMin = bounds.x;
    s.densityMax = bounds.y;
    return s;
}

// A profile of the given shape scaled to optical depth tau over [0, 1].
TrSegment withDepth(DensityProfile p, double tau) {
    p.a = float(tau / profileIntegral(p, 0.0, 1.0));
    return segment(p);
}

double depthOf(const TrSegment& s) { return profileIntegral(s.profile, 0.0, s.len); }

struct Moments {
    double mean = 0, variance = 0, se = 0, lookups = 0;
    bool finite = true;
};

Moments run(const TrEstimator& e, const TrModel& m, uint32_t form, const TrSegment& s, int samples, uint32_t seed,
            uint32_t variant = kTaylorExact) {
    double sum = 0, sum2 = 0, lookups = 0;
    Moments mo;
    for (int i = 0; i < samples; ++i) {
        Rng rng = rngCreate(uint32_t(i), 4242u, seed);
        uint32_t n = 0;
        const double z = trTaylor(e, m, form, s, rng, n, variant).x;
        if (!std::isfinite(z)) mo.finite = false;
        sum += z;
        sum2 += z * z;
        lookups += n;
    }
    mo.mean = sum / samples;
    mo.variance = std::max(0.0, sum2 / samples - mo.mean * mo.mean) * samples / (samples - 1.0);
    mo.se = std::sqrt(mo.variance / samples);
    mo.lookups = lookups / samples;
    return mo;
}

constexpr double kZ = 5.0;  // per check; a few dozen checks

double zScore(const Moments& mo, double truth) { return (mo.mean - truth) / std::max(mo.se, 1e-300); }

// The supported models, with the radius of convergence of their series around x (infinite but
// for Davis: x + alpha).
struct SeriesModel {
    std::string name;
    TrModel model;
    float alpha;  // Davis's alpha, 0 for entire models
};

std::vector<SeriesModel> seriesModels() {
    return {
        {"exponential", trSimple(kTrExponential, glm::vec4(0.0f)), 0.0f},
        {"davis c=0.8", davis(1.5625f), 1.5625f},
        {"davis c=0.3", davis(11.11f), 11.11f},
        {"davis c=3", davis(0.111f), 0.111f},
        {"double_exponential", trSimple(kTrDoubleExponential, glm::vec4(0.5f, 3.0f, 0, 0)), 0.0f},
        {"erlang", trSimple(kTrErlang, glm::vec4(2.0f, 0, 0, 0)), 0.0f},
        {"interpolated davis/erlang", TrModel{kTrInterpolated, kTrDavis, kTrErlang, 0.3f, glm::vec4(2.0f, 0, 0, 0),
                                              glm::vec4(1.5f, 0, 0, 0)},
         2.0f},
    };
}

}  // namespace

// ---- The series: sum_j c_j(x) h^j equals the form at x + h (every sign and index) ----
TEST(TaylorSeries, MatchesTheModelsFormsAroundAnyPivot) {
    for (const SeriesModel& sm : seriesModels()) {
        for (uint32_t form : {kFormSurfaceSurface, kFormSurfaceMedium, kFormMediumMedium}) {
            for (float x : {0.0f, 0.3f, 2.0f}) {
                const float radius = sm.alpha > 0.0f ? x + sm.alpha : 1e9f;
                for (float h : {-0.25f, 0.1f, 0.6f, -0.9f}) {
                    if (x + h < 0.0f) continue;
                    h = std::copysign(std::min(std::abs(h), 0.5f * radius), h);  // inside the radius
                    TrTaylorSeries s = trTaylorSeries(sm.model, form, glm::vec3(x));
                    double sum = trTaylorValue(s).x;
                    for (uint32_t j = 1; j <= 60; ++j) sum += trTaylorNext(s, j, glm::vec3(h), -1.0f).x;
                    const double truth = trForm(sm.model, form, x + h);
                    EXPECT_NEAR(sum, truth, 2e-5 * (1.0 + std::abs(truth)))
                        << sm.name << " form " << form << " x " << x << " h " << h;
                }
            }
        }
    }
}

TEST(TaylorSeries, DavisTermsAreThePapersWithTheirSign) {
    // g(F) = (1 + F C^2)^(-1/C^2): term j = (x - F)^j / j! (1 + x C^2)^(-1/C^2 - j) prod_{i=1}^{j-1} (1 + i C^2),
    // i.e. c_j = (-1)^j / j! (1 + x C^2)^(-1/C^2 - j) prod_{i=1}^{j-1} (1 + i C^2).
    for (double c2 : {0.1, 0.64, 2.5}) {
        const double x = 0.7;
        TrTaylorSeries s = trTaylorSeries(davis(float(1.0 / c2)), kFormSurfaceSurface, glm::vec3(float(x)));
        double factorial = 1, product = 1;
        for (uint32_t j = 1; j <= 8; ++j) {
            factorial *= j;
            if (j >= 2) product *= 1.0 + (j - 1) * c2;
            const double expected = (j % 2 ? -1.0 : 1.0) / factorial * std::pow(1.0 + x * c2, -1.0 / c2 - j) * product;
            const double got = trTaylorNext(s, j, glm::vec3(1.0f), -1.0f).x;
            EXPECT_NEAR(got, expected, 2e-5 * std::abs(expected)) << "C^2 " << c2 << " j " << j;
        }
    }
}

TEST(TaylorSeries, SupportsTheModelsWithAConvergentSeriesOnly) {
    for (uint32_t t : {kTrExponential, kTrDoubleExponential, kTrErlang, kTrDavis}) EXPECT_TRUE(trTaylorSimpleSupported(t)) << t;
    for (uint32_t t : {kTrLinear, kTrQuadratic, kTrPulse, kTrDavisWeinstein, kTrInterpolated})
        EXPECT_FALSE(trTaylorSimpleSupported(t)) << t;
}

// ---- Constant density: every comb is exact, the estimator is g(tau) exactly ----
TEST(TaylorEstimator, HasZeroVarianceOnConstantDensity) {
    for (const SeriesModel& sm : seriesModels()) {
        const TrSegment s = segment(makeProfile(kProfileConstant, 1.7f, 0, 0), 1.3f);
        const double truth = trForm(sm.model, kFormSurfaceSurface, 1.7f * 1.3f);
        const Moments mo = run(taylor(), sm.model, kFormSurfaceSurface, s, 20000, 3);
        EXPECT_NEAR(mo.mean, truth, 1e-6 * truth) << sm.name;
        EXPECT_LT(mo.variance, 1e-12 * truth * truth) << sm.name << ": the variance must be ~0, not just the mean";
    }
}

// ---- Varying density, Davis: unbiased with the default settings, on every form ----
TEST(TaylorEstimator, MatchesDavisClosedFormsOnVaryingDensity) {
    const std::vector<std::pair<std::string, TrSegment>> segments = {
        {"falloff", withDepth(makeProfile(kProfileExponential, 1.0f, 4.0f, 0.0f), 1.5)},
        {"sine 2.3 periods", withDepth(makeProfile(kProfileSine, 1.0f, 0.9f, 2.3f), 2.0)},
        {"gaussian", withDepth(makeProfile(kProfileGaussian, 1.0f, 0.45f, 0.12f), 0.8)},
    };
    uint32_t seed = 10;
    for (float alpha : {0.39f, 1.5625f, 6.25f})
        for (const auto& [name, s] : segments)
            for (uint32_t form : {kFormSurfaceSurface, kFormSurfaceMedium, kFormMediumMedium}) {
                const double truth = trForm(davis(alpha), form, float(depthOf(s)));
                const Moments mo = run(taylor(), davis(alpha), form, s, 40000, seed++);
                EXPECT_LT(std::abs(zScore(mo, truth)), kZ)
                    << name << " alpha " << alpha << " form " << form << ": mean " << mo.mean << " truth " << truth;
                EXPECT_TRUE(mo.finite);
            }
}

// ---- The deciding test and its three positive controls, at the same sample count ----
// Davis (c = 0.8, Misso et al.), a sine slab over one whole period (tau = 1.5, amplitude 0.6),
// one-point combs and a one-point pivot: coarse on purpose, so that the powers of (X - x) carry
// weight. |X - x| <= 1.8 < x + alpha (x >= 0.6) everywhere: the series converges for every
// sample, so the variance is finite and a Z-test is valid.
TEST(TaylorEstimator, DavisSlabPassesAndTheControlsFail) {
    const TrModel m = davis(1.5625f);
    const TrSegment s = withDepth(makeProfile(kProfileSine, 1.0f, 0.6f, 1.0f), 1.5);
    const double truth = trForm(m, kFormSurfaceSurface, float(depthOf(s)));
    const TrEstimator e = taylor(0, 1, 1);
    const int samples = 100000;
    const Moments exact = run(e, m, kFormSurfaceSurface, s, samples, 77);
    std::printf("taylor: mean %.6f truth %.6f z %.2f, standard error %.3f%%\n", exact.mean, truth, zScore(exact, truth),
                100 * exact.se / truth);
    EXPECT_LT(exact.se / truth, 0.005 / 3) << "the test must resolve 0.5%";
    EXPECT_LT(std::abs(zScore(exact, truth)), kZ) << "mean " << exact.mean << " truth " << truth;
    const std::pair<uint32_t, const char*> controls[] = {
        {kTaylorControlReusedDepth, "one depth estimate reused for every factor"},
        {kTaylorControlNoSign, "(-1)^j dropped"},
        {kTaylorControlThreeTerms, "three terms, no roulette"},
    };
    for (const auto& [variant, what] : controls) {
        const Moments wrong = run(e, m, kFormSurfaceSurface, s, samples, 77, variant);
        std::printf("control '%s': mean %.6f z %.2f\n", what, wrong.mean, zScore(wrong, truth));
        EXPECT_GT(std::abs(zScore(wrong, truth)), kZ) << what << ": the test cannot tell it from the estimator";
    }
}

// ---- Extremes: optical depth 1e-6 to 1e3, C^2 = 0.01 to 10 ----
TEST(TaylorEstimator, StaysFiniteAndRightAtExtremeDepthsAndTails) {
    uint32_t seed = 100;
    for (double c2 : {0.01, 0.64, 10.0})
        for (double tau : {1e-6, 1e-3, 1.0, 30.0, 1e3}) {
            const TrModel m = davis(float(1.0 / c2));
            const TrSegment s = withDepth(makeProfile(kProfileExponential, 1.0f, 3.0f, 0.0f), tau);
            const double truth = trForm(m, kFormSurfaceSurface, float(depthOf(s)));
            const Moments mo = run(taylor(), m, kFormSurfaceSurface, s, 4000, seed++);
            EXPECT_TRUE(mo.finite) << "C^2 " << c2 << " tau " << tau;
            EXPECT_LT(std::abs(mo.mean - truth), kZ * mo.se + 1e-5 * truth + 1e-30)
                << "C^2 " << c2 << " tau " << tau << ": mean " << mo.mean << " truth " << truth;
            EXPECT_LE(mo.lookups, 2.0 * (256 + 40 * 256)) << "C^2 " << c2 << " tau " << tau;
        }
    // Exponential up to tau = 1e3 (exp(-1e3) underflows to 0 exactly)
    for (double tau : {1e-6, 1.0, 1e3}) {
        const TrSegment s = withDepth(makeProfile(kProfileExponential, 1.0f, 3.0f, 0.0f), tau);
        const Moments mo = run(taylor(), trSimple(kTrExponential, glm::vec4(0.0f)), kFormSurfaceSurface, s, 4000, seed++);
        const double truth = std::exp(-depthOf(s));
        EXPECT_TRUE(mo.finite) << tau;
        EXPECT_LT(std::abs(mo.mean - truth), kZ * mo.se + 1e-5 * truth + 1e-30) << tau;
    }
}
