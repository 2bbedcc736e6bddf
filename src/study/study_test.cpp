// Convergence-study helpers on the CPU: error metrics, log-log slopes, time to a target error,
// and method presets.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "study/error_metrics.h"
#include "study/methods.h"

using namespace telescope;

TEST(ErrorMetrics, AgainstAKnownImage) {
    Film film(2, 1);
    film.setSamplesPerPixel(2);
    film.sums(shader::kChannelEstimate)[0] = glm::dvec4(2.0, 2.0, 2.0, 0.0);  // mean 1
    film.sums(shader::kChannelEstimate)[1] = glm::dvec4(0.0);                 // mean 0
    RgbImage ref;
    ref.width = 2, ref.height = 1;
    ref.pixels = {1, 1, 1, 1, 1, 1};
    ErrorMetrics m = compareToReference(film, ref);
    EXPECT_DOUBLE_EQ(m.rmse, std::sqrt(0.5));
    EXPECT_DOUBLE_EQ(m.relMse, 0.5 / (1.0 + kRelMseEpsilon));
    EXPECT_DOUBLE_EQ(m.meanError, -0.5);
    EXPECT_DOUBLE_EQ(m.relMeanError, -0.5);
    ref.width = 1;
    EXPECT_THROW(compareToReference(film, ref), std::invalid_argument);
}

TEST(ErrorMetrics, LogLogSlopeOfAPowerLaw) {
    std::vector<double> x, y;
    for (int i = 0; i < 6; ++i) x.push_back(std::ldexp(1.0, i)), y.push_back(3.0 * std::pow(x.back(), -0.75));
    EXPECT_NEAR(logLogSlope(x, y), -0.75, 1e-12);
    EXPECT_TRUE(std::isnan(logLogSlope({1.0}, {1.0})));
    // Points with non-positive values are left out.
    x.push_back(0.0), y.push_back(5.0);
    EXPECT_NEAR(logLogSlope(x, y), -0.75, 1e-12);
}

TEST(ErrorMetrics, TimeToReachInterpolatesInLogLog) {
    std::vector<double> t = {1, 10, 100}, e = {1e-1, 1e-2, 1e-3};
    EXPECT_NEAR(timeToReach(t, e, 1e-2), 10.0, 1e-9);
    EXPECT_NEAR(timeToReach(t, e, std::sqrt(1e-1 * 1e-2)), std::sqrt(10.0), 1e-9);
    EXPECT_EQ(timeToReach(t, e, 1e-4), -1.0);
    EXPECT_EQ(timeToReach(t, e, 1.0), 1.0);
}

TEST(Methods, PresetsAndCustomMethods) {
    Method m = parseMethod("single_term:3", "--methods");
    EXPECT_EQ(m.label, "single_term:3");
    ASSERT_EQ(m.overrides.size(), 2u);
    EXPECT_EQ(m.overrides[0].key, "integrator.max_bounces");
    EXPECT_EQ(m.overrides[0].value, "4");  // k = 3 bounces: max_bounces counts the light connection
    EXPECT_NE(m.overrides[1].value.find("single_term"), std::string::npos);
    EXPECT_EQ(parseMethod("biased:2", "--methods").overrides[1].value, "null");

    Method c = parseMethod("deep: integrator.max_bounces=64; camera.resolution=[8,8]", "--method");
    EXPECT_EQ(c.label, "deep");
    ASSERT_EQ(c.overrides.size(), 2u);
    EXPECT_EQ(c.overrides[1].key, "camera.resolution");
    EXPECT_EQ(c.overrides[1].value, "[8,8]");

    for (const char* bad : {"biased", "biased:x", "biased:-1", "magic:3", ":3", "label: novalue"})
        EXPECT_THROW(parseMethod(bad, "--methods"), InputError) << bad;
}
