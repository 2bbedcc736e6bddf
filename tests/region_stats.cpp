#include "region_stats.h"

#include <fmt/format.h>

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
