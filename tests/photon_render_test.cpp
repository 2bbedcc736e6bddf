// Photon mapping on the device against the analytic point light over a diffuse plane
// (scenes/point-plane-photon.json): L = (albedo / pi) I cos(theta) / d^2.
//
// Unbiased photon mapping has infinite variance (tail index a = 1.45 with the default blocks,
// docs/PHOTON-MAPPING.md), so a per-pixel Z-test with the sample variance is meaningless. Each
// test renders B batches of blocks and tests, per image region, the batch means: a t-test with the
// batch means' own spread (Student quantile) and a sign test, both Sidak-corrected over the
// regions. Every unbiasedness test has a positive control at the same sample count: the same
// samples with the correction dropped, which the same tests must reject (docs/TESTING.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "region_stats.h"
#include "render/film_io.h"
#include "render/photon_map.h"
#include "render/renderer.h"
#include "render_harness.h"
#include "shared/photon_density.h"

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

// Batch means of one render: per batch and region, the means of the base and of the correction
// (the estimate is their sum). Batches are consecutive samples of one render (independent: each
// sample draws its photons, pixel samples and level from its own index).
struct Batches {
    std::vector<std::vector<double>> base, correction;  // [region][batch]
    uint64_t passes = 0, samples = 0;
};

Batches renderBatches(const Scene& scene, uint32_t batches, uint32_t samplesPerBatch, uint32_t seed) {
    const size_t regions = (kRes / kBlock) * (kRes / kBlock);
    Batches out;
    out.base.resize(regions);
    out.correction.resize(regions);
    Renderer renderer(sharedContext(), resolved(scene), seed);
    std::vector<double> baseBefore(regions, 0.0), corrBefore(regions, 0.0);
    for (uint32_t b = 0; b < batches; ++b) {
        RenderRequest request;
        request.spp = samplesPerBatch;
        renderer.render(request);
        Film film = renderer.film();
        const double n = double(film.samplesPerPixel());
        auto base = blockMeans(film, kBlock, shader::kChannelBase);
        auto corr = blockMeans(film, kBlock, shader::kChannelCorrection);
        for (size_t r = 0; r < regions; ++r) {
            const double bs = base[r].mean.x * n, cs = corr[r].mean.x * n;
            out.base[r].push_back((bs - baseBefore[r]) / samplesPerBatch);
            out.correction[r].push_back((cs - corrBefore[r]) / samplesPerBatch);
            baseBefore[r] = bs;
            corrBefore[r] = cs;
        }
    }
    out.passes = renderer.stats().integrator.photonPasses;
    out.samples = renderer.stats().samplesPerPixel;
    return out;
}

struct BatchTest {
    size_t tFailures = 0, signFailures = 0, regions = 0;
    double worstT = 0.0;
    std::string worst;
};

// Per region, the batch means of base + weight x correction against the analytic answer: a t-test
// (Student quantile with B - 1 degrees of freedom) and a sign test (the count of batch means above
// the answer is Binomial(B, 1/2) when the batch means are centred on it), each Sidak-corrected
// over the regions at family-wise rate kAlpha: a test's false-alarm rate is at most 2 kAlpha.
// weight = 1 is the estimator; weight = 0 drops the correction; 1 / 1.1 is p(k) mis-weighted by
// 10% (the same samples, so the controls run at the same sample count).
BatchTest batchMeansTest(const Batches& batches, double weight, const char* label) {
    const std::vector<double> want = analyticRegions();
    const uint32_t n = uint32_t(batches.base[0].size());
    const double tLimit = sidakThresholdT(kAlpha, want.size(), n - 1.0);
    const SignTestBounds sign = sidakSignTest(kAlpha, want.size(), n);
    BatchTest t;
    t.regions = want.size();
    for (size_t r = 0; r < want.size(); ++r) {
        double mean = 0.0, var = 0.0;
        uint32_t above = 0;
        std::vector<double> m(n);
        for (uint32_t b = 0; b < n; ++b) {
            m[b] = batches.base[r][b] + weight * batches.correction[r][b];
            mean += m[b] / n;
            above += m[b] > want[r];
        }
        for (double x : m) var += (x - mean) * (x - mean) / (n - 1);
        const double tStat = (mean - want[r]) / std::sqrt(var / n);
        t.tFailures += !(std::abs(tStat) <= tLimit);
        t.signFailures += above < sign.k || above > n - sign.k;
        if (std::abs(tStat) > t.worstT) {
            t.worstT = std::abs(tStat);
            t.worst = fmt::format("region {}: mean {:.5f} vs {:.5f} ({:+.2f}%), t = {:.2f} (limit {:.2f}), {}/{} above "
                                  "(accepted {}..{})",
                                  r, mean, want[r], 100.0 * (mean / want[r] - 1.0), tStat, tLimit, above, n, sign.k,
                                  n - sign.k);
        }
    }
    std::printf("%s: %zu/%zu regions fail the t-test, %zu the sign test; worst %s\n", label, t.tFailures, t.regions,
                t.signFailures, t.worst.c_str());
    return t;
}

class PhotonRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

// A large base radius: the base's bias (-2.6% in the centre regions) makes the control visible.
const char* kUnbiased =
    R"({"type":"photon_map","photon_count":20000,"gather_radius":0.5,"direct_lighting":"photons",
        "debias":{"estimator":"single_term"}})";

void expectUnbiasedWithRejectedControls(const Scene& scene, uint32_t batches, uint32_t perBatch, uint32_t seed) {
    const Batches b = renderBatches(scene, batches, perBatch, seed);
    std::printf("%llu photon passes for %llu samples: %.2f per sample\n", (unsigned long long)b.passes,
                (unsigned long long)b.samples, double(b.passes) / double(b.samples));
    const BatchTest estimator = batchMeansTest(b, 1.0, "estimator");
    EXPECT_EQ(estimator.tFailures, 0u) << estimator.worst;
    EXPECT_EQ(estimator.signFailures, 0u) << estimator.worst;
    const BatchTest dropped = batchMeansTest(b, 0.0, "control, correction dropped");
    EXPECT_GT(dropped.tFailures + dropped.signFailures, 0u) << "the control must fail: " << dropped.worst;
    // p(k) mis-weighted by 10% shifts the mean by a tenth of the base bias (0.3% here): printed for
    // the record, below what 256 samples resolve (docs/TESTING.md; bench/photon_bench measures it).
    batchMeansTest(b, 1.0 / 1.1, "(not asserted) p(k) 10% too large");
}

}  // namespace

TEST_F(PhotonRender, UnbiasedBlocksMatchTheAnalyticPlaneAndControlsFail) {
    expectUnbiasedWithRejectedControls(plane(kUnbiased), 32, 8, 100);
}

TEST_F(PhotonRender, UnbiasedProgressiveBlocksMatchTheAnalyticPlaneAndControlsFail) {
    expectUnbiasedWithRejectedControls(
        plane(R"({"type":"progressive_photon_map","photon_count":20000,"gather_radius":1.0,"direct_lighting":"photons",
                  "debias":{"estimator":"single_term"}})"),
        32, 4, 200);
}

TEST_F(PhotonRender, OtherKernelsAndBlockSettingsMatchTheAnalyticPlane) {
    for (const char* kernel : {"epanechnikov", "uniform"}) {
        const Batches b = renderBatches(
            plane(fmt::format(R"({{"type":"photon_map","photon_count":20000,"gather_radius":0.5,"direct_lighting":"photons",
                              "kernel":"{}","debias":{{"estimator":"single_term","pmf":{{"type":"geometric","r":0.6}},
                              "area_ratio":0.8,"photon_growth":2}}}})",
                              kernel)),
            32, 8, 250);
        BatchTest t = batchMeansTest(b, 1.0, kernel);
        EXPECT_EQ(t.tFailures, 0u) << kernel << ": " << t.worst;
        EXPECT_EQ(t.signFailures, 0u) << kernel << ": " << t.worst;
        BatchTest control = batchMeansTest(b, 0.0, "control, correction dropped");
        EXPECT_GT(control.tFailures + control.signFailures, 0u) << kernel << ": " << control.worst;
    }
}

TEST_F(PhotonRender, BiasedLargeRadiusFailsTheSameTest) {
    const Batches b = renderBatches(
        plane(R"({"type":"photon_map","photon_count":20000,"gather_radius":0.5,"direct_lighting":"photons"})"), 32, 8, 300);
    BatchTest t = batchMeansTest(b, 1.0, "biased");
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
    Renderer renderer(sharedContext(), resolved(scene), 600);
    RenderRequest request;
    request.spp = 16;
    renderer.render(request);
    EXPECT_EQ(renderer.stats().integrator.photonsStored, 0u);
    const std::vector<double> want = analyticRegions();
    auto regions = blockMeans(renderer.film(), kBlock);
    for (size_t r = 0; r < want.size(); ++r) EXPECT_NEAR(regions[r].mean.x, want[r], 0.02 * want[r]) << "region " << r;
}

TEST_F(PhotonRender, UnbiasedPixelsGoNegative) {
    // Signed corrections reach the film unclamped: at a small base radius a few of 8 blocks give
    // negative pixels.
    Film film = renderFilm(plane(R"({"type":"photon_map","photon_count":20000,"gather_radius":0.05,
                                     "direct_lighting":"photons","debias":{"estimator":"single_term"}})"),
                           8, 500);
    size_t negative = 0, negativeCorrection = 0;
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        negative += film.mean(shader::kChannelEstimate, i).x < 0.0;
        negativeCorrection += film.mean(shader::kChannelCorrectionNegative, i).x < 0.0;
    }
    EXPECT_GT(negative, 0u);
    EXPECT_GT(negativeCorrection, negative);
    EXPECT_EQ(film.nonFiniteSamples(), 0u);
}

TEST_F(PhotonRender, PerPixelScheduleIsConsistent) {
    // Each pixel draws its own levels and counts its own completed blocks; unfinished blocks are
    // dropped. The count per pixel is a renewal process with block lengths 3^k, k ~ p(k): its mean
    // and variance after 192 passes follow from the pmf (the mean of 256 independent pixels is
    // checked at 5 standard errors). The regions are within a few percent of the answer.
    Scene scene = plane(R"({"type":"photon_map","photon_count":20000,"gather_radius":0.5,"direct_lighting":"photons",
                            "debias":{"estimator":"single_term","level_schedule":"per_pixel"}})");
    Film film = renderFilm(scene, 192, 550);
    ASSERT_TRUE(film.perPixelCounts());
    double counted = 0.0;
    for (size_t i = 0; i < film.pixelCount(); ++i) counted += film.samplesOf(i);
    const double perPixel = counted / double(film.pixelCount());
    // E[N(t)] and E[N(t)^2] of the renewal count, by recursion over t.
    const shader::PhotonLevels levels{0.7f, float(std::log(std::sqrt(0.5))), 3u, 20u};
    std::vector<double> m1(193, 0.0), m2(193, 0.0);
    for (uint32_t t = 1; t <= 192; ++t)
        for (uint32_t k = 0; k < levels.cap; ++k) {
            const uint32_t x = shader::photonBlockPasses(levels, k);
            if (x > t) break;
            const double p = shader::photonLevelProbability(levels, k);
            m1[t] += p * (1.0 + m1[t - x]);
            m2[t] += p * (1.0 + 2.0 * m1[t - x] + m2[t - x]);
        }
    const double sd = std::sqrt((m2[192] - m1[192] * m1[192]) / double(film.pixelCount()));
    EXPECT_NEAR(perPixel, m1[192], 5.0 * sd) << "blocks completed per pixel (192 / 6.15 = 31 if no block were cut)";
    const std::vector<double> want = analyticRegions();
    auto regions = blockMeans(film, kBlock);
    double error = 0.0;
    for (size_t r = 0; r < want.size(); ++r) error += std::abs(regions[r].mean.x / want[r] - 1.0) / want.size();
    EXPECT_LT(error, 0.03) << "mean relative error of the regions";
}

TEST_F(PhotonRender, SixteenMillionPhotons) {
    // 2^25 + 2^22 photon paths, of which about 45% reach the plane: over 16 M stored photons (over
    // 512 MiB of photons, beyond the 128 MiB binding limit) in one pass.
    Scene scene = loadTestScene(kScene, {{"camera.resolution", "[16,16]"},
                                         {"integrator", R"({"type":"photon_map","photon_count":37748736,
                                           "gather_radius":0.02,"direct_lighting":"photons"})"}});
    Renderer renderer(sharedContext(), resolved(scene), 1);
    RenderRequest request;
    request.spp = 1;
    renderer.render(request);
    EXPECT_GE(renderer.stats().integrator.photonsStored, 16u << 20);
    Film film = renderer.film();
    const std::vector<double> want = analyticRegions();
    auto regions = blockMeans(film, kBlock);
    // The centre (regions 5, 6, 9, 10: 8x8 pixels): the biased estimate at r = 0.02 is within 2%.
    // (One pixel, one gather point each: a single region of 4x4 is 2-3% off in some seeds.)
    double got = 0.0, expected = 0.0;
    for (size_t r : {5, 6, 9, 10}) {
        got += regions[r].mean.x / 4.0;
        expected += want[r] / 4.0;
    }
    EXPECT_NEAR(got, expected, 0.02 * expected);
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

TEST_F(PhotonRender, GatherSlicesLeaveTheFilmUnchanged) {
    // A pass whose fullest bucket holds more photons than one gather dispatch reads runs the gather
    // in slices; a pixel completes its pass in the first slice after which its own buckets hold no
    // more photons and sits out the rest. With the slice lowered to 8 photons a bucket (2 for k nearest)
    // (TELESCOPE_GATHER_SLICE), the caustic Cornell box's gathers run in dozens of slices a pass,
    // and the film must equal the one gathered in one or two but for float rounding: the k nearest
    // are the same photons, summed in the order the heap was left in; fixed radii add the slices'
    // sums in turn.
    // A pixel that finished before its last bucket's photons, or that added a finished pass again
    // in a later slice, would change it.
    const uint32_t paths = 20000;
    for (const char* gatherCount : {"20", "0"}) {
        SCOPED_TRACE(std::string("gather_photon_count ") + gatherCount);
        Scene scene = loadTestScene("scenes/cornell-box-caustic.json", {{"camera.resolution", "[32,32]"},
                                                                        {"integrator.debias", "null"},
                                                                        {"integrator.photon_count", std::to_string(paths)},
                                                                        {"integrator.gather_radius", "0.1"},
                                                                        {"integrator.gather_photon_count", gatherCount}});
        RenderRequest request;
        request.spp = 3;
        Renderer whole(sharedContext(), resolved(scene), 901);
        whole.render(request);
        const uint64_t fewSlices = whole.stats().passes.at("gather").dispatches;

        // (the k-nearest gather's cells are a quarter of the side: its buckets hold fewer photons)
        ASSERT_EQ(setenv("TELESCOPE_GATHER_SLICE", std::string(gatherCount) == "0" ? "8" : "2", 1), 0);
        Renderer sliced(sharedContext(), resolved(scene), 901);
        sliced.render(request);
        unsetenv("TELESCOPE_GATHER_SLICE");
        const uint64_t manySlices = sliced.stats().passes.at("gather").dispatches;
        EXPECT_LE(fewSlices, 3u * 3u) << "the unsliced render should gather in at most a few slices a pass";
        EXPECT_GE(manySlices, 3u * 20u) << "the sliced render should gather in many slices a pass";

        const Film a = whole.film(), b = sliced.film();
        ASSERT_EQ(a.pixelCount(), b.pixelCount());
        size_t lit = 0;
        for (size_t i = 0; i < a.pixelCount(); ++i) {
            const glm::dvec3 x = a.mean(shader::kChannelEstimate, i), y = b.mean(shader::kChannelEstimate, i);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(x[c], y[c], 1e-5 * std::abs(x[c]) + 1e-12) << "pixel " << i << " channel " << c;
            lit += x.x > 0.0;
        }
        EXPECT_GT(lit, a.pixelCount() / 2);
    }
}

TEST_F(PhotonRender, PhotonsReadByAddressGiveTheSameFilm) {
    // The gather reads the sorted photons through a texel buffer, or by address when they exceed
    // the device's texel-buffer limit (a gather pipeline of its own, swapped in when the photon map
    // grows past the limit). With the limit lowered to the first pass's capacity, the photon map
    // outgrows it in the first pass (the caustic Cornell box stores more photons than it emits
    // paths), so the gather must switch; the film must equal the one read through texels, but for
    // the order in which the scatter's atomics leave each bucket's photons (float rounding). The
    // unbiased estimator (its blocks cut to one pass at level 0) keeps every photon of its paths;
    // biased photon mapping would stop near photon_count photons (docs/PHOTON-MAPPING.md).
    const uint32_t paths = 20000;
    Scene scene = loadTestScene("scenes/cornell-box-caustic.json", {{"camera.resolution", "[32,32]"},
                                                                    {"integrator.debias.level_cap", "1"},
                                                                    {"integrator.direct_lighting", R"("photons")"},
                                                                    {"integrator.photon_count", std::to_string(paths)},
                                                                    {"integrator.gather_radius", "0.05"}});
    Renderer texels(sharedContext(), resolved(scene), 900);
    RenderRequest request;
    request.spp = 3;
    texels.render(request);
    ASSERT_GT(texels.stats().integrator.photonsStored, uint64_t(3 * paths)) << "the photon map must outgrow its first capacity";

    const std::string limit = std::to_string(2 * paths);  // texels of `paths` photons
    ASSERT_EQ(setenv("TELESCOPE_MAX_TEXELS", limit.c_str(), 1), 0);
    {
        PhotonMap map(sharedContext(), paths);  // the limit is what sends the grown map to addresses
        EXPECT_TRUE(map.texelsFit());
        map.reserve(paths + 1);
        EXPECT_FALSE(map.texelsFit());
    }
    Renderer byAddress(sharedContext(), resolved(scene), 900);
    byAddress.render(request);
    unsetenv("TELESCOPE_MAX_TEXELS");

    const Film a = texels.film(), b = byAddress.film();
    ASSERT_EQ(a.pixelCount(), b.pixelCount());
    size_t lit = 0;
    for (size_t i = 0; i < a.pixelCount(); ++i) {
        const glm::dvec3 x = a.mean(shader::kChannelEstimate, i), y = b.mean(shader::kChannelEstimate, i);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(x[c], y[c], 1e-5 * std::abs(x[c]) + 1e-12) << "pixel " << i << " channel " << c;
        lit += x.x > 0.0;
    }
    EXPECT_GT(lit, a.pixelCount() / 2);
}

namespace {

// A render of `spp` samples stopped before its `stopAt`-th batch (a signal): its film, with the
// samples in progress.
Film interruptedFilm(const Scene& scene, uint32_t seed, uint64_t spp, uint32_t stopAt) {
    Renderer renderer(sharedContext(), resolved(scene), seed);
    RenderRequest request;
    request.spp = spp;
    uint32_t asked = 0;
    request.stop = [&] { return ++asked > stopAt; };
    renderer.render(request);
    return renderer.film();
}

// The film of `film`'s render continued to `spp` samples, through a checkpoint file; the photon
// passes the continuation ran in *passes.
Film resumedFilm(const Scene& scene, uint32_t seed, const Film& film, uint64_t spp, uint64_t* passes) {
    const std::string path = (std::filesystem::temp_directory_path() / "telescope-pending-block.ckpt").string();
    saveCheckpoint(path, Checkpoint{film, seed, "{}", "", "", {seed}});
    const Film restored = loadCheckpoint(path).film;
    std::filesystem::remove(path);
    Renderer renderer(sharedContext(), resolved(scene), seed);
    renderer.resume(restored);
    RenderRequest request;
    request.spp = spp - restored.samplesPerPixel();
    renderer.render(request);
    if (passes) *passes = renderer.stats().integrator.photonPasses;
    return renderer.film();
}

}  // namespace

TEST_F(PhotonRender, AnInterruptedBlockResumesWhereItStopped) {
    // Uniform schedule: a level-k block is 3^k photon passes, one sample. A render stopped inside
    // a long block keeps the block's passes and sums (Film::pending, saved in the checkpoint);
    // resumed, it equals the uninterrupted render up to float rounding (the scatter's atomics order
    // each bucket's photons differently in every run: two uninterrupted renders differ as much) and
    // traces no pass twice. Controls: the block's sums lost (the passes done are kept) fail the
    // equality; the whole block dropped passes it (the same random numbers restart the block) but
    // traces the interrupted passes again, which a time-limited Slurm task may never get past.
    Scene scene = plane(R"({"type":"photon_map","photon_count":4000,"gather_radius":0.5,"direct_lighting":"photons",
                            "debias":{"estimator":"single_term"}})");
    uint32_t seed = 1;
    while (photonBlockLevel(scene.integrator.debias, 0, seed) < 2) ++seed;  // block 0: 9 passes or more
    const uint64_t blocks = 3;
    Renderer whole(sharedContext(), resolved(scene), seed);
    RenderRequest request;
    request.spp = blocks;
    whole.render(request);
    const Film wholeFilm = whole.film();
    EXPECT_TRUE(wholeFilm.pending().empty()) << "a render that ran its blocks to the end has none in progress";
    const Film again = renderFilm(scene, blocks, seed);
    const double floor = 1e-3;
    const double rounding = largestRelativeDifference(again, wholeFilm, floor);

    const Film part = interruptedFilm(scene, seed, blocks, 4);
    ASSERT_EQ(part.samplesPerPixel(), 0u);
    const PendingSamples& p = part.pending();
    ASSERT_GT(p.unitsDone, 0u);
    ASSERT_LT(p.unitsDone, p.unitsTotal);
    EXPECT_EQ(p.level, photonBlockLevel(scene.integrator.debias, 0, seed));
    uint64_t passes = 0;
    const Film resumed = resumedFilm(scene, seed, part, blocks, &passes);
    const double tolerance = std::max(1e-5, 10.0 * rounding);
    std::printf("two uninterrupted renders differ by %.3g, the resumed one by %.3g (tolerance %.3g)\n", rounding,
                largestRelativeDifference(resumed, wholeFilm, floor), tolerance);
    EXPECT_LT(largestRelativeDifference(resumed, wholeFilm, floor), tolerance);
    EXPECT_EQ(passes + p.unitsDone, whole.stats().integrator.photonPasses) << "passes traced twice or skipped";

    Film lostSums = part;
    PendingSamples zeroed = part.pending();
    std::fill(zeroed.device.begin(), zeroed.device.end(), uint8_t(0));
    lostSums.setPending(zeroed);
    EXPECT_GT(largestRelativeDifference(resumedFilm(scene, seed, lostSums, blocks, nullptr), wholeFilm, floor), 100 * tolerance)
        << "the control (the block's sums lost) passed";
    Film dropped = part;
    dropped.setPending({});
    uint64_t droppedPasses = 0;
    EXPECT_LT(largestRelativeDifference(resumedFilm(scene, seed, dropped, blocks, &droppedPasses), wholeFilm, floor), tolerance);
    EXPECT_EQ(droppedPasses, whole.stats().integrator.photonPasses) << "dropping the block retraces its passes";

    // A block that is not this render's (another seed draws another level for block 0) is refused.
    uint32_t other = seed + 1;
    while (photonBlockLevel(scene.integrator.debias, 0, other) == p.level) ++other;
    Renderer wrong(sharedContext(), resolved(scene), other);
    EXPECT_THROW(wrong.resume(part), std::invalid_argument);
}

TEST_F(PhotonRender, PerPixelBlocksResumeWhereTheyStopped) {
    // per_pixel: every pixel keeps its own block across passes. Resumed with them, the render
    // equals the uninterrupted one; without them (the control) each pixel starts a new block at
    // the resumed pass, and the pixels differ.
    Scene scene = plane(R"({"type":"photon_map","photon_count":4000,"gather_radius":0.5,"direct_lighting":"photons",
                            "debias":{"estimator":"single_term","level_schedule":"per_pixel"}})");
    const uint32_t seed = 21;
    const uint64_t passes = 24;
    const Film wholeFilm = renderFilm(scene, passes, seed);
    const double floor = 1e-3;
    const double tolerance = std::max(1e-5, 10.0 * largestRelativeDifference(renderFilm(scene, passes, seed), wholeFilm, floor));
    const Film part = interruptedFilm(scene, seed, passes, 11);
    ASSERT_GT(part.samplesPerPixel(), 0u);
    ASSERT_LT(part.samplesPerPixel(), passes);
    ASSERT_FALSE(part.pending().device.empty());
    EXPECT_LT(largestRelativeDifference(resumedFilm(scene, seed, part, passes, nullptr), wholeFilm, floor), tolerance);
    Film dropped = part;
    dropped.setPending({});
    EXPECT_GT(largestRelativeDifference(resumedFilm(scene, seed, dropped, passes, nullptr), wholeFilm, floor), 100 * tolerance)
        << "the control (blocks dropped) passed";
}
