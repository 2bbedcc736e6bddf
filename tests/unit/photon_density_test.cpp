// Photon density estimation (shaders/shared/photon_density.h), run on the CPU exactly as the
// shaders run it: kernels, closed-form kernel differences, levels and their sampler, grid cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "shared/photon_density.h"
#include "shared/rng.h"

using namespace telescope::shader;

namespace {

glm::vec3 uniformDirection(float u1, float u2) {
    float z = 1.0f - 2.0f * u1, s = std::sqrt(std::max(0.0f, 1.0f - z * z)), phi = 2.0f * float(M_PI) * u2;
    return glm::vec3(s * std::cos(phi), s * std::sin(phi), z);
}

LevelPmf powerLaw(float alpha) { return LevelPmf{kPmfPowerLaw, 0.0f, alpha}; }
LevelPmf geometric(float r) { return LevelPmf{kPmfGeometric, r, 0.0f}; }

// Integral of W over the disk by the midpoint rule in d.
double integrateOverDisk(uint kernel, double r) {
    const int n = 20000;
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
        double d = (i + 0.5) / n * r;
        sum += kernelWeight(kernel, float(d * d), float(r * r)) * 2.0 * M_PI * d * (r / n);
    }
    return sum;
}

double exactKernel(uint kernel, double d, double r) {
    if (d >= r) return 0.0;
    double t = d / r;
    double shape = kernel == kKernelUniform ? 1.0 : kernel == kKernelEpanechnikov ? 2.0 * (1.0 - t * t) : 3.0 * (1.0 - t);
    return shape / (M_PI * r * r);
}

}  // namespace

TEST(PhotonKernel, EachKernelIntegratesToOne) {
    for (uint k : {kKernelCone, kKernelUniform, kKernelEpanechnikov})
        for (double r : {1e-3, 0.5, 20.0}) EXPECT_NEAR(integrateOverDisk(k, r), 1.0, 1e-3) << "kernel " << k << " r " << r;
}

TEST(PhotonKernel, DifferenceMatchesDoublePrecisionForModerateSteps) {
    for (uint k : {kKernelCone, kKernelUniform, kKernelEpanechnikov}) {
        for (double q2 : {0.5, 0.9, 0.99}) {
            const double r = 0.3, rp = r * std::sqrt(q2);
            for (double d : {0.0, 0.05, 0.2, 0.27, 0.29}) {
                double exact = exactKernel(k, d, rp) - exactKernel(k, d, r);
                float got = kernelDifference(k, float(d * d), float(r * r), float(std::log(q2)));
                EXPECT_NEAR(got, exact, 2e-5 * (std::abs(exact) + 1.0 / (r * r))) << k << " " << q2 << " " << d;
            }
        }
    }
}

TEST(PhotonKernel, DifferenceKeepsItsSizeWhenTheRadiiAgreeInFloat) {
    // Level j = 2^40: r_{j+1} and r_j are equal in float, the difference is not zero.
    const LevelPmf pmf = powerLaw(2.0f / 3.0f);
    const float j = std::ldexp(1.0f, 40);
    const float logStep = levelLogStep2(pmf, j);
    EXPECT_LT(logStep, 0.0f);
    const double eps = -(2.0 / 3.0 - 1.0) * std::log1p(1.0 / std::ldexp(1.0, 40));
    EXPECT_NEAR(logStep, -eps, 1e-6 * eps);
    // At the centre: 3 (r^2/r'^2 - 1) / (pi r^2) = 3 eps / (pi r^2) to first order.
    float diff = kernelDifference(kKernelCone, 0.0f, 1.0f, logStep);
    EXPECT_NEAR(diff, 3.0 * eps / M_PI, 1e-5 * 3.0 * eps / M_PI);
    // Divided by p(j) it stays finite and positive.
    float p = levelProbabilityFrom(pmf, j, 1.0f);
    EXPECT_GT(p, 0.0f);
    EXPECT_TRUE(std::isfinite(diff / p));
}

TEST(PhotonLevels, PowerLawScheduleAndPmf) {
    const LevelPmf pmf = powerLaw(2.0f / 3.0f);
    // r_j^2 / r_1^2 = j^(alpha-1)
    EXPECT_NEAR(std::exp(levelLogRadius2(pmf, 8.0f, 1.0f)), 0.5, 1e-6);
    // p(j) = j^(alpha-1) - (j+1)^(alpha-1) sums to one, and renormalised to j >= b too.
    for (float b : {1.0f, 5.0f}) {
        double sum = 0.0;
        for (int j = int(b); j < 200000; ++j) sum += levelProbabilityFrom(pmf, float(j), b);
        double tail = std::pow(200000.0 / b, -1.0 / 3.0);
        EXPECT_NEAR(sum + tail, 1.0, 1e-4) << "b = " << b;
    }
    EXPECT_NEAR(levelProbabilityFrom(pmf, 1.0f, 1.0f), 1.0 - std::pow(2.0, -1.0 / 3.0), 1e-6);
}

TEST(PhotonLevels, GeometricScheduleAndPmf) {
    const LevelPmf pmf = geometric(0.65f);
    EXPECT_NEAR(std::exp(levelLogRadius2(pmf, 3.0f, 1.0f)), 0.25, 1e-6);  // r_j = r_1 / sqrt(2)^(j-1)
    EXPECT_NEAR(levelProbabilityFrom(pmf, 4.0f, 2.0f), 0.65 * 0.35 * 0.35, 1e-6);
}

// The sampler against its pmf: chi-square over levels 1..15 and the tail (48 random bits).
TEST(PhotonLevels, SamplerMatchesThePmf) {
    for (LevelPmf pmf : {powerLaw(2.0f / 3.0f), geometric(0.5f)}) {
        for (float b : {1.0f, 3.0f}) {
            const int bins = 15, n = 200000;
            std::vector<double> counts(bins + 1, 0.0);
            Rng rng = rngCreate(3, 5, 7);
            for (int i = 0; i < n; ++i) {
                float u1 = rngNext(rng), u2 = rngNext(rng);
                float j = levelSampleFrom(pmf, b, u1, u2);
                if (j == 0.0f) continue;  // beyond the truncation (probability ~1e-10 here)
                ASSERT_GE(j, b);
                counts[j - b >= float(bins) ? bins : int(j - b)] += 1.0;
            }
            double chi2 = 0.0, tail = 1.0;
            for (int k = 0; k <= bins; ++k) {
                double p = k < bins ? levelProbabilityFrom(pmf, b + float(k), b) : tail;
                tail -= p;
                chi2 += (counts[k] - p * n) * (counts[k] - p * n) / (p * n);
            }
            EXPECT_LT(chi2, 45.0) << "16 bins, 15 dof, p ~ 1e-4";  // chi2(15) 0.9999 quantile ~ 44
        }
    }
}

TEST(PhotonLevels, TruncationOnlyBeyondTheRadiusFloor) {
    const LevelPmf pmf = powerLaw(2.0f / 3.0f);
    // v = 2^-24 gives j ~ 2^72: r_j^2 / r_1^2 = 2^-24 > 2^-32, still corrected.
    EXPECT_GT(levelSampleFrom(pmf, 1.0f, 1.0f - std::ldexp(1.0f, -24), 0.0f), 1e20f);
    // v ~ 2^-40 gives r_j^2 / r_1^2 ~ 2^-40 < 2^-32: truncated.
    EXPECT_EQ(levelSampleFrom(pmf, 1.0f, 1.0f - std::ldexp(1.0f, -24), 1.0f - std::ldexp(1.0f, -16)), 0.0f);
}

TEST(PhotonGridCells, NegativeCoordinatesRoundDown) {
    EXPECT_EQ(gridCell(glm::vec3(-0.1f, 0.1f, -2.5f), 1.0f), glm::ivec3(-1, 0, -3));
    EXPECT_EQ(gridCell(glm::vec3(1e30f, -1e30f, 0.0f), 1e-4f), glm::ivec3(1 << 30, -(1 << 30), 0));
}

TEST(PhotonGridCells, NeighbourhoodCoversTheHalfCellBall) {
    Rng rng = rngCreate(1, 2, 3);
    const float cell = 0.4f, r = 0.2f;
    for (int i = 0; i < 20000; ++i) {
        glm::vec3 x((rngNext(rng) - 0.5f) * 10.0f, (rngNext(rng) - 0.5f) * 10.0f, (rngNext(rng) - 0.5f) * 10.0f);
        glm::vec3 d = uniformDirection(rngNext(rng), rngNext(rng)) * (r * 0.999f * rngNext(rng));
        glm::ivec3 c = gridCell(x + d, cell), low = gridNeighbourhood(x, cell);
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(c, low)) && glm::all(glm::lessThanEqual(c, low + 1)))
            << "point " << i;
    }
}

TEST(PhotonGridCells, HashStaysInTheTable) {
    for (int x = -3; x <= 3; ++x)
        for (int y : {-(1 << 30), -1, 0, 1 << 30}) EXPECT_LT(gridHash(glm::ivec3(x, y, 7), 1024u), 1024u);
}

TEST(PhotonDirection, OctahedralRoundTrip) {
    Rng rng = rngCreate(9, 9, 9);
    for (int i = 0; i < 10000; ++i) {
        glm::vec3 d = uniformDirection(rngNext(rng), rngNext(rng));
        glm::vec3 e = decodeDirection(encodeDirection(d));
        ASSERT_GT(glm::dot(d, e), 0.99999f) << i;
    }
}
