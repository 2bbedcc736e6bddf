// Statistics for testing BSDF routines on the CPU (tests/unit/microfacet_test.cpp):
// a chi-square test of a sampling routine against a density, after Mitsuba 3's habit: directions
// binned in (cos theta, phi) over the whole sphere, the expected count of each bin the density
// integrated over it by a fine midpoint rule, bins expecting fewer than 5 samples pooled, and the
// samples the routine loses (it returns false) compared with the mass the density misses.
#pragma once

#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "shared/lang.h"

namespace telescope::test {

// Upper quantile of chi-square with k degrees of freedom (Wilson-Hilferty), z = normal quantile.
inline double chiSquareUpperQuantile(double k, double z) {
    const double h = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - h + z * std::sqrt(h), 3.0);
}

struct ChiSquareResult {
    double statistic = 0.0;
    int dof = 0;
    double threshold = 0.0;  // at p = 1e-4 (z = 3.719)
    double lostSamples = 0.0, lostExpected = 0.0;
    bool rejected() const { return statistic > threshold; }
    std::string describe() const {
        return fmt::format("chi2 {:.1f} on {} dof (threshold {:.1f}); lost {} samples, expected {:.1f}", statistic, dof,
                           threshold, lostSamples, lostExpected);
    }
};

using SampleFn = std::function<bool(float u1, float u2, glm::vec3& wo)>;
using PdfFn = std::function<double(glm::vec3 wo)>;

// Histogram of n samples against the integral of pdf over each bin (thetaBins in theta over
// [0, pi], phiBins in phi; bins uniform in theta resolve lobes around the poles that bins in
// cos theta squash into one bin).
inline ChiSquareResult chiSquareSphere(const SampleFn& sample, const PdfFn& pdf, uint32_t n, uint32_t seed,
                                       int thetaBins = 32, int phiBins = 64, int sub = 16) {
    const double pi = 3.14159265358979323846, twoPi = 2.0 * pi;
    std::vector<double> observed(size_t(thetaBins) * phiBins, 0.0), expected(observed.size(), 0.0);
    std::mt19937_64 gen(seed);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    double lost = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
        glm::vec3 wo;
        float u1 = uni(gen), u2 = uni(gen);
        if (!sample(u1, u2, wo)) {
            lost += 1.0;
            continue;
        }
        const double z = std::clamp(double(wo.z) / std::max(1e-30, double(glm::length(wo))), -1.0, 1.0);
        double phi = std::atan2(double(wo.y), double(wo.x));
        if (phi < 0.0) phi += twoPi;
        const int ti = std::min(thetaBins - 1, int(std::acos(z) / pi * thetaBins));
        const int pj = std::min(phiBins - 1, int(phi / twoPi * phiBins));
        observed[size_t(ti) * phiBins + pj] += 1.0;
    }
    // Integral of the pdf over each bin: dw = sin theta dtheta dphi.
    double total = 0.0;
    const double dt = pi / thetaBins, dphi = twoPi / phiBins;
    for (int ti = 0; ti < thetaBins; ++ti)
        for (int pj = 0; pj < phiBins; ++pj) {
            double sum = 0.0;
            for (int a = 0; a < sub; ++a) {
                const double t = dt * (ti + (a + 0.5) / sub);
                const double z = std::cos(t), r = std::sin(t);
                for (int b = 0; b < sub; ++b) {
                    const double phi = dphi * (pj + (b + 0.5) / sub);
                    sum += r * pdf(glm::vec3(float(r * std::cos(phi)), float(r * std::sin(phi)), float(z)));
                }
            }
            const double mass = sum * dt * dphi / (sub * sub);
            expected[size_t(ti) * phiBins + pj] = mass * n;
            total += mass;
        }
    // Pool the bins expecting fewer than 5 samples; the lost samples form one more bin.
    ChiSquareResult r;
    r.lostSamples = lost;
    r.lostExpected = std::max(0.0, 1.0 - total) * n;
    std::vector<std::pair<double, double>> cells;  // observed, expected
    double pooledO = 0.0, pooledE = 0.0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] < 5.0) {
            pooledO += observed[i];
            pooledE += expected[i];
        } else {
            cells.push_back({observed[i], expected[i]});
        }
    }
    if (r.lostExpected >= 5.0) cells.push_back({lost, r.lostExpected});
    else {
        pooledO += lost;
        pooledE += r.lostExpected;
    }
    if (pooledE >= 5.0) cells.push_back({pooledO, pooledE});
    else if (pooledO > 0.0 && !cells.empty()) {
        // too little pooled mass for a cell of its own: fold it into the smallest cell
        size_t smallest = 0;
        for (size_t i = 1; i < cells.size(); ++i)
            if (cells[i].second < cells[smallest].second) smallest = i;
        cells[smallest].first += pooledO;
        cells[smallest].second += pooledE;
    }
    for (const auto& [o, e] : cells) r.statistic += (o - e) * (o - e) / e;
    r.dof = int(cells.size()) - 1;
    r.threshold = chiSquareUpperQuantile(std::max(1, r.dof), 3.719);
    return r;
}

// Integral over the sphere of f(w) dw, midpoint rule in (theta, phi) around `axis`: dw = sin theta
// dtheta dphi (steps in theta resolve lobes a few hundredths of a radian wide around the axis; put
// the axis on a narrow lobe).
inline double integrateSphere(const std::function<double(glm::vec3)>& f, int thetaSteps = 4096, int phiSteps = 256,
                              glm::vec3 axis = glm::vec3(0.0f, 0.0f, 1.0f)) {
    const double pi = 3.14159265358979323846;
    const glm::dvec3 n = glm::normalize(glm::dvec3(axis));
    const glm::dvec3 helper = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
    const glm::dvec3 t = glm::normalize(glm::cross(helper, n)), b = glm::cross(n, t);
    const double dt = pi / thetaSteps, dphi = 2.0 * pi / phiSteps;
    double sum = 0.0;
    for (int i = 0; i < thetaSteps; ++i) {
        const double th = dt * (i + 0.5);
        const double z = std::cos(th), r = std::sin(th);
        double ring = 0.0;
        for (int j = 0; j < phiSteps; ++j) {
            const double phi = dphi * (j + 0.5);
            ring += f(glm::vec3(t * (r * std::cos(phi)) + b * (r * std::sin(phi)) + n * z));
        }
        sum += ring * r;
    }
    return sum * dt * dphi;
}

}  // namespace telescope::test
