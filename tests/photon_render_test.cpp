// Photon mapping on the device against the analytic point light over a diffuse plane
// (scenes/point-plane-photon.json): L = (albedo / pi) I cos(theta) / d^2.
//
// The unbiased estimator has infinite variance (ESTIMATORS.md sections 3 and 6; its correction
// even has tails P(|Z| > z) ~ 1/z, see docs/PHOTON-MAPPING.md), so a per-pixel Z-test with the
// sample variance is meaningless. Each test renders B independent batches (seeds) and tests, per
// image region, the batch means: a t-test with the batch means' own spread, and a sign test (the
// number of batch means above the analytic value is Binomial(B, 1/2) for a symmetric batch-mean
// distribution centred on the answer), both Sidak-corrected over the regions. The biased
// estimator with a large radius fails the same test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;

namespace {

const char* kScene = "scenes/point-plane-photon.json";
constexpr uint32_t kRes = 16;    // 16x16 pixels over [-2, 2]^2 on the plane
constexpr uint32_t kBlock = 4;   // 16 regions of 4x4 pixels
constexpr double kAlpha = 1e-3;  // family-wise false-failure rate

// Pixel-averaged analytic radiance (box filter) of each region: the camera at height 2 with a
// 90 degree field of view sees x, z in [-2, 2]; the light (I = 1) is at height 1, albedo 0.5.
std::vector<double> analyticRegions() {
    const uint32_t regions = kRes / kBlock, sub = 16;
    std::vector<double> out(regions * regions, 0.0);
    for (uint32_t py = 0; py < kRes; ++py)
        for (uint32_t px = 0; px < kRes; ++px) {
            double sum = 0.0;
            for (uint32_t i = 0; i < sub; ++i)
                for (uint32_t k = 0; k < sub; ++k) {
                    double x = -2.0 + 4.0 * (px + (i + 0.5) / sub) / kRes;
                    double z = -2.0 + 4.0 * (py + (k + 0.5) / sub) / kRes;
                    sum += 0.5 / M_PI * std::pow(1.0 + x * x + z * z, -1.5);
                }
            out[(py / kBlock) * regions + px / kBlock] += sum / (sub * sub) / (kBlock * kBlock);
        }
    return out;
}

Scene plane(const std::string& integrator) {
    return loadTestScene(kScene, {{"camera.resolution", fmt::format("[{},{}]", kRes, kRes)}, {"integrator", integrator}});
}

struct BatchTest {
    size_t tFailures = 0, signFailures = 0, regions = 0;
    std::string worst;
};

// B batches of `passes` passes each; per region a t-test on the batch means and a sign test.
// Passes are independent (each draws its photons and pixel samples from its own index), so the
// batches are consecutive passes of one render.
BatchTest batchMeansTest(const Scene& scene, uint32_t batches, uint32_t passes, uint32_t seed) {
    const std::vector<double> want = analyticRegions();
    std::vector<std::vector<double>> means(want.size());
    Renderer renderer(sharedContext(), scene, seed);
    std::vector<double> before(want.size(), 0.0);
    for (uint32_t b = 0; b < batches; ++b) {
        RenderRequest request;
        request.spp = passes;
        renderer.render(request);
        Film film = renderer.film();
        auto regions = blockMeans(film, kBlock);
        for (size_t r = 0; r < want.size(); ++r) {
            const double sum = regions[r].mean.x * double(film.samplesPerPixel());
            means[r].push_back((sum - before[r]) / passes);
            before[r] = sum;
        }
    }
    BatchTest t;
    t.regions = want.size();
    const double z = sidakThreshold(kAlpha, want.size());
    // Sign test: reject when the count above is outside [k, B - k], P(X < k) <= alpha' / 2.
    const double alphaOne = 1.0 - std::pow(1.0 - kAlpha, 1.0 / double(want.size()));
    uint32_t k = 0;
    double cdf = std::pow(0.5, batches), term = cdf;
    while (cdf + term * double(batches - k) / double(k + 1) <= alphaOne / 2) {
        term *= double(batches - k) / double(k + 1);
        ++k;
        cdf += term;
    }
    ++k;  // smallest accepted count
    double worst = -1.0;
    for (size_t r = 0; r < want.size(); ++r) {
        double mean = 0.0, var = 0.0;
        uint32_t above = 0;
        for (double m : means[r]) {
            mean += m / batches;
            above += m > want[r];
        }
        for (double m : means[r]) var += (m - mean) * (m - mean) / (batches - 1);
        double tStat = (mean - want[r]) / std::sqrt(var / batches);
        bool tFail = !(std::abs(tStat) <= z);
        bool signFail = above < k || above > batches - k;
        t.tFailures += tFail;
        t.signFailures += signFail;
        if (std::abs(tStat) > worst) {
            worst = std::abs(tStat);
            std::ostringstream s;
            s << "region " << r << ": mean " << mean << " vs " << want[r] << ", t = " << tStat << ", " << above << "/"
              << batches << " batches above (accepted " << k << ".." << batches - k << ")";
            t.worst = s.str();
        }
    }
    std::printf("batch means: %zu/%zu regions fail the t-test, %zu the sign test; worst %s\n", t.tFailures, t.regions,
                t.signFailures, t.worst.c_str());
    return t;
}

class PhotonRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

const char* kUnbiased =
    R"({"type":"photon_map","photon_count":20000,"gather_radius":0.1,"direct_lighting":"photons",
        "debias":{"estimator":"single_term"}})";

}  // namespace

TEST_F(PhotonRender, UnbiasedMatchesTheAnalyticPlane) {
    BatchTest t = batchMeansTest(plane(kUnbiased), 32, 4, 100);
    EXPECT_EQ(t.tFailures, 0u) << t.worst;
    EXPECT_EQ(t.signFailures, 0u) << t.worst;
}

TEST_F(PhotonRender, UnbiasedProgressiveMatchesTheAnalyticPlane) {
    BatchTest t = batchMeansTest(
        plane(R"({"type":"progressive_photon_map","photon_count":20000,"gather_radius":0.1,"direct_lighting":"photons",
                  "debias":{"estimator":"single_term"}})"),
        32, 4, 200);
    EXPECT_EQ(t.tFailures, 0u) << t.worst;
    EXPECT_EQ(t.signFailures, 0u) << t.worst;
}

TEST_F(PhotonRender, UnbiasedGeometricLevelsAndOtherKernelsMatchTheAnalyticPlane) {
    for (const char* kernel : {"epanechnikov", "uniform"}) {
        BatchTest t = batchMeansTest(
            plane(fmt::format(R"({{"type":"photon_map","photon_count":20000,"gather_radius":0.1,"direct_lighting":"photons",
                              "kernel":"{}","debias":{{"estimator":"single_term","pmf":{{"type":"geometric","r":0.5}}}}}})",
                              kernel)),
            32, 4, 250);
        EXPECT_EQ(t.tFailures, 0u) << kernel << ": " << t.worst;
        EXPECT_EQ(t.signFailures, 0u) << kernel << ": " << t.worst;
    }
}

TEST_F(PhotonRender, BiasedLargeRadiusFailsTheSameTest) {
    BatchTest t = batchMeansTest(
        plane(R"({"type":"photon_map","photon_count":20000,"gather_radius":0.5,"direct_lighting":"photons"})"), 32, 4, 300);
    EXPECT_GT(t.tFailures, t.regions / 4) << t.worst;
    EXPECT_GT(t.signFailures, 0u) << t.worst;
}

TEST_F(PhotonRender, ProgressivePhotonMappingConverges) {
    // Starting from a large radius, the average of the passes approaches the answer.
    Scene scene = plane(R"({"type":"progressive_photon_map","photon_count":20000,"gather_radius":0.6,
                            "direct_lighting":"photons"})");
    const std::vector<double> want = analyticRegions();
    auto error = [&](uint64_t passes) {
        auto regions = blockMeans(renderFilm(scene, passes, 400), kBlock);
        double e = 0.0;
        for (size_t r = 0; r < want.size(); ++r) e += std::abs(regions[r].mean.x - want[r]) / want[r] / want.size();
        return e;
    };
    double early = error(2), late = error(64);
    EXPECT_LT(late, 0.6 * early) << "relative error after 2 passes " << early << ", after 64 " << late;
    EXPECT_LT(late, 0.03);
}

TEST_F(PhotonRender, NextEventDirectLightMatchesThePlaneWithoutPhotonsAtTheFirstHit) {
    // With next-event direct light the plane receives no photon (they would be first hits): the
    // estimate is the light sample alone, exact up to the pixel jitter. Photons stored at the
    // first hit as well would double it.
    Scene scene = plane(R"({"type":"photon_map","photon_count":20000,"gather_radius":0.1,
                            "direct_lighting":"next_event","debias":{"estimator":"single_term"}})");
    Renderer renderer(sharedContext(), scene, 600);
    RenderRequest request;
    request.spp = 16;
    renderer.render(request);
    EXPECT_EQ(renderer.stats().photonsStored, 0u);
    const std::vector<double> want = analyticRegions();
    auto regions = blockMeans(renderer.film(), kBlock);
    for (size_t r = 0; r < want.size(); ++r) EXPECT_NEAR(regions[r].mean.x, want[r], 0.02 * want[r]) << "region " << r;
}

TEST_F(PhotonRender, BaseAndCorrectionAddUpAndSplitIntoSignedParts) {
    Film film = renderFilm(plane(kUnbiased), 4, 500);
    size_t negative = 0;
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        glm::dvec3 est = film.mean(shader::kChannelEstimate, i);
        glm::dvec3 base = film.mean(shader::kChannelBase, i), corr = film.mean(shader::kChannelCorrection, i);
        glm::dvec3 pos = film.mean(shader::kChannelCorrectionPositive, i);
        glm::dvec3 neg = film.mean(shader::kChannelCorrectionNegative, i);
        ASSERT_NEAR(base.x + corr.x, est.x, 1e-4 * (1.0 + std::abs(est.x))) << i;
        ASSERT_NEAR(pos.x + neg.x, corr.x, 1e-4 * (1.0 + std::abs(pos.x) + std::abs(neg.x))) << i;
        ASSERT_GE(pos.x, 0.0);
        ASSERT_LE(neg.x, 0.0);
        negative += est.x < 0.0;
    }
    EXPECT_GT(negative, 0u) << "a few pixels of a 4-pass unbiased render are negative";
    EXPECT_EQ(film.nonFiniteSamples(), 0u);
}

TEST_F(PhotonRender, SixteenMillionPhotons) {
    // 2^25 + 2^22 photon paths, of which about 45% reach the plane: over 16 M stored photons (over
    // 512 MiB of photons, beyond the 128 MiB binding limit) in one pass.
    Scene scene = loadTestScene(kScene, {{"camera.resolution", "[16,16]"},
                                         {"integrator", R"({"type":"photon_map","photon_count":37748736,
                                           "gather_radius":0.02,"direct_lighting":"photons"})"}});
    Renderer renderer(sharedContext(), scene, 1);
    RenderRequest request;
    request.spp = 1;
    renderer.render(request);
    EXPECT_GE(renderer.stats().photonsStored, 16u << 20);
    Film film = renderer.film();
    const std::vector<double> want = analyticRegions();
    auto regions = blockMeans(film, kBlock);
    // The centre regions: the biased estimate at r = 0.02 is within a few percent.
    for (size_t r : {5, 6, 9, 10}) EXPECT_NEAR(regions[r].mean.x, want[r], 0.03 * want[r]) << "region " << r;
}

TEST_F(PhotonRender, CausticCornellBoxAgreesWithThePathTracer) {
    // Progressive photon mapping with next-event direct light (caustics and indirect light from
    // photons) against the path tracer with the sum estimator: the whole image and the floor under
    // the glass sphere (the caustic) agree within a few percent.
    const char* kCaustic = "scenes/cornell-box-caustic.json";
    Scene ppm = loadTestScene(kCaustic, {{"camera.resolution", "[48,48]"},
                                         {"integrator.type", R"("progressive_photon_map")"},
                                         {"integrator.debias", "null"},
                                         {"integrator.photon_count", "60000"},
                                         {"integrator.gather_radius", "0.04"}});
    Scene pt = loadTestScene(kCaustic, {{"camera.resolution", "[48,48]"},
                                        {"integrator.type", R"("path_tracer")"},
                                        {"integrator.debias", R"({"estimator":"sum"})"}});
    Film a = renderFilm(ppm, 16, 700), b = renderFilm(pt, 128, 701);
    auto mean = [](const Film& f, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h) {
        glm::dvec3 m(0.0);
        for (uint32_t y = y0; y < y0 + h; ++y)
            for (uint32_t x = x0; x < x0 + w; ++x) m += f.mean(shader::kChannelEstimate, size_t(y) * f.width() + x);
        return m / double(w * h);
    };
    glm::dvec3 imageA = mean(a, 0, 0, 48, 48), imageB = mean(b, 0, 0, 48, 48);
    glm::dvec3 causticA = mean(a, 26, 38, 12, 6), causticB = mean(b, 26, 38, 12, 6);
    std::printf("image %.4f %.4f (PPM, PT), caustic %.4f %.4f (red)\n", imageA.x, imageB.x, causticA.x, causticB.x);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(imageA[c], imageB[c], 0.04 * imageB[c]) << "channel " << c;
        EXPECT_NEAR(causticA[c], causticB[c], 0.08 * causticB[c]) << "channel " << c;
    }
}
