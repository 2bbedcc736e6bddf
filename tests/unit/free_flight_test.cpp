// Free-flight sampling (shaders/shared/free_flight.h), run on the CPU exactly as the shaders run
// it: the optical depths drawn from a surface and from a medium point follow the survival
// functions T_ss and T_ms of every model (chi-square of a histogram against the forms), the
// Dirac flights of `linear` and `pulse` included; drawing from the surface form where the medium
// form is due fails the same test. The Dirac segment's weights have the expectation of
// Tungsten's collision and passing probabilities per colour channel; weighting by the drawn
// channel alone (no sharing between channels) fails.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "shared/free_flight.h"
#include "shared/rng.h"

using namespace telescope::shader;

namespace {

struct NamedModel {
    std::string name;
    TrModel model;
};

// Tungsten's defaults, and the parameters of scenes/tungsten/non-exponential.
std::vector<NamedModel> models() {
    return {
        {"exponential", trSimple(kTrExponential, glm::vec4(0.0f))},
        {"linear 0.75", trSimple(kTrLinear, glm::vec4(0.75f, 0, 0, 0))},
        {"quadratic 0.75", trSimple(kTrQuadratic, glm::vec4(0.75f, 0, 0, 0))},
        {"double_exponential 1 10", trSimple(kTrDoubleExponential, glm::vec4(1.0f, 10.0f, 0, 0))},
        {"erlang 5", trSimple(kTrErlang, glm::vec4(5.0f, 0, 0, 0))},
        {"davis 1.1", trSimple(kTrDavis, glm::vec4(1.1f, 0, 0, 0))},
        {"pulse 0 1 4", trSimple(kTrPulse, glm::vec4(0.0f, 1.0f, 4.0f, 0))},
    };
}

// Upper quantile of chi-square with k degrees of freedom (Wilson-Hilferty), z = normal quantile.
double chiSquareQuantile(double k, double z) {
    double h = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - h + z * std::sqrt(h), 3.0);
}

// The sampler the path tracer uses (medium.glsl): Dirac flights from a medium point, else the
// inverse of the survival function.
float drawDepth(const TrModel& m, bool fromSurface, float u) {
    if (!fromSurface && trModelIsDirac(m)) return sampleDiracDepth(m, u);
    return sampleGuideDepth(m, fromSurface, u);
}

struct ChiSquare {
    double statistic = 0.0;
    double critical = 0.0;
};

// `samples` draws against the survival function F (T_ss or T_ms): bins with edges
// 8 (i / 60)^2 (none on a Dirac of the models above) and a tail, merged until each expects >= 20.
ChiSquare chiSquare(const std::function<float(float)>& draw, const std::function<double(double)>& survival,
                    int samples, uint32_t seed, double z) {
    const int bins = 60;
    std::vector<double> edges;
    for (int i = 0; i <= bins; ++i) edges.push_back(8.0 * (double(i) / bins) * (double(i) / bins));
    std::vector<double> counts(bins + 1, 0.0);
    Rng rng = rngCreate(3, 5, seed);
    for (int i = 0; i < samples; ++i) {
        double tau = draw(rngNext(rng));
        int b = bins;
        for (int k = 0; k < bins; ++k)
            if (tau >= edges[k] && tau < edges[k + 1]) b = k;
        counts[b] += 1.0;
    }
    ChiSquare r;
    double observed = 0.0, expected = 0.0;
    int cells = 0;
    for (int b = 0; b <= bins; ++b) {
        double p = b < bins ? survival(edges[b]) - survival(edges[b + 1]) : survival(edges[bins]);
        if (p <= 0.0 && counts[b] > 0.0) r.statistic = INFINITY;  // samples where the model has no probability
        observed += counts[b];
        expected += p * samples;
        if (expected >= 20.0 || b == bins) {
            if (expected > 0.0) {
                r.statistic += (observed - expected) * (observed - expected) / expected;
                ++cells;
            } else if (observed > 0.0) {
                r.statistic = INFINITY;
            }
            observed = expected = 0.0;
        }
    }
    r.critical = chiSquareQuantile(std::max(cells - 1, 1), z);
    return r;
}

// Family of 2 x 7 tests at 1e-3 overall: z for 1e-3 / 14 (one-sided).
constexpr double kZ = 3.80;
constexpr int kSamples = 200000;

}  // namespace

TEST(FreeFlight, DepthsFollowTheSurfaceAndMediumForms) {
    uint32_t seed = 1;
    for (const NamedModel& nm : models()) {
        for (bool fromSurface : {true, false}) {
            const TrModel m = nm.model;
            const uint form = fromSurface ? kFormSurfaceSurface : kFormSurfaceMedium;
            ChiSquare c = chiSquare([&](float u) { return drawDepth(m, fromSurface, u); },
                                    [&](double tau) { return double(trForm(m, form, float(tau))); }, kSamples,
                                    seed++, kZ);
            EXPECT_LT(c.statistic, c.critical) << nm.name << (fromSurface ? " from a surface" : " from a medium point");
        }
    }
}

// Positive control: from a medium point, drawing the surface form (what a renderer that ignores
// where the flight starts does) is rejected for every model whose two forms differ.
TEST(FreeFlight, SurfaceFormFromAMediumPointIsRejected) {
    uint32_t seed = 101;
    for (const NamedModel& nm : models()) {
        if (nm.model.type == kTrExponential) continue;  // the forms are equal
        const TrModel m = nm.model;
        ChiSquare c = chiSquare([&](float u) { return drawDepth(m, true, u); },
                                [&](double tau) { return double(trForm(m, kFormSurfaceMedium, float(tau))); },
                                kSamples, seed++, kZ);
        EXPECT_GT(c.statistic, c.critical) << nm.name << ": the test cannot tell the surface form from the medium form";
    }
}

namespace {

// Monte Carlo means of the Dirac segment's weights, per channel: scattering weight x f(t) and
// passing weight, against the closed forms
//   E[w_s f(t)] = sigma_s / sigma_t x sum over Diracs i with tau_i < sigma_t l of mass_i f(tau_i / sigma_t),
//   E[w_p]      = T_ms(sigma_t l).
struct DiracMeans {
    glm::dvec3 scatter{0.0}, scatterTrue{0.0}, scatterSe{0.0};
    glm::dvec3 pass{0.0}, passTrue{0.0}, passSe{0.0};
};

DiracMeans diracMeans(const TrModel& m, glm::vec3 sigmaT, glm::vec3 sigmaS, float l, bool shareChannels, uint32_t seed) {
    const int n = 400000;
    auto f = [](double t) { return 1.0 + t; };
    glm::dvec3 s1(0.0), s2(0.0), p1(0.0), p2(0.0);
    Rng rng = rngCreate(9, 4, seed);
    for (int i = 0; i < n; ++i) {
        float uc = rngNext(rng), ud = rngNext(rng);
        float t = 0.0f;
        glm::vec3 w(0.0f);
        bool scattered = sampleDiracFlight(m, sigmaT, sigmaS, l, uc, ud, t, w);
        if (!shareChannels && scattered) {
            // control: the drawn channel alone, weighted as if every channel had drawn it
            uint c = std::min(uint(uc * 3.0f), 2u);
            w = sigmaS / sigmaT[c];
        }
        glm::dvec3 ws = scattered ? glm::dvec3(w) * f(t) : glm::dvec3(0.0);
        glm::dvec3 wp = scattered ? glm::dvec3(0.0) : glm::dvec3(w);
        s1 += ws; s2 += ws * ws; p1 += wp; p2 += wp * wp;
    }
    DiracMeans r;
    r.scatter = s1 / double(n);
    r.pass = p1 / double(n);
    r.scatterSe = glm::sqrt(glm::max(s2 / double(n) - r.scatter * r.scatter, 0.0) / double(n));
    r.passSe = glm::sqrt(glm::max(p2 / double(n) - r.pass * r.pass, 0.0) / double(n));
    const bool linear = m.type == kTrLinear;
    const int diracs = linear ? 1 : int(m.a.z);
    for (int c = 0; c < 3; ++c) {
        for (int i = 0; i < diracs; ++i) {
            double tau = linear ? m.a.x : m.a.x + (i + 0.5) / diracs * (m.a.y - m.a.x);
            if (tau < double(sigmaT[c]) * l)
                r.scatterTrue[c] += double(sigmaS[c]) / sigmaT[c] * f(tau / sigmaT[c]) / diracs;
        }
        r.passTrue[c] = trForm(m, kFormSurfaceMedium, sigmaT[c] * l);
    }
    return r;
}

int worstZ(const DiracMeans& r, double& z) {
    z = 0.0;
    for (int c = 0; c < 3; ++c) {
        z = std::max(z, std::abs(r.scatter[c] - r.scatterTrue[c]) / std::max(r.scatterSe[c], 1e-12));
        z = std::max(z, std::abs(r.pass[c] - r.passTrue[c]) / std::max(r.passSe[c], 1e-12));
    }
    return 0;
}

}  // namespace

// Chromatic media: the channels' Diracs fall at different distances, so the flight is shared by
// channels as a one-sample mixture. Z-tests of 2 models x 2 segment lengths x 6 means, Sidak at
// 1e-3 overall (|Z| < 4.0); sampling noise only (the weights are bounded).
TEST(FreeFlight, DiracSegmentWeightsMatchTheCollisionAndPassingProbabilities) {
    const glm::vec3 sigmaT(0.5f, 0.8f, 1.3f), sigmaS(0.4f, 0.5f, 1.0f);
    uint32_t seed = 7;
    for (const NamedModel& nm : models()) {
        if (!trModelIsDirac(nm.model)) continue;
        for (float l : {0.9f, 3.0f}) {
            double z = 0.0;
            worstZ(diracMeans(nm.model, sigmaT, sigmaS, l, true, seed++), z);
            EXPECT_LT(z, 4.0) << nm.name << ", l = " << l;
        }
        // Positive control at the longer segment (every Dirac of every channel inside).
        double z = 0.0;
        worstZ(diracMeans(nm.model, sigmaT, sigmaS, 3.0f, false, seed++), z);
        EXPECT_GT(z, 4.0) << nm.name << ": the test cannot see weights that ignore the other channels";
    }
    // Grey media (the scene's): every channel shares the Dirac, scattering weight sigma_s / sigma_t.
    float t = 0.0f;
    glm::vec3 w(0.0f);
    ASSERT_TRUE(sampleDiracFlight(trSimple(kTrLinear, glm::vec4(0.75f, 0, 0, 0)), glm::vec3(0.5f), glm::vec3(0.5f), 2.0f,
                                  0.3f, 0.6f, t, w));
    EXPECT_FLOAT_EQ(t, 1.5f);
    EXPECT_FLOAT_EQ(w.x, 1.0f);
}
