// The Henyey-Greenstein phase function of shared/phase.h, as the path tracer runs it (CPU build of
// the same code): its density integrates to 1 with mean cosine g, and samplePhaseHG draws
// directions with exactly that density (chi-square over the sphere, bsdf_stats.h), for forward,
// backward and isotropic scattering and a direction off the axes. Positive controls, rejected by
// the same test with the same samples: the density of g mirrored (-g), and of g 10% too weak.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "bsdf_stats.h"
#include "shared/phase.h"

using namespace telescope;
using namespace telescope::shader;

namespace {

const float kGs[] = {-0.7f, 0.0f, 0.3f, 0.9f};

}  // namespace

TEST(PhaseFunction, HenyeyGreensteinIntegratesToOneWithMeanCosineG) {
    for (float g : kGs) {
        const double mass = test::integrateSphere([&](glm::vec3 w) { return double(phaseHG(w.z, g)); });
        const double meanCos = test::integrateSphere([&](glm::vec3 w) { return double(w.z) * phaseHG(w.z, g); });
        EXPECT_NEAR(mass, 1.0, 1e-4) << "g " << g;
        EXPECT_NEAR(meanCos, double(g), 1e-4) << "g " << g;
    }
    // The isotropic case is 1 / (4 pi) everywhere.
    EXPECT_FLOAT_EQ(phaseHG(0.3f, 0.0f), float(1.0 / (4.0 * 3.14159265358979323846)));
}

TEST(PhaseFunction, HenyeyGreensteinSamplingMatchesItsDensity) {
    const glm::vec3 axes[] = {glm::vec3(0.0f, 0.0f, 1.0f), glm::normalize(glm::vec3(0.3f, -0.8f, 0.5f))};
    const uint32_t n = 400000;
    for (const glm::vec3 dir : axes)
        for (float g : kGs) {
            const test::SampleFn sample = [&](float u1, float u2, glm::vec3& wo) {
                wo = samplePhaseHG(dir, g, u1, u2);
                return true;
            };
            auto density = [&](float gOf) {
                return [=](glm::vec3 w) { return double(phaseHG(glm::dot(dir, w), gOf)); };
            };
            const test::ChiSquareResult ok = test::chiSquareSphere(sample, density(g), n, 11);
            EXPECT_FALSE(ok.rejected()) << "g " << g << ": " << ok.describe();
            if (g != 0.0f) {
                const test::ChiSquareResult mirrored = test::chiSquareSphere(sample, density(-g), n, 11);
                const test::ChiSquareResult weaker = test::chiSquareSphere(sample, density(0.9f * g), n, 11);
                EXPECT_TRUE(mirrored.rejected()) << "control -g, g " << g << ": " << mirrored.describe();
                EXPECT_TRUE(weaker.rejected()) << "control 0.9 g, g " << g << ": " << weaker.describe();
                std::printf("g %+.1f dir (%.2f %.2f %.2f): %s\n  control -g: %s\n  control 0.9 g: %s\n", g, dir.x, dir.y,
                            dir.z, ok.describe().c_str(), mirrored.describe().c_str(), weaker.describe().c_str());
            }
        }
}
