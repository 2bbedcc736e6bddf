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

namespace telescope::test {

namespace {
// P(|T| > t) for Student's t with nu degrees of freedom: 1 - 2 int_0^t pdf, Simpson's rule.
double studentTwoSidedTail(double t, double nu) {
    const double logc = std::lgamma(0.5 * (nu + 1.0)) - std::lgamma(0.5 * nu) - 0.5 * std::log(nu * M_PI);
    auto pdf = [&](double x) { return std::exp(logc - 0.5 * (nu + 1.0) * std::log1p(x * x / nu)); };
    const int n = 4000;  // even
    const double h = t / n;
    double sum = pdf(0.0) + pdf(t);
    for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * pdf(i * h);
    return 1.0 - 2.0 * sum * h / 3.0;
}
}  // namespace

double sidakStudentThreshold(double alpha, size_t tests, double dof) {
    const double one = 1.0 - std::pow(1.0 - alpha, 1.0 / double(tests));
    double lo = 0.0, hi = 1.0;
    while (studentTwoSidedTail(hi, dof) > one) hi *= 2.0;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (studentTwoSidedTail(mid, dof) > one ? lo : hi) = mid;
    }
    return hi;
}

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
