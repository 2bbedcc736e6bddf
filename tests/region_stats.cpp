#include "region_stats.h"

#include <algorithm>
#include <cstdio>

#include <fmt/format.h>
#include <gtest/gtest.h>

namespace telescope::test {

std::vector<RegionMean> blockMeans(const Film& film, uint32_t block, uint32_t channel) {
    std::vector<RegionMean> out;
    for (uint32_t by = 0; by + block <= film.height(); by += block)
        for (uint32_t bx = 0; bx + block <= film.width(); bx += block) {
            RegionMean r;
            double n = double(block) * block;
            for (uint32_t y = by; y < by + block; ++y)
                for (uint32_t x = bx; x < bx + block; ++x) {
                    size_t i = size_t(y) * film.width() + x;
                    r.mean += film.mean(channel, i) / n;
                    r.variance += film.varianceOfMean(i) / (n * n);
                }
            out.push_back(r);
        }
    return out;
}

RegionMean imageMean(const Film& film, uint32_t channel) {
    RegionMean r;
    const double n = double(film.pixelCount());
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        r.mean += film.mean(channel, i) / n;
        r.variance += film.varianceOfMean(i) / (n * n);
    }
    return r;
}

namespace {
// Inverse of the standard normal upper tail by bisection on erfc (accurate and dependency-free).
double normalUpperQuantile(double p) {
    double lo = 0.0, hi = 40.0;
    for (int i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        if (0.5 * std::erfc(mid / std::sqrt(2.0)) > p) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

void record(ZSummary& s, double z, double threshold, size_t region, int channel) {
    ++s.tests;
    if (std::abs(z) > threshold) ++s.failing;
    if (std::abs(z) > s.maxAbsZ) {
        s.maxAbsZ = std::abs(z);
        s.worst = fmt::format("region {} channel {}: Z = {:.2f}", region, channel, z);
    }
}
}  // namespace

double sidakThreshold(double alpha, size_t tests) {
    double perTest = 1.0 - std::pow(1.0 - alpha, 1.0 / double(tests));
    return normalUpperQuantile(perTest / 2.0);
}

namespace {
// Regularised incomplete beta I_x(a, b) by its continued fraction (modified Lentz), with the
// symmetry I_x(a, b) = 1 - I_{1-x}(b, a) where the fraction converges slowly.
double incompleteBeta(double a, double b, double x) {
    if (x <= 0.0) return 0.0;
    if (x >= 1.0) return 1.0;
    if (x > (a + 1.0) / (a + b + 2.0)) return 1.0 - incompleteBeta(b, a, 1.0 - x);
    const double tiny = 1e-300;
    auto guard = [tiny](double v) { return std::abs(v) < tiny ? tiny : v; };
    double c = 1.0, d = 1.0 / guard(1.0 - (a + b) * x / (a + 1.0)), h = d;
    for (int m = 1; m <= 500; ++m) {
        const double m2 = 2.0 * m;
        double num = m * (b - m) * x / ((a - 1.0 + m2) * (a + m2));
        d = 1.0 / guard(1.0 + num * d);
        c = guard(1.0 + num / c);
        h *= d * c;
        num = -(a + m) * (a + b + m) * x / ((a + m2) * (a + 1.0 + m2));
        d = 1.0 / guard(1.0 + num * d);
        c = guard(1.0 + num / c);
        const double step = d * c;
        h *= step;
        if (std::abs(step - 1.0) < 1e-15) break;
    }
    const double front = std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x));
    return front * h / a;
}

// Upper tail of Student's t with nu degrees of freedom: P(T > t) = I_{nu / (nu + t^2)}(nu / 2, 1 / 2) / 2.
double studentUpperTail(double t, double nu) { return 0.5 * incompleteBeta(0.5 * nu, 0.5, nu / (nu + t * t)); }
}  // namespace

double sidakThresholdT(double alpha, size_t tests, double dof) {
    const double perTest = 1.0 - std::pow(1.0 - alpha, 1.0 / double(tests));
    double lo = 0.0, hi = 1e3;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (studentUpperTail(mid, dof) > perTest / 2.0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

ZSummary compareBlocksAndImage(const Film& film, const std::vector<RegionMean>& referenceBlocks,
                               const RegionMean& referenceImage, uint32_t block, double alpha) {
    const std::vector<RegionMean> blocks = blockMeans(film, block);
    const double threshold = sidakThreshold(alpha, (blocks.size() + 1) * 3);
    ZSummary z = compareRegions(blocks, referenceBlocks, threshold);
    const ZSummary whole = compareRegions({imageMean(film)}, {referenceImage}, threshold);
    z.tests += whole.tests;
    z.failing += whole.failing;
    if (whole.maxAbsZ > z.maxAbsZ) {
        z.maxAbsZ = whole.maxAbsZ;
        z.worst = "image mean " + whole.worst.substr(whole.worst.find("channel"));
    }
    z.threshold = threshold;
    return z;
}

ZSummary compareRegions(const std::vector<RegionMean>& a, const std::vector<RegionMean>& b, double threshold) {
    ZSummary s;
    for (size_t i = 0; i < a.size() && i < b.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            double var = a[i].variance[c] + b[i].variance[c];
            double diff = a[i].mean[c] - b[i].mean[c];
            if (var > 0.0) record(s, diff / std::sqrt(var), threshold, i, c);
            else if (diff != 0.0) record(s, INFINITY, threshold, i, c);  // noiseless yet different
        }
    return s;
}

ZSummary compareToValue(const std::vector<RegionMean>& a, glm::dvec3 value, double threshold) {
    ZSummary s;
    for (size_t i = 0; i < a.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            double diff = a[i].mean[c] - value[c];
            if (a[i].variance[c] > 0.0) record(s, diff / std::sqrt(a[i].variance[c]), threshold, i, c);
            else record(s, std::abs(diff) <= 1e-6 * std::abs(value[c]) ? 0.0 : INFINITY, threshold, i, c);  // noiseless
        }
    return s;
}

}  // namespace telescope::test

namespace telescope::test {

SignTestBounds sidakSignTest(double alpha, size_t tests, uint32_t n) {
    const double one = 1.0 - std::pow(1.0 - alpha, 1.0 / double(tests));
    // Largest k with 2 P(X < k) <= one.
    SignTestBounds b;
    double cdf = 0.0;  // P(X < k)
    for (uint32_t k = 0; k <= n / 2; ++k) {
        const double pk = std::exp(std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) - n * std::log(2.0));
        if (2.0 * (cdf + pk) > one) {
            b.k = k;
            b.rate = 2.0 * cdf;
            return b;
        }
        cdf += pk;
    }
    b.k = n / 2;
    b.rate = 2.0 * cdf;
    return b;
}

}  // namespace telescope::test

namespace telescope::test {

BatchVerdict compareBatchMeans(const std::vector<std::vector<glm::dvec3>>& batches,
                               const std::vector<RegionMean>& reference, uint32_t channels, double alpha,
                               const char* label) {
    BatchVerdict v;
    if (batches.empty() || batches.size() != reference.size()) {
        ADD_FAILURE() << label << ": " << batches.size() << " regions of batches against " << reference.size();
        return v;
    }
    const double n = double(batches[0].size());
    v.tests = batches.size() * channels;
    v.limit = sidakThresholdT(alpha, v.tests, n - 1.0);
    for (size_t r = 0; r < batches.size(); ++r)
        for (uint32_t c = 0; c < channels; ++c) {
            double mean = 0.0, var = 0.0;
            for (const glm::dvec3& m : batches[r]) mean += m[c] / n;
            for (const glm::dvec3& m : batches[r]) var += (m[c] - mean) * (m[c] - mean) / (n - 1.0);
            const double t = (mean - reference[r].mean[c]) / std::sqrt(var / n + reference[r].variance[c]);
            v.worstT = std::max(v.worstT, std::abs(t));
            if (!(std::abs(t) <= v.limit)) ++v.failures;
            std::printf("%s region %2zu %c: %.5f vs %.5f (t %+.2f)\n", label, r, "RGB"[c], mean, reference[r].mean[c], t);
        }
    std::printf("%s: %zu of %zu region-channel tests fail (t limit %.2f, worst |t| %.2f)\n", label, v.failures, v.tests,
                v.limit, v.worstT);
    return v;
}

}  // namespace telescope::test
