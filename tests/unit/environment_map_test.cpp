// Environment-map sampling (shaders/shared/environment_map.h) on the CPU, the code the path tracer
// runs: a chi-square test of envSample against envPdf with two positive controls, the rotation,
// the lookup, and the variance of an importance-sampled irradiance estimate against uniform
// sphere sampling on a peaky map.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace envmap_test {
std::vector<float> data;  // the environment buffer the shared code reads
}
#define ENV_DATA(i) (::envmap_test::data[i])
#include "shared/environment_map.h"
#include "shared/sampling.h"

#include "bsdf_stats.h"
#include "render/environment_map.h"
#include "scene/transform.h"

namespace telescope {
namespace {

using glm::vec2;
using glm::vec3;
using namespace shader;

// A 64 x 32 sky: a gradient, a black ground (the bottom four rows), and a sun of 3 x 2 texels
// 2000 times brighter than the sky.
EnvironmentImage peakySky() {
    EnvironmentImage img;
    img.width = 64;
    img.height = 32;
    img.rgb.resize(size_t(img.width) * img.height * 3);
    for (uint32_t y = 0; y < img.height; ++y)
        for (uint32_t x = 0; x < img.width; ++x) {
            float* t = &img.rgb[(size_t(y) * img.width + x) * 3];
            const float sky = y >= 28 ? 0.0f : 0.2f + 0.6f * float(y) / img.height;
            t[0] = sky * 0.6f;
            t[1] = sky * 0.8f;
            t[2] = sky;
            if (x >= 40 && x < 43 && y >= 8 && y < 10) t[0] = t[1] = t[2] = 1000.0f;
        }
    return img;
}

glm::mat3 rotation(vec3 degrees) {
    TransformSpec spec;
    spec.rotationDegrees = degrees;
    return columnDirections(buildTransform(spec));
}

// The chi-square test's frame: bins in theta around +z and phi from +x line up with the texels
// when t = (l.x, l.z, -l.y) for the local direction l (theta = the map's theta, phi = the map's
// phi - pi), so the expected count of a bin (pdf constant over it) is exact.
vec3 localToTest(vec3 l) { return vec3(l.x, l.z, -l.y); }
vec3 testToLocal(vec3 t) { return vec3(t.x, -t.z, t.y); }

TEST(EnvironmentMap, SamplingMatchesItsPdf) {
    const glm::mat3 rot = rotation({30.0f, 70.0f, -20.0f});
    envmap_test::data = buildEnvironmentBuffer(peakySky(), rot);
    const test::SampleFn sample = [&](float u1, float u2, vec3& wo) {
        vec3 w;
        vec2 uv;
        float pdf;
        if (!envSample(vec2(u1, u2), w, uv, pdf)) return false;
        wo = localToTest(envToLocal(w));
        return true;
    };
    const auto worldOf = [&](vec3 t) { return envToWorld(testToLocal(t)); };
    const uint32_t n = 2000000;
    const test::ChiSquareResult ok = test::chiSquareSphere(sample, [&](vec3 t) { return double(envPdf(worldOf(t))); },
                                                           n, 7, 64, 128, 4);
    EXPECT_FALSE(ok.rejected()) << ok.describe();
    EXPECT_LT(ok.lostSamples, 10.0);

    // Control 1: the pdf without the Jacobian 1 / (2 pi^2 sin theta) of the sphere map,
    // renormalised (so only its shape is wrong).
    const auto noJacobian = [&](vec3 t) {
        const vec3 l = testToLocal(t);
        const float s = std::sqrt(std::max(1.0f - l.y * l.y, 0.0f));
        return double(envPdf(worldOf(t))) * s;
    };
    const double mass = test::integrateSphere(noJacobian, 1024, 256);
    const test::ChiSquareResult control1 =
        test::chiSquareSphere(sample, [&](vec3 t) { return noJacobian(t) / mass; }, n, 7, 64, 128, 4);
    EXPECT_TRUE(control1.rejected()) << "control (no Jacobian): " << control1.describe();

    // Control 2: the pdf of the image flipped upside down (rows counted from the bottom).
    const test::ChiSquareResult control2 = test::chiSquareSphere(
        sample, [&](vec3 t) { return double(envPdf(worldOf(vec3(t.x, t.y, -t.z)))); }, n, 7, 64, 128, 4);
    EXPECT_TRUE(control2.rejected()) << "control (flipped): " << control2.describe();
    std::printf("env map chi2: %s\n  control no Jacobian: %s\n  control flipped: %s\n", ok.describe().c_str(),
                control1.describe().c_str(), control2.describe().c_str());
}

// The pdf integrates to 1 over the sphere, and the lookup reads texels at their centres, with the
// image's top row up (+y) in the local frame and the primitive's rotation applied to directions.
TEST(EnvironmentMap, PdfIntegratesToOneAndLookupFollowsTungstenAndTheRotation) {
    const glm::mat3 rot = rotation({0.0f, 0.0f, 90.0f});
    EnvironmentImage img = peakySky();
    img.interpolate = false;
    envmap_test::data = buildEnvironmentBuffer(img, rot);
    EXPECT_NEAR(test::integrateSphere([](vec3 w) { return double(envPdf(w)); }, 2048, 512), 1.0, 2e-3);
    // Local +y (the top row) goes where the transform takes +y, off the world y axis.
    const vec3 up = envToWorld(vec3(0.0f, 1.0f, 0.0f));
    EXPECT_NEAR(glm::length(up - rot[1]), 0.0f, 1e-6f);
    EXPECT_NEAR(up.y, 0.0f, 1e-6f);
    // The sun's texel centre (41.5, 8.5) in (x, y) -> (u, v) -> local -> world; its radiance there.
    const vec2 uv(41.5f / 64.0f, 1.0f - 8.5f / 32.0f);
    float sinTheta;
    const vec3 world = envToWorld(envUvToLocal(uv, sinTheta));
    EXPECT_FLOAT_EQ(envRadiance(world).x, 1000.0f);
    EXPECT_FLOAT_EQ(envRadiance(rot * glm::inverse(rot) * world).y, 1000.0f);
    // Without the rotation the same world direction misses the sun.
    envmap_test::data = buildEnvironmentBuffer(img, glm::mat3(1.0f));
    EXPECT_LT(envRadiance(world).x, 1.0f);
    // Bilinear lookups (the default) equal the texel at its centre and mix neighbours between.
    img.interpolate = true;
    envmap_test::data = buildEnvironmentBuffer(img, glm::mat3(1.0f));
    EXPECT_NEAR(envLookup(uv).x, 1000.0f, 1e-3f);
    EXPECT_NEAR(envLookup(vec2(43.0f / 64.0f, uv.y)).x, 0.5f * (1000.0f + envTexel(43, 8).x), 1e-2f);
}

// Irradiance on a plate facing +z (world) under the peaky sky, E = int L max(cos, 0) dw, by
// light sampling (envSample) and by uniform sphere sampling: both agree with the quadrature, and
// importance sampling has the smaller variance (measured and printed).
TEST(EnvironmentMap, ImportanceSamplingReducesVarianceOnAPeakyMap) {
    const glm::mat3 rot = rotation({0.0f, 30.0f, 0.0f});
    envmap_test::data = buildEnvironmentBuffer(peakySky(), rot);
    const vec3 n(0.0f, 0.0f, 1.0f);
    auto integrand = [&](vec3 w) { return double(envRadiance(w).y) * std::max(0.0, double(glm::dot(w, n))); };
    const double exact = test::integrateSphere(integrand, 4096, 2048);
    std::mt19937_64 gen(11);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    const int count = 400000;
    double sumIs = 0.0, sumIs2 = 0.0, sumU = 0.0, sumU2 = 0.0;
    for (int i = 0; i < count; ++i) {
        vec3 w;
        vec2 uv;
        float pdf;
        double x = 0.0;
        if (envSample(vec2(uni(gen), uni(gen)), w, uv, pdf))
            x = double(envLookup(uv).y) * std::max(0.0, double(glm::dot(w, n))) / pdf;
        sumIs += x;
        sumIs2 += x * x;
        const vec3 wu = sampleUniformSphere(uni(gen), uni(gen));
        const double y = integrand(wu) * 4.0 * 3.14159265358979323846;
        sumU += y;
        sumU2 += y * y;
    }
    const double meanIs = sumIs / count, varIs = sumIs2 / count - meanIs * meanIs;
    const double meanU = sumU / count, varU = sumU2 / count - meanU * meanU;
    std::printf("irradiance %.5f: importance %.5f (variance %.4g), uniform %.5f (variance %.4g), ratio %.1f\n", exact,
                meanIs, varIs, meanU, varU, varU / varIs);
    // 5 standard errors (the quadrature's own error is far smaller).
    EXPECT_NEAR(meanIs, exact, 5.0 * std::sqrt(varIs / count));
    EXPECT_NEAR(meanU, exact, 5.0 * std::sqrt(varU / count));
    EXPECT_LT(varIs, varU);
}

}  // namespace
}  // namespace telescope
