// Reconstruction filters on the device (shaders/shared/pixel_filter.h, docs/TESTING.md).
//
// A vertical edge: an emitter (Le = 1) fills the half of the view on one side of the optical axis,
// black on the other, so the edge falls on a pixel boundary and the filtered image of column i is
// the filter's tail mass beyond the edge, int_{c_i}^{2} f / F with c_i the edge's offset from
// the column centre (computed here by quadrature of the profile, not by the shader's sampler).
// Each filter's render matches it per column (8 rows x 4096 spp; Z-test, one Sidak family of 32
// columns at 1e-3 per render; the weights are bounded, so the variance is finite). Positive
// control: the tent render, which is what these filters silently were before, fails the test of
// every wide filter.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "region_stats.h"
#include "render_harness.h"
#include "shared/pixel_filter.h"

using namespace telescope;
using namespace telescope::test;
using nlohmann::json;

namespace {

constexpr uint32_t kWidth = 32, kHeight = 8;
constexpr uint64_t kSpp = 4096;

Scene edgeScene(const std::string& filter) {
    std::ifstream in(sourcePath("scenes/absorbing-slab.json"));
    json j = json::parse(in);
    json emitter = j["primitives"][2];
    emitter["transform"]["position"] = {-1.0, 0.0, 1.0};
    emitter["transform"]["scale"] = {2.0, 1.0, 4.0};  // x in [-2, 0], y in [-2, 2]
    j["primitives"] = json::array({emitter});
    j["media"] = json::array();
    j["integrator"].erase("transmittance_estimator");
    j["integrator"]["max_bounces"] = 1;  // emitters only
    return loadSceneFromString(j.dump(), "edge", sourcePath("scenes"),
                               {{"camera.resolution", fmt::format("[{},{}]", kWidth, kHeight)},
                                {"camera.reconstruction_filter", "\"" + filter + "\""}});
}

// The 1-D profile of every filter the renderer has, and its support radius.
double profile(const std::string& filter, double x) {
    using namespace telescope::shader;
    if (filter == "box") return std::abs(x) < 0.5 ? 1.0 : 0.0;
    if (filter == "tent") return std::max(0.0, 1.0 - std::abs(x));
    const uint type = filter == "gaussian" ? kFilterGaussian
                      : filter == "mitchell_netravali" ? kFilterMitchellNetravali
                      : filter == "catmull_rom" ? kFilterCatmullRom
                                                : kFilterLanczos;
    return filterProfile(type, float(x));
}

// int_c^2 f / int_-2^2 f by Simpson's rule.
double tailMass(const std::string& filter, double c) {
    auto integrate = [&](double a, double b) {
        if (b <= a) return 0.0;
        const int n = 20000;
        const double h = (b - a) / n;
        double s = profile(filter, a) + profile(filter, b);
        for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * profile(filter, a + i * h);
        return s * h / 3.0;
    };
    return integrate(std::max(c, -2.0), 2.0) / integrate(-2.0, 2.0);
}

// Expected value of every column: the lit side is where the camera's image x maps to world x < 0.
std::vector<double> expectedColumns(const Scene& scene, const std::string& filter) {
    std::vector<double> out;
    const bool litRight = scene.camera.right.x < 0.0f;
    for (uint32_t i = 0; i < kWidth; ++i) {
        const double c = 0.5 * kWidth - (i + 0.5);  // the edge's offset from the column centre
        out.push_back(litRight ? tailMass(filter, c) : 1.0 - tailMass(filter, c));
    }
    return out;
}

// Per-column Z-tests (channel R; the emitter is grey) against `expected`.
ZSummary compareColumns(const Film& film, const std::vector<double>& expected) {
    std::vector<RegionMean> columns(kWidth);
    for (uint32_t y = 0; y < kHeight; ++y)
        for (uint32_t x = 0; x < kWidth; ++x) {
            const size_t i = size_t(y) * kWidth + x;
            columns[x].mean += film.mean(shader::kChannelEstimate, i) / double(kHeight);
            columns[x].variance += film.varianceOfMean(i) / double(kHeight * kHeight);
        }
    ZSummary z;
    z.threshold = sidakThreshold(1e-3, kWidth);
    for (uint32_t x = 0; x < kWidth; ++x) {
        const double diff = columns[x].mean.x - expected[x];
        const double zx = columns[x].variance.x > 0.0 ? diff / std::sqrt(columns[x].variance.x)
                                                      : (std::abs(diff) <= 1e-6 ? 0.0 : INFINITY);
        ++z.tests;
        if (std::abs(zx) > z.threshold) ++z.failing;
        if (std::abs(zx) > z.maxAbsZ) {
            z.maxAbsZ = std::abs(zx);
            z.worst = fmt::format("column {}: {:.4f} vs {:.4f}, Z = {:.2f}", x, columns[x].mean.x, expected[x], zx);
        }
    }
    return z;
}

class FilterRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

}  // namespace

TEST_F(FilterRender, EveryFilterReproducesTheFilteredEdgeAndTentDoesNotStandIn) {
    const Film tent = renderFilm(edgeScene("tent"), kSpp, 7);
    uint32_t seed = 8;
    for (const std::string filter : {"tent", "gaussian", "mitchell_netravali", "catmull_rom", "lanczos"}) {
        const Scene scene = edgeScene(filter);
        const std::vector<double> expected = expectedColumns(scene, filter);
        const Film film = filter == "tent" ? tent : renderFilm(scene, kSpp, seed++);
        EXPECT_EQ(film.nonFiniteSamples(), 0u) << filter;
        const ZSummary z = compareColumns(film, expected);
        EXPECT_EQ(z.failing, 0u) << filter << ": " << z.worst << " (threshold " << z.threshold << ")";
        if (filter == "tent") continue;
        const ZSummary control = compareColumns(tent, expected);
        std::printf("%s: worst %s; tent in its place: %zu of %zu columns fail, worst %s\n", filter.c_str(), z.worst.c_str(),
                    control.failing, control.tests, control.worst.c_str());
        EXPECT_GT(control.failing, 0u) << "the tent filter passes the test of " << filter;
    }
}
