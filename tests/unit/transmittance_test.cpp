// Transmittance models and estimators (shaders/shared/transmittance*.h), run on the CPU exactly as
// the shaders run them: the forms agree with the derivatives of T_ss, every unbiased estimator's
// mean matches the closed form within its statistical bound, biased marching fails the same test,
// unbiased ray marching has zero variance on constant density, and the correlated difference of
// debiased marching has a much smaller variance than an uncorrelated one.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "shared/transmittance_estimators.h"

using namespace telescope::shader;

namespace {

struct NamedModel {
    std::string name;
    TrModel model;
    bool diracMediumMedium;  // mediumMedium holds a Dirac part the forms cannot show
};

TrModel interpolated(uint32_t a, glm::vec4 pa, uint32_t b, glm::vec4 pb, float ratio) {
    TrModel m = trSimple(kTrInterpolated, pa);
    m.typeA = a;
    m.typeB = b;
    m.a = pa;
    m.b = pb;
    m.ratio = ratio;
    return m;
}

// Tungsten's default parameters (docs/TUNGSTEN-FORMAT.md), Davis also at Misso's c = 0.5.
std::vector<NamedModel> allModels() {
    return {
        {"exponential", trSimple(kTrExponential, glm::vec4(0.0f)), false},
        {"linear", trSimple(kTrLinear, glm::vec4(1.0f, 0, 0, 0)), true},
        {"quadratic", trSimple(kTrQuadratic, glm::vec4(0.75f, 0, 0, 0)), false},
        {"double_exponential", trSimple(kTrDoubleExponential, glm::vec4(0.5f, 10.0f, 0, 0)), false},
        {"erlang", trSimple(kTrErlang, glm::vec4(5.0f, 0, 0, 0)), false},
        {"davis", trSimple(kTrDavis, glm::vec4(1.1f, 0, 0, 0)), false},
        {"davis_c0.5", trSimple(kTrDavis, glm::vec4(4.0f, 0, 0, 0)), false},
        {"davis_weinstein", trSimple(kTrDavisWeinstein, glm::vec4(0.75f, 1.0f, 0, 0)), false},
        {"pulse", trSimple(kTrPulse, glm::vec4(0.0f, 1.0f, 4.0f, 0)), true},
        {"interpolated", interpolated(kTrLinear, glm::vec4(1.0f, 0, 0, 0), kTrErlang, glm::vec4(5.0f, 0, 0, 0), 0.5f), true},
    };
}

// A falloff slab: d(t) = a exp(-b t) on [0, 1], sigma_t = 1, optical depth tau.
TrSegment falloffSegment(double tau, float b = 2.0f) {
    TrSegment s{};
    // integral_0^1 a exp(-b t) dt = a (1 - e^-b) / b
    float a = float(tau * b / (1.0 - std::exp(-double(b))));
    s.profile = makeProfile(kProfileExponential, a, b, 0.0f);
    s.sigmaT = glm::vec3(1.0f);
    s.len = 1.0f;
    glm::vec2 bounds = profileBounds(s.profile, 0.0f, 1.0f);
    s.densityMin = bounds.x;
    s.densityMax = bounds.y;
    return s;
}

TrSegment profileSegment(DensityProfile p, float length, float looseness = 1.0f) {
    TrSegment s{};
    s.profile = p;
    s.sigmaT = glm::vec3(1.0f);
    s.len = length;
    glm::vec2 bounds = profileBounds(p, 0.0f, length);
    s.densityMin = bounds.x;
    s.densityMax = bounds.y * looseness;
    return s;
}

double tauOf(const TrSegment& s) { return profileIntegral(s.profile, 0.0, s.len); }

struct Moments {
    double mean = 0, varianceOfMean = 0, variance = 0, lookupsPerSample = 0;
};

Moments run(const std::function<glm::vec3(Rng&, uint32_t&)>& estimate, int samples, uint32_t seed) {
    double sum = 0, sum2 = 0;
    uint32_t lookups = 0;
    double totalLookups = 0;
    for (int i = 0; i < samples; ++i) {
        Rng rng = rngCreate(uint32_t(i), 12345u, seed);
        lookups = 0;
        double z = estimate(rng, lookups).x;
        totalLookups += lookups;
        sum += z;
        sum2 += z * z;
    }
    Moments m;
    m.mean = sum / samples;
    m.variance = std::max(0.0, sum2 / samples - m.mean * m.mean) * samples / (samples - 1.0);
    m.varianceOfMean = m.variance / samples;
    m.lookupsPerSample = totalLookups / samples;
    return m;
}

TrEstimator estimator(uint32_t type, uint32_t level = 1, float r = 0.65f) {
    return TrEstimator{type, level, LevelPmf{kPmfGeometric, r, 0.0f}};
}

constexpr double kZ = 5.0;  // |Z| bound per check (a few dozen checks: false alarms ~1e-5)

}  // namespace

// ---- The forms of every model are T_ss and its derivatives (Tungsten's eval) ----
TEST(TransmittanceModels, FormsAreDerivativesOfSurfaceSurface) {
    for (const NamedModel& nm : allModels()) {
        const TrModel& m = nm.model;
        EXPECT_NEAR(trForm(m, kFormSurfaceSurface, 0.0f), 1.0f, 1e-5f) << nm.name;
        const float sb = trSigmaBar(m);
        for (float tau : {0.05f, 0.2f, 0.37f, 0.6f, 1.3f, 2.9f}) {
            const float h = std::min(1e-2f, 0.05f * tau);
            auto g = [&](float t) { return double(trForm(m, kFormSurfaceSurface, t)); };
            double dg = (g(tau + h) - g(tau - h)) / (2 * h);
            // eval(mm) = g''/sigmaBar^2 = -(d/dtau T_sm) / sigmaBar
            double dms = (double(trForm(m, kFormSurfaceMedium, tau + h)) - trForm(m, kFormSurfaceMedium, tau - h)) / (2 * h);
            // Skip the kinks of piecewise models: finite differences straddle them.
            double ms = trForm(m, kFormSurfaceMedium, tau);
            double msL = trForm(m, kFormSurfaceMedium, tau - h), msR = trForm(m, kFormSurfaceMedium, tau + h);
            if (std::abs(msL - msR) > 0.5 * std::abs(ms) * 0.05 + 1e-3 && nm.diracMediumMedium) continue;
            EXPECT_NEAR(ms, -dg / sb, 2e-3 * (1 + std::abs(ms))) << nm.name << " tau " << tau;
            if (!nm.diracMediumMedium) {
                double mm = trForm(m, kFormMediumMedium, tau);
                EXPECT_NEAR(mm, -dms / sb, 2e-3 * (1 + std::abs(mm))) << nm.name << " tau " << tau;
            }
        }
    }
}

TEST(TransmittanceModels, DavisMatchesEstimatorsDoc) {
    // T_ss = (1 + tau/a)^-a, T_sm = (1 + tau/a)^-(a+1), T_mm = (1 + 1/a)(1 + tau/a)^-(a+2)
    TrModel m = trSimple(kTrDavis, glm::vec4(4.0f, 0, 0, 0));  // c = 0.5
    float tau = 0.8f;
    EXPECT_NEAR(trForm(m, kFormSurfaceSurface, tau), std::pow(1 + 0.25 * 0.8, -4.0), 1e-6);
    EXPECT_NEAR(trForm(m, kFormSurfaceMedium, tau), std::pow(1 + 0.25 * 0.8, -5.0), 1e-6);
    EXPECT_NEAR(trForm(m, kFormMediumMedium, tau), 1.25 * std::pow(1 + 0.25 * 0.8, -6.0), 1e-6);
}

// ---- Every model: debiased marching is unbiased on a falloff slab ----
TEST(TransmittanceEstimators, DebiasedMeanMatchesEveryModelOnFalloffSlab) {
    for (const NamedModel& nm : allModels()) {
        for (double tau : {0.3, 0.7}) {
            TrSegment s = falloffSegment(tau, 3.0f);
            double truth = trForm(nm.model, kFormSurfaceSurface, float(tau));
            TrEstimator e = estimator(kTrEstDebiasedRayMarch, 1);
            Moments mo = run([&](Rng& rng, uint32_t& n) { return trEstimate(e, nm.model, kFormSurfaceSurface, s, rng, n); },
                             100000, 11);
            double z = (mo.mean - truth) / std::sqrt(mo.varianceOfMean);
            EXPECT_LT(std::abs(z), kZ) << nm.name << " tau " << tau << ": mean " << mo.mean << " truth " << truth;
        }
    }
}

TEST(TransmittanceEstimators, DebiasedMeanMatchesMediumFormsForDavis) {
    TrModel m = trSimple(kTrDavis, glm::vec4(1.1f, 0, 0, 0));
    TrSegment s = falloffSegment(1.5, 4.0f);
    for (uint32_t form : {kFormSurfaceMedium, kFormMediumMedium}) {
        double truth = trForm(m, form, 1.5f);
        TrEstimator e = estimator(kTrEstDebiasedRayMarch, 2);
        Moments mo = run([&](Rng& rng, uint32_t& n) { return trEstimate(e, m, form, s, rng, n); }, 100000, 12);
        EXPECT_LT(std::abs(mo.mean - truth) / std::sqrt(mo.varianceOfMean), kZ) << "form " << form;
    }
}

// ---- The biased base fails the same test ----
TEST(TransmittanceEstimators, BiasedMarchingAtSmallLevelFails) {
    TrModel m = trSimple(kTrDavis, glm::vec4(1.1f, 0, 0, 0));
    TrSegment s = falloffSegment(2.0, 4.0f);
    double truth = trForm(m, kFormSurfaceSurface, 2.0f);
    TrEstimator e = estimator(kTrEstRayMarch, 1);
    Moments mo = run([&](Rng& rng, uint32_t& n) { return trEstimate(e, m, kFormSurfaceSurface, s, rng, n); }, 100000, 13);
    EXPECT_GT(std::abs(mo.mean - truth) / std::sqrt(mo.varianceOfMean), 20.0) << "mean " << mo.mean << " truth " << truth;
}

// ---- Exponential media: every unbiased estimator matches exp(-tau) ----
TEST(TransmittanceEstimators, UnbiasedEstimatorsMatchExponential) {
    TrModel m = trSimple(kTrExponential, glm::vec4(0.0f));
    std::vector<std::pair<std::string, TrSegment>> segments = {
        {"falloff", falloffSegment(1.2, 3.0f)},
        {"sine", profileSegment(makeProfile(kProfileSine, 2.0f, 0.9f, 2.7f), 1.0f, 1.5f)},
        {"gaussian", profileSegment(makeProfile(kProfileGaussian, 4.0f, 0.4f, 0.15f), 1.0f)},
    };
    for (uint32_t type : {kTrEstDebiasedRayMarch, kTrEstDeltaTracking, kTrEstRatioTracking,
                          kTrEstResidualRatioTracking, kTrEstUnbiasedRayMarch}) {
        for (const auto& [name, s] : segments) {
            double truth = std::exp(-tauOf(s));
            TrEstimator e = estimator(type, 1);
            Moments mo = run([&](Rng& rng, uint32_t& n) { return trEstimate(e, m, kFormSurfaceSurface, s, rng, n); },
                             100000, 14 + type);
            EXPECT_LT(std::abs(mo.mean - truth) / std::sqrt(mo.varianceOfMean + 1e-14), kZ)
                << "estimator " << type << " on " << name << ": mean " << mo.mean << " truth " << truth;
        }
    }
}

TEST(TransmittanceEstimators, UnbiasedRayMarchingHasZeroVarianceOnConstantDensity) {
    TrModel m = trSimple(kTrExponential, glm::vec4(0.0f));
    TrSegment s = profileSegment(makeProfile(kProfileConstant, 1.7f, 0, 0), 1.3f);
    double truth = std::exp(-1.7 * 1.3);
    TrEstimator e = estimator(kTrEstUnbiasedRayMarch);
    for (int i = 0; i < 10000; ++i) {
        Rng rng = rngCreate(uint32_t(i), 1u, 99u);
        uint32_t n = 0;
        ASSERT_NEAR(trEstimate(e, m, kFormSurfaceSurface, s, rng, n).x, truth, 2e-6 * truth) << "sample " << i;
    }
}

// ---- Correlation: the antithetic comb difference against independent combs (measured) ----
TEST(TransmittanceEstimators, CorrelatedDifferenceHasMuchLowerVariance) {
    TrModel m = trSimple(kTrDavis, glm::vec4(1.1f, 0, 0, 0));
    TrSegment s = profileSegment(makeProfile(kProfileSine, 3.0f, 0.8f, 2.5f), 1.0f);
    const uint32_t j = 4;
    auto correlated = [&](Rng& rng, uint32_t& n) {
        // One comb of 2^(j+1) points: all, even, odd.
        float u = rngNext(rng);
        float even = combSum(s, u, 0, 2, 1u << j, float(1u << (j + 1)), n);
        float odd = combSum(s, u, 1, 2, 1u << j, float(1u << (j + 1)), n);
        float all = (even + odd) / float(1u << (j + 1)), e = even / float(1u << j), o = odd / float(1u << j);
        return glm::vec3(trForm(m, 0, all * s.len) -
                         0.5f * (trForm(m, 0, e * s.len) + trForm(m, 0, o * s.len)));
    };
    auto uncorrelated = [&](Rng& rng, uint32_t& n) {
        float fine = combSum(s, rngNext(rng), 0, 1, 1u << (j + 1), float(1u << (j + 1)), n) / float(1u << (j + 1));
        float coarse = combSum(s, rngNext(rng), 0, 1, 1u << j, float(1u << j), n) / float(1u << j);
        return glm::vec3(trForm(m, 0, fine * s.len) - trForm(m, 0, coarse * s.len));
    };
    Moments c = run(correlated, 50000, 21), u = run(uncorrelated, 50000, 22);
    // Same expectation, D_j = I(j+1) - I(j)
    EXPECT_LT(std::abs(c.mean - u.mean) / std::sqrt(c.varianceOfMean + u.varianceOfMean), kZ);
    RecordProperty("variance_correlated", std::to_string(c.variance));
    RecordProperty("variance_uncorrelated", std::to_string(u.variance));
    std::printf("D_%u variance: correlated %.3g, uncorrelated %.3g (ratio %.3g)\n", j, c.variance, u.variance,
                u.variance / c.variance);
    EXPECT_LT(c.variance * 10.0, u.variance);
}

TEST(TransmittanceEstimators, DebiasedMarchingCostIsTheCombSize) {
    // Cost 2^(j+1) lookups; E[cost] = sum_m p(m) 2^(k+m+1) = 2^(k+1) r / (1 - 2(1-r)) for r > 1/2.
    TrModel m = trSimple(kTrExponential, glm::vec4(0.0f));
    TrSegment s = falloffSegment(1.0);
    TrEstimator e = estimator(kTrEstDebiasedRayMarch, 1, 0.65f);
    Moments mo = run([&](Rng& rng, uint32_t& n) { return trEstimate(e, m, 0, s, rng, n); }, 200000, 31);
    double expected = 4.0 * 0.65 / (1.0 - 2.0 * 0.35);
    EXPECT_NEAR(mo.lookupsPerSample, expected, 0.05 * expected);
}

TEST(DensityProfiles, IntegralsMatchQuadrature) {
    for (DensityProfile p : {makeProfile(kProfileConstant, 2, 0, 0), makeProfile(kProfileLinear, 1, 3, 0),
                             makeProfile(kProfileExponential, 2, 1.5f, 0), makeProfile(kProfileSine, 2, 0.7f, 2.2f),
                             makeProfile(kProfileGaussian, 3, 0.4f, 0.2f)}) {
        double sum = 0;
        const int n = 200000;
        for (int i = 0; i < n; ++i) sum += profileDensity(p, float((i + 0.5) / n * 1.7)) * 1.7 / n;
        EXPECT_NEAR(profileIntegral(p, 0.0, 1.7), sum, 1e-4 * (1 + sum)) << "profile " << p.type;
        glm::vec2 b = profileBounds(p, 0.0f, 1.7f);
        for (int i = 0; i <= 100; ++i) {
            float d = profileDensity(p, 1.7f * i / 100);
            EXPECT_GE(d, b.x - 1e-5f);
            EXPECT_LE(d, b.y + 1e-5f);
        }
    }
}
