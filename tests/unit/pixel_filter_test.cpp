// The wide reconstruction filters (shaders/shared/pixel_filter.h), on the CPU exactly as the
// shaders run them. The sampler and its weights must reproduce the filter: for test functions g,
// E_u[w(x) g(x)] = int f g / F, with the expectation over u taken by a fine midpoint rule (so the
// check is deterministic) and the right side by Simpson quadrature of the profile. Positive
// control: the tent offsets with unit weight (what these filters silently rendered as before)
// fail the same check.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "shared/pixel_filter.h"

using namespace telescope::shader;

namespace {

using Fn = std::function<double(double)>;

double simpson(const Fn& f, double a, double b, int n = 200000) {
    const double h = (b - a) / n;
    double s = f(a) + f(b);
    for (int i = 1; i < n; ++i) s += (i % 2 ? 4.0 : 2.0) * f(a + i * h);
    return s * h / 3.0;
}

// int f g / F over [-2, 2], from the profile alone.
double filtered(uint type, const Fn& g) {
    const Fn f = [type](double x) { return double(filterProfile(type, float(x))); };
    return simpson([&](double x) { return f(x) * g(x); }, -2.0, 2.0) / simpson(f, -2.0, 2.0);
}

// E_u[w(x) g(x)] for the sampler (or, for the control, tent offsets of radius 2 with weight 1).
double sampled(uint type, const Fn& g, bool control = false) {
    const int n = 1 << 20;
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
        const float u = (float(i) + 0.5f) / float(n);
        float w;
        const float x = control ? kWideFilterRadius * sampleTent(u) : sampleWideFilter(type, u, w);
        if (control) w = 1.0f;
        s += double(w) * g(double(x));
    }
    return s / n;
}

const uint kWide[] = {kFilterGaussian, kFilterMitchellNetravali, kFilterCatmullRom, kFilterLanczos};

struct TestFunction {
    std::string name;
    Fn g;
};

std::vector<TestFunction> testFunctions() {
    // Steps are the profile of an edge; the offsets cover where the filters differ.
    std::vector<TestFunction> out = {{"1", [](double) { return 1.0; }}, {"x^2", [](double x) { return x * x; }}};
    for (double c : {-1.5, -0.5, 0.3, 1.2})
        out.push_back({"step at " + std::to_string(c), [c](double x) { return x > c ? 1.0 : 0.0; }});
    return out;
}

}  // namespace

TEST(PixelFilter, IntegralsMatchQuadrature) {
    for (uint type : kWide) {
        const double F = simpson([type](double x) { return double(filterProfile(type, float(x))); }, -2.0, 2.0);
        EXPECT_NEAR(filterProfileIntegral(type) / F, 1.0, 2e-6) << "filter " << type;
    }
}

TEST(PixelFilter, WeightedTentSamplesReproduceTheFilter) {
    for (uint type : kWide)
        for (const TestFunction& t : testFunctions())
            EXPECT_NEAR(sampled(type, t.g), filtered(type, t.g), 2e-4) << "filter " << type << ", g = " << t.name;
}

TEST(PixelFilter, UnweightedTentSamplesFailTheSameCheck) {
    for (uint type : kWide) {
        double worst = 0.0;
        for (const TestFunction& t : testFunctions()) worst = std::max(worst, std::abs(sampled(type, t.g, true) - filtered(type, t.g)));
        EXPECT_GT(worst, 1e-2) << "filter " << type;
    }
}

TEST(PixelFilter, WeightsAreBoundedAndNegativeInTheLobes) {
    for (uint type : kWide) {
        float lo = 0.0f, hi = 0.0f;
        for (int i = 0; i < 1 << 20; ++i) {
            float w;
            sampleWideFilter(type, (float(i) + 0.5f) / float(1 << 20), w);
            ASSERT_TRUE(std::isfinite(w));
            lo = std::min(lo, w), hi = std::max(hi, w);
        }
        EXPECT_LT(hi, 4.0f) << "filter " << type;
        EXPECT_GT(lo, -1.0f) << "filter " << type;
        if (type == kFilterGaussian) EXPECT_EQ(lo, 0.0f);
        else EXPECT_LT(lo, 0.0f) << "filter " << type << " has negative lobes";
    }
}
