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
    // A ratio of areas 1 - 2^-30: r' and r are equal in float, the difference is not zero.
    const float logStep = float(std::log1p(-std::ldexp(1.0, -30)));
    EXPECT_LT(logStep, 0.0f);
    const double eps = std::ldexp(1.0, -30);
    // At the centre: 3 (r^2/r'^2 - 1) / (pi r^2) = 3 eps / (pi r^2) to first order.
    float diff = kernelDifference(kKernelCone, 0.0f, 1.0f, logStep);
    EXPECT_NEAR(diff, 3.0 * eps / M_PI, 1e-5 * 3.0 * eps / M_PI);
}

PhotonLevels defaultLevels() { return PhotonLevels{0.7f, float(std::log(std::sqrt(0.5))), 3u, 20u}; }

TEST(PhotonLevels, RadiiPassesAndPmf) {
    const PhotonLevels l = defaultLevels();
    EXPECT_NEAR(std::exp(photonLevelLogRadius2(l, 4)), 0.25, 1e-6);  // r_k^2 = r_b^2 2^(-k/2)
    EXPECT_EQ(photonBlockPasses(l, 0), 1u);
    EXPECT_EQ(photonBlockPasses(l, 5), 243u);
    EXPECT_EQ(photonBlockPasses(l, 19), 1162261467u);
    // p(k) = r q^k / (1 - q^K) sums to one over k < K.
    double sum = 0.0, passes = 0.0;
    for (uint32_t k = 0; k < l.cap; ++k) {
        sum += photonLevelProbability(l, k);
        passes += photonLevelProbability(l, k) * photonBlockPasses(l, k);
    }
    EXPECT_NEAR(sum, 1.0, 1e-5);
    EXPECT_NEAR(photonLevelProbability(l, 2), 0.7 * 0.09 / (1.0 - std::pow(0.3, 20)), 1e-7);
    // Expected passes per sample: (1 - q) / (1 - q m) = 7 untruncated; the cap removes 0.9^20 of it.
    EXPECT_NEAR(passes, 7.0 * (1.0 - std::pow(0.9, 20)), 1e-3);
}

// The sampler against its pmf: chi-square over all levels of a short cap and the default one.
TEST(PhotonLevels, SamplerMatchesThePmf) {
    for (PhotonLevels l : {defaultLevels(), PhotonLevels{0.4f, -0.5f, 2u, 6u}}) {
        const int n = 400000;
        std::vector<double> counts(l.cap, 0.0);
        Rng rng = rngCreate(3, 5, 7);
        for (int i = 0; i < n; ++i) {
            float u1 = rngNext(rng), u2 = rngNext(rng);
            uint32_t k = photonLevelSample(l, u1, u2);
            ASSERT_LT(k, l.cap);
            counts[k] += 1.0;
        }
        // Bins with at least 20 expected draws; the rest pooled into the last bin.
        double chi2 = 0.0, pooledCount = 0.0, pooledP = 0.0;
        int bins = 0;
        for (uint32_t k = 0; k < l.cap; ++k) {
            double p = photonLevelProbability(l, k);
            if (p * n < 20.0) {
                pooledCount += counts[k];
                pooledP += p;
                continue;
            }
            chi2 += (counts[k] - p * n) * (counts[k] - p * n) / (p * n);
            ++bins;
        }
        if (pooledP * n > 0.0) {
            chi2 += (pooledCount - pooledP * n) * (pooledCount - pooledP * n) / std::max(pooledP * n, 1.0);
            ++bins;
        }
        // chi2 quantile 1 - 1e-4 for <= 12 degrees of freedom is below 38.
        EXPECT_LT(chi2, 38.0) << bins << " bins, cap " << l.cap;
    }
}

TEST(PhotonLevels, ASkewedSamplerFailsTheSameTest) {
    // The control: levels drawn with r = 0.66 tested against the pmf with r = 0.7.
    PhotonLevels wrong = defaultLevels();
    wrong.r = 0.66f;
    const PhotonLevels l = defaultLevels();
    const int n = 400000;
    std::vector<double> counts(l.cap, 0.0);
    Rng rng = rngCreate(3, 5, 7);
    for (int i = 0; i < n; ++i) {
        float u1 = rngNext(rng), u2 = rngNext(rng);
        counts[photonLevelSample(wrong, u1, u2)] += 1.0;
    }
    double chi2 = 0.0;
    for (uint32_t k = 0; k < 6; ++k) {
        double p = photonLevelProbability(l, k);
        chi2 += (counts[k] - p * n) * (counts[k] - p * n) / (p * n);
    }
    EXPECT_GT(chi2, 38.0);
}

TEST(PhotonLevels, SamplerResolvesTheDeepLevels) {
    // 48 random bits: P(level >= k) = (q^k - q^K) / (1 - q^K) holds down to the cap, where one
    // float's 24 bits would stop at level 13 (0.3^14 < 2^-24), 7 levels short of K = 20.
    const PhotonLevels l = defaultLevels();
    const double q = 0.3, qK = std::pow(q, 20);
    for (uint32_t k : {1u, 5u, 13u, 17u, 19u}) {
        // v just below the tail probability of k draws level k; just above it, level k - 1.
        const double tail = (std::pow(q, k) - qK) / (1.0 - qK);
        auto draw = [&](double v) {
            // v = (1 - u1) - u2 2^-24, split into the two 24-bit draws
            double u1 = 1.0 - std::ceil(v * 16777216.0) / 16777216.0;
            double u2 = (std::ceil(v * 16777216.0) - v * 16777216.0);
            return photonLevelSample(l, float(u1), float(u2));
        };
        EXPECT_EQ(draw(tail * 0.999), k) << "k = " << k;
        EXPECT_EQ(draw(tail * 1.001), k - 1) << "k = " << k;
    }
    EXPECT_EQ(photonLevelSample(l, 0.0f, 0.0f), 0u);
    EXPECT_EQ(photonLevelSample(l, 1.0f - std::ldexp(1.0f, -24), 1.0f - std::ldexp(1.0f, -24)), l.cap - 1);
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

TEST(PhotonGridCells, CellsLessThanEightApartNeverShareABucket) {
    // The gathers read each bucket once because of this (photon_gather.glsl bucketSlice), also at
    // the smallest table and around the coordinates' sign change and the clamp.
    Rng rng = rngCreate(4, 5, 6);
    uint32_t near = 0;
    for (int i = 0; i < 4000; ++i) {
        const int big = 1 << 30;
        glm::ivec3 c(int(rngNextUint(rng) % 64u) - 32, int(rngNextUint(rng) % 64u) - 32, int(rngNextUint(rng)));
        if (i % 4 == 0) c.z = big - int(rngNextUint(rng) % 16u);
        glm::ivec3 o(int(rngNextUint(rng) % 15u) - 7, int(rngNextUint(rng) % 15u) - 7, int(rngNextUint(rng) % 15u) - 7);
        if (o == glm::ivec3(0)) continue;
        for (uint32_t table : {512u, 4096u, 1u << 22})
            ASSERT_NE(gridHash(c, table), gridHash(c + o, table)) << "cell " << i << ", table " << table;
        // Locality: a neighbour in the same block of 8x8x8 takes a bucket of the same 512.
        if ((c.x & 7) != 7) {
            const uint32_t a = gridHash(c, 1u << 22), b = gridHash(c + glm::ivec3(1, 0, 0), 1u << 22);
            near += a / 512u == b / 512u;
        }
    }
    EXPECT_GT(near, 3000u);
}

TEST(PhotonDirection, OctahedralRoundTrip) {
    Rng rng = rngCreate(9, 9, 9);
    for (int i = 0; i < 10000; ++i) {
        glm::vec3 d = uniformDirection(rngNext(rng), rngNext(rng));
        glm::vec3 e = decodeDirection(encodeDirection(d));
        ASSERT_GT(glm::dot(d, e), 0.99999f) << i;
    }
}
