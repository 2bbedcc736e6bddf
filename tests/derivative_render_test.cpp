// Derivative images (render/derivative.h, docs/DERIVATIVES.md) against derivatives known in closed
// form, each with a positive control that the same test rejects at the same sample count.
//
// The level of a derivative sample is drawn per sample index and shared by every pixel, so the
// pixels of one sample are correlated and a block mean's variance cannot be taken from per-pixel
// variances. The tests cut one render into batches of consecutive sample indices (independent:
// their random numbers and levels are) and t-test the batch means of every block.
//
// Finite variance: every parameter here enters the estimate smoothly with common random numbers
// (f(theta + h) - f(theta) = O(h) per sample), so E[D_j^2] falls as 4^-j and the correction's
// second moment sum_j E[D_j^2] / p(j) converges for the default p(j) ~ 2^-j.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"
#include "region_stats.h"
#include "render/derivative.h"
#include "render_harness.h"
#include "slab_closed_form.h"

using namespace telescope;
using namespace telescope::test;

namespace {

constexpr double kAlpha = 1e-3;
constexpr double kPi = 3.14159265358979323846;

// Per block and batch: the mean of the red channel over the block's pixels.
using Batches = std::vector<std::vector<double>>;  // [batch][block]

std::vector<double> blockMeansOfSums(const Film& now, const Film& before, uint64_t spp, uint32_t block) {
    const uint32_t bw = now.width() / block, bh = now.height() / block;
    std::vector<double> out(size_t(bw) * bh, 0.0);
    const auto& a = now.sums(shader::kChannelEstimate);
    const auto& b = before.sums(shader::kChannelEstimate);
    for (uint32_t y = 0; y < bh * block; ++y)
        for (uint32_t x = 0; x < bw * block; ++x) {
            const size_t p = size_t(y) * now.width() + x;
            out[size_t(y / block) * bw + x / block] += (a[p].x - b[p].x) / double(spp) / double(block * block);
        }
    return out;
}

// Renders `batches` batches of `spp` samples each with one DerivativeRenderer.
Batches renderBatches(DerivativeRenderer& r, uint32_t batches, uint64_t spp, uint32_t block) {
    Batches out;
    Film before = r.film();
    for (uint32_t i = 0; i < batches; ++i) {
        RenderRequest request;
        request.spp = spp;
        r.render(request);
        out.push_back(blockMeansOfSums(r.film(), before, spp, block));
        before = r.film();
    }
    expectLoopsComplete(r.renderer().stats());
    return out;
}

struct TSummary {
    size_t failing = 0, tests = 0;
    double maxAbsT = 0.0, threshold = 0.0;
    std::string worst;
};

// One-sample t-test of every block's batch means against the exact block mean (Sidak over blocks).
TSummary tTest(const Batches& b, const std::vector<double>& exact) {
    TSummary s;
    const size_t n = b.size(), blocks = exact.size();
    s.tests = blocks;
    s.threshold = sidakThresholdT(kAlpha, blocks, double(n - 1));
    for (size_t k = 0; k < blocks; ++k) {
        double mean = 0.0, m2 = 0.0;
        for (size_t i = 0; i < n; ++i) mean += b[i][k] / double(n);
        for (size_t i = 0; i < n; ++i) m2 += (b[i][k] - mean) * (b[i][k] - mean);
        const double se = std::sqrt(m2 / double(n - 1) / double(n));
        const double t = se > 0.0 ? (mean - exact[k]) / se : (std::abs(mean - exact[k]) < 1e-9 ? 0.0 : 1e300);
        if (std::abs(t) > s.threshold) ++s.failing;
        if (std::abs(t) > s.maxAbsT) {
            s.maxAbsT = std::abs(t);
            s.worst = "block " + std::to_string(k) + ": " + std::to_string(mean) + " against " +
                      std::to_string(exact[k]) + ", t = " + std::to_string(t);
        }
    }
    std::printf("  t-test: %zu of %zu blocks beyond %.2f, max |t| %.2f (%s)\n", s.failing, s.tests, s.threshold, s.maxAbsT,
                s.worst.c_str());
    return s;
}

class DerivativeRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

// ---- Point light over a diffuse plane: d L / d z ----
// scenes/point-plane.json: the plane y = 0 (albedo rho = 0.5), a point light of intensity I = 1
// (power 4 pi) at height z = 1, the camera at height 2 looking straight down (fov 90, box filter).
// At horizontal distance x: L = (rho / pi) I z / (x^2 + z^2)^(3/2), so
//   dL/dz = (rho / pi) I ((x^2 + z^2) - 3 z^2) / (x^2 + z^2)^(5/2) = (rho / pi) I (x^2 - 2 z^2) / (x^2 + z^2)^(5/2):
// negative under the light (raising it dims the spot), positive beyond x = sqrt(2) z.
// The box filter spreads a pixel's samples uniformly over its square on the plane (the plane
// faces the camera: the pinhole maps it affinely), so a block's exact mean is the mean of dL/dz
// over the block's square, integrated here with 16 x 16 points per pixel.
std::vector<double> pointPlaneExact(uint32_t res, uint32_t block) {
    const double rho = 0.5, I = 1.0, z = 1.0, halfWidth = 2.0;  // camera height 2, fov 90
    const uint32_t sub = 16, bw = res / block;
    std::vector<double> out(size_t(bw) * bw, 0.0);
    for (uint32_t by = 0; by < bw; ++by)
        for (uint32_t bx = 0; bx < bw; ++bx) {
            double sum = 0.0;
            const uint32_t n = block * sub;
            for (uint32_t j = 0; j < n; ++j)
                for (uint32_t i = 0; i < n; ++i) {
                    const double u = (bx * block + (i + 0.5) / sub) / res, v = (by * block + (j + 0.5) / sub) / res;
                    const double px = (2.0 * u - 1.0) * halfWidth, pz = (2.0 * v - 1.0) * halfWidth;
                    const double d2 = px * px + pz * pz + z * z;
                    sum += rho / kPi * I * (px * px + pz * pz - 2.0 * z * z) / std::pow(d2, 2.5);
                }
            out[size_t(by) * bw + bx] = sum / double(n) / double(n);
        }
    return out;
}

TEST_F(DerivativeRender, PointLightHeightMatchesTheClosedFormAndALargeForwardStepDoesNot) {
    // 12 levels: the estimates are unbiased for I(levels), whose bias h_0 2^-levels L'' / 2 the auto
    // pmf resolves at 8 levels and h_0 = 0.25 (t = -4.2 in a corner block, within the bound).
    constexpr uint32_t kRes = 32, kBlock = 8, kBatches = 16, kLevels = 12;
    constexpr uint64_t kSpp = 16;
    const Scene scene = loadTestScene("scenes/point-plane.json", {{"camera.resolution", "[32, 32]"}});
    const std::vector<double> exact = pointPlaneExact(kRes, kBlock);
    // The closed form's sign: dimmer under the light, brighter far out.
    ASSERT_LT(exact[size_t(kRes / kBlock) * (kRes / kBlock) / 2 + 1], 0.0);
    ASSERT_GT(exact[0], 0.0);
    auto run = [&](DerivativeEstimator e) {
        DerivativeSettings s;
        s.key = "primitives[1].transform.position[1]";
        s.step = 0.25;
        s.levels = kLevels;
        s.estimator = e;
        DerivativeRenderer r(sharedContext(), resolved(scene), s, 7);
        return tTest(renderBatches(r, kBatches, kSpp, kBlock), exact);
    };
    for (auto e : {DerivativeEstimator::SingleTerm, DerivativeEstimator::Sum}) {
        const TSummary t = run(e);
        EXPECT_EQ(t.failing, 0u) << derivativeEstimatorName(e) << ": " << t.worst << " (threshold " << t.threshold << ")";
    }
    // pmf "auto": the pilot's table is a pmf, its moments fall over the first levels (a smooth
    // parameter), and the render with it stays unbiased.
    {
        DerivativeSettings s;
        s.key = "primitives[1].transform.position[1]";
        s.step = 0.25;
        s.levels = kLevels;
        s.autoPmf = true;
        DerivativeRenderer r(sharedContext(), resolved(scene), s, 13);
        const std::vector<double>& m = r.pilotSecondMoments();
        ASSERT_EQ(m.size(), s.levels);
        EXPECT_LT(m[1], 0.5 * m[0]);
        EXPECT_LT(m[2], 0.5 * m[1]);
        double total = 0.0;
        for (uint32_t j = 0; j < s.levels; ++j) {
            EXPECT_GT(r.levelProbability(j), 0.0);
            total += r.levelProbability(j);
        }
        EXPECT_NEAR(total, 1.0, 1e-12);
        const TSummary t = tTest(renderBatches(r, kBatches, kSpp, kBlock), exact);
        EXPECT_EQ(t.failing, 0u) << "auto pmf: " << t.worst;
    }
    // Positive control: the forward difference at h_0 = 0.25 (its bias ~ h_0 / 2 d2L/dz2).
    const TSummary forward = run(DerivativeEstimator::Forward);
    EXPECT_GT(forward.failing, 0u) << "the biased forward difference passed: " << forward.worst;
    EXPECT_GT(forward.maxAbsT, 6.0) << forward.worst;
}

// ---- White furnace: d L / d rho ----
// scenes/furnace.json: a closed box of albedo rho = 0.5 emitting Le = 1 everywhere: L = Le / (1 - rho)
// (truncated at 24 bounces here, the derivative misses sum_(n>24) n rho^(n-1) ~ 3e-6), so
// dL/drho = Le / (1 - rho)^2 = 4 in every pixel.
TEST_F(DerivativeRender, FurnaceAlbedoMatchesTheClosedFormAndAMisweightedCorrectionDoesNot) {
    constexpr uint32_t kBlock = 8, kBatches = 16;
    constexpr uint64_t kSpp = 8;
    const Scene scene = loadTestScene("scenes/furnace.json", {{"camera.resolution", "[32, 32]"}, {"integrator.max_bounces", "25"}});
    const std::vector<double> exact(16, 4.0);
    auto run = [&](DerivativeEstimator e, DerivativeControl c) {
        DerivativeSettings s;
        s.key = "bsdfs[0].albedo";
        s.step = 0.2;  // I(0) = (L(0.7) - L(0.5)) / 0.2 = 6.67: the series corrects a large bias
        s.estimator = e;
        s.control = c;
        DerivativeRenderer r(sharedContext(), resolved(scene), s, 11);
        return tTest(renderBatches(r, kBatches, kSpp, kBlock), exact);
    };
    for (auto e : {DerivativeEstimator::SingleTerm, DerivativeEstimator::Sum}) {
        const TSummary t = run(e, DerivativeControl::None);
        EXPECT_EQ(t.failing, 0u) << derivativeEstimatorName(e) << ": " << t.worst << " (threshold " << t.threshold << ")";
        // Positive control: 1 / p(j+1) where 1 / p(j) belongs.
        const TSummary wrong = run(e, DerivativeControl::ShiftedPmf);
        EXPECT_EQ(wrong.failing, wrong.tests) << derivativeEstimatorName(e) << " mis-weighted passed: " << wrong.worst;
    }
}

// ---- Absorbing slab: d T / d sigma through debiased ray marching ----
// scenes/absorbing-slab.json, exponential transmittance: the bottom half of the frame sees the
// emitter (Le = 1) through the exponential-falloff slab, L = exp(-s tau_f / cos) with density
// 3 s (s = 1) and tau_f = 1 - exp(-3) along the normal; so dL/d(density) = -(tau_f / 3) / cos L.
// The top half sees through the other medium: derivative 0. Dirac filter: one direction per pixel.
std::vector<double> slabExact(const Scene& scene, uint32_t block) {
    const Camera& cam = scene.camera;
    const double w = cam.width, h = cam.height;
    const double plane = 1.0 / std::tan(0.5 * cam.fovDegrees * kPi / 180.0);
    const uint32_t bw = cam.width / block, bh = cam.height / block;
    std::vector<double> out(size_t(bw) * bh, 0.0);
    for (uint32_t y = 0; y < bh * block; ++y)
        for (uint32_t x = 0; x < bw * block; ++x) {
            const double lx = -1.0 + 2.0 * (x + 0.5) / w, ly = h / w - 2.0 * (y + 0.5) / w;
            const double cosZ = plane / std::sqrt(lx * lx + ly * ly + plane * plane);
            const double tauF = slabTauFalloff() / cosZ;
            const double d = ly > 0 ? 0.0 : -(tauF / 3.0) * std::exp(-tauF);
            out[size_t(y / block) * bw + x / block] += d / double(block * block);
        }
    return out;
}

TEST_F(DerivativeRender, SlabDensityThroughDebiasedMarchingAndIndependentNumbersCostVariance) {
    constexpr uint32_t kBlock = 8, kBatches = 16;
    constexpr uint64_t kSpp = 8;
    const Scene scene = loadTestScene("scenes/absorbing-slab.json",
                                      {{"camera.resolution", "[32, 32]"},
                                       {"integrator.transmittance_estimator", R"({"type":"debiased_ray_march","level":1})"}});
    const std::vector<double> exact = slabExact(scene, kBlock);
    DerivativeSettings s;
    s.key = "media[1].density";
    s.step = 0.5;
    // The estimate is unbiased for I(levels), whose bias h_0 2^-levels L'' / 2 is 4e-5 at the default
    // 8 levels: a third of this test's standard error (it shows as t ~ 1-3). At 12 levels it is 3e-6.
    s.levels = 12;
    DerivativeRenderer r(sharedContext(), resolved(scene), s, 5);
    const TSummary t = tTest(renderBatches(r, kBatches, kSpp, kBlock), exact);
    EXPECT_EQ(t.failing, 0u) << t.worst << " (threshold " << t.threshold << ")";

    // Variance control: independent random numbers for the evaluations of a sample. Per pixel the
    // film's own variance of the mean is valid (each pixel's samples are independent).
    // (The same renderer, restarted: one set of media pipelines.)
    const Film withCommon = r.film();
    r.restart(DerivativeControl::IndependentNumbers);
    (void)renderBatches(r, kBatches, kSpp, kBlock);
    double common = 0.0, separate = 0.0;
    for (size_t p = 0; p < withCommon.pixelCount(); ++p) {
        common += withCommon.varianceOfMean(p).x;
        separate += r.film().varianceOfMean(p).x;
    }
    EXPECT_GT(common, 0.0);
    EXPECT_GE(separate, 10.0 * common) << "common random numbers: " << common << ", independent: " << separate;
    RecordProperty("variance_ratio", std::to_string(separate / common));
    std::printf("slab derivative: variance of the mean, independent / common random numbers = %.1f\n", separate / common);
}

// ---- Bad parameters: one InputError naming the key ----
TEST_F(DerivativeRender, RefusesParametersWithoutADerivative) {
    const Scene scene = loadTestScene("scenes/point-plane.json", {{"camera.resolution", "[16, 16]"}});
    auto refused = [&](const std::string& key, double step, const std::string& expect,
                       DerivativeEstimator e = DerivativeEstimator::SingleTerm) {
        DerivativeSettings s;
        s.key = key;
        s.step = step;
        s.estimator = e;
        try {
            DerivativeRenderer r(sharedContext(), resolved(scene), s, 1);
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find(expect), std::string::npos) << key << ": " << e.what();
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
            return;
        }
        ADD_FAILURE() << key << " was accepted";
    };
    refused("bsdfs[0].type", 0.0, "is not a number");
    refused("bsdfs[0].nonexistent", 0.0, "no such value");
    refused("camera.resolution[0]", 0.0, "discrete");
    refused("integrator.max_bounces", 0.0, "setting of the estimator");
    refused("camera.fov", 0.0, "field of view");
    refused("bsdfs[0].albedo", 0.75, "refuses the value", DerivativeEstimator::Central);  // 0.5 - 0.75 < 0
    refused("primitives[0].name", 0.0, "is not a number");
}

}  // namespace
