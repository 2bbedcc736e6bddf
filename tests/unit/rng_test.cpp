// Independence of the random streams (shaders/shared/rng.h; the header runs unchanged in the
// shaders, so testing it on the CPU tests the device's numbers bit for bit).
//
// A render gives every (pixel, sample index, seed) its own PCG32 stream. Neighbouring pixels
// share the increment and differ in the state; neighbouring samples of one pixel share the
// starting state and differ only in the increment, a pattern known to correlate PCG streams when
// the increments are close. Over 10^6 pairs of neighbouring streams, for each of the first four
// draws, and over 10^6 consecutive draws of one stream:
//   - Pearson correlation: Z = r sqrt(n) is standard normal for independent uniforms;
//   - chi-square of the 2-D projection on a 32 x 32 grid (1023 degrees of freedom), turned into
//     a standard normal deviate by the Wilson-Hilferty cube root.
// The 18 statistics of each of two seeds (36) share one Sidak threshold for a family-wise
// false-alarm rate of 1e-3 (for seeds drawn at random; these are fixed, so the test repeats). Positive control:
// the same family rejects streams that differ only in an unhashed increment (2 s + 1), the weak
// pattern the hashing in rngCreate() exists to avoid.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "shared/rng.h"

using namespace telescope::shader;

namespace {

constexpr int kPairs = 1000000;
constexpr int kGrid = 32;
constexpr int kStatisticsPerSeed = 18;  // (2 pairings x 4 draws + consecutive draws) x 2 statistics
constexpr int kSeeds = 2;
constexpr double kFamilyAlpha = 1e-3;   // over both seeds: 36 statistics

double normalUpperQuantile(double p) {
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

// Two-sided threshold on |Z| for one of the kSeeds x kStatisticsPerSeed tests.
double threshold() {
    const double perTest = 1.0 - std::pow(1.0 - kFamilyAlpha, 1.0 / (kSeeds * kStatisticsPerSeed));
    return normalUpperQuantile(perTest / 2.0);
}

struct PairStatistics {
    double correlationZ = 0.0;
    double chiSquareZ = 0.0;
};

PairStatistics pairStatistics(const std::vector<float>& a, const std::vector<float>& b) {
    const double n = double(a.size());
    double sa = 0, sb = 0, sab = 0, saa = 0, sbb = 0;
    std::vector<double> cells(kGrid * kGrid, 0.0);
    for (size_t i = 0; i < a.size(); ++i) {
        const double x = a[i] - 0.5, y = b[i] - 0.5;
        sa += x, sb += y, sab += x * y, saa += x * x, sbb += y * y;
        cells[size_t(a[i] * kGrid) * kGrid + size_t(b[i] * kGrid)] += 1.0;
    }
    const double cov = sab / n - (sa / n) * (sb / n);
    const double r = cov / std::sqrt((saa / n - (sa / n) * (sa / n)) * (sbb / n - (sb / n) * (sb / n)));
    const double expected = n / double(kGrid * kGrid), dof = kGrid * kGrid - 1.0;
    double chi2 = 0.0;
    for (double c : cells) chi2 += (c - expected) * (c - expected) / expected;
    PairStatistics s;
    s.correlationZ = r * std::sqrt(n);
    s.chiSquareZ = (std::cbrt(chi2 / dof) - (1.0 - 2.0 / (9.0 * dof))) / std::sqrt(2.0 / (9.0 * dof));
    return s;
}

// A stream source: (pixel, sample index) -> the stream's first draws.
using StreamDraws = std::function<void(uint32_t pixel, uint32_t sample, float* draws, int count)>;

StreamDraws telescopeStreams(uint32_t seed) {
    return [seed](uint32_t pixel, uint32_t sample, float* draws, int count) {
        Rng rng = rngCreate(pixel, sample, seed);
        for (int d = 0; d < count; ++d) draws[d] = rngNext(rng);
    };
}

// The weak pattern: one starting state per pixel, streams told apart by the increment 2 s + 1 only.
StreamDraws incrementOnlyStreams() {
    return [](uint32_t pixel, uint32_t sample, float* draws, int count) {
        Rng rng;
        rng.state = pcgHash(pixel);
        rng.inc = (sample << 1u) | 1u;
        for (int d = 0; d < count; ++d) draws[d] = rngNext(rng);
    };
}

struct FamilyResult {
    double worstZ = 0.0;
    std::string worst;
};

// The kStatisticsPerSeed tests on one stream source.
FamilyResult streamFamily(const StreamDraws& streams) {
    FamilyResult result;
    auto record = [&](const std::string& what, const PairStatistics& s) {
        for (auto [name, z] : {std::pair<const char*, double>{"correlation", s.correlationZ}, {"chi-square", s.chiSquareZ}})
            if (std::abs(z) > result.worstZ) {
                result.worstZ = std::abs(z);
                result.worst = what + " " + name + ": Z = " + std::to_string(z);
            }
    };
    constexpr int kDraws = 4;
    std::vector<std::vector<float>> pa(kDraws, std::vector<float>(kPairs)), pb = pa, sa = pa, sb = pa;
    float d1[kDraws], d2[kDraws];
    for (int i = 0; i < kPairs; ++i) {
        // Neighbouring pixels (one row: pixel indices 2i, 2i + 1), sample 3.
        streams(2u * i, 3u, d1, kDraws);
        streams(2u * i + 1u, 3u, d2, kDraws);
        for (int d = 0; d < kDraws; ++d) pa[d][i] = d1[d], pb[d][i] = d2[d];
        // Neighbouring samples 2i, 2i + 1 of pixel 12345.
        streams(12345u, 2u * i, d1, kDraws);
        streams(12345u, 2u * i + 1u, d2, kDraws);
        for (int d = 0; d < kDraws; ++d) sa[d][i] = d1[d], sb[d][i] = d2[d];
    }
    for (int d = 0; d < kDraws; ++d) {
        record("neighbouring pixels, draw " + std::to_string(d), pairStatistics(pa[d], pb[d]));
        record("neighbouring samples, draw " + std::to_string(d), pairStatistics(sa[d], sb[d]));
    }
    // Consecutive draws of one long stream.
    std::vector<float> a(kPairs), b(kPairs);
    std::vector<float> all(2 * size_t(kPairs));
    streams(777u, 5u, all.data(), int(all.size()));
    for (int i = 0; i < kPairs; ++i) a[i] = all[2 * i], b[i] = all[2 * i + 1];
    record("consecutive draws", pairStatistics(a, b));
    return result;
}

}  // namespace

TEST(Rng, NeighbouringStreamsAndConsecutiveDrawsAreIndependent) {
    const double t = threshold();
    for (uint32_t seed : {1u, 0x9e3779b9u}) {
        const FamilyResult r = streamFamily(telescopeStreams(seed));
        EXPECT_LT(r.worstZ, t) << "seed " << seed << ": " << r.worst << " (threshold " << t << ")";
    }
}

TEST(Rng, IncrementOnlyStreamsFailTheSameTest) {
    const FamilyResult r = streamFamily(incrementOnlyStreams());
    EXPECT_GT(r.worstZ, threshold()) << r.worst;
    std::printf("increment-only streams: %s\n", r.worst.c_str());
}

TEST(Rng, DrawsAreInTheHalfOpenUnitInterval) {
    // 24 bits of the word: 0 is reachable, 1 is not (so -log(1 - u) is finite).
    Rng rng = rngCreate(1, 2, 3);
    float lo = 1.0f, hi = 0.0f;
    for (int i = 0; i < 1 << 20; ++i) {
        const float u = rngNext(rng);
        lo = std::min(lo, u), hi = std::max(hi, u);
    }
    EXPECT_GE(lo, 0.0f);
    EXPECT_LT(hi, 1.0f);
    EXPECT_LT(lo, 1e-5f);
    EXPECT_GT(hi, 1.0f - 1e-5f);
}
