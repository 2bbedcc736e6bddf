// Media and transmittance (docs/BENCHMARKS.md, "Media and transmittance"): work x MSE of every
// transmittance estimator in renders of the absorbing slab and the smoke box, density lookups per
// second of the shared estimator code, and the MSE slope of debiased marching. Run through
// bench/run.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "bench_main.h"
#include "gpu/context.h"
#include "render/pmf_pilot.h"
#include "render/renderer.h"
#include "scene/density_grid.h"
#include "scene/scene_loader.h"
#include "shared/transmittance_estimators.h"

using namespace telescope;
using telescope::bench::context;

namespace {

const std::map<std::string, std::string> kEstimators = {
    {"ray_march_k1", R"({"type":"ray_march","level":1})"},
    {"debiased_ray_march", R"({"type":"debiased_ray_march","level":1})"},
    {"delta_tracking", R"({"type":"delta_tracking"})"},
    {"ratio_tracking", R"({"type":"ratio_tracking"})"},
    {"residual_ratio_tracking", R"({"type":"residual_ratio_tracking"})"},
    {"unbiased_ray_march", R"({"type":"unbiased_ray_march"})"},
    {"taylor", R"({"type":"taylor"})"},
};

// Closed form of scenes/absorbing-slab.json per pixel (see tests/media_render_test.cpp).
double slabClosedForm(const Camera& cam, uint32_t x, uint32_t y) {
    const double plane = 1.0 / std::tan(0.5 * cam.fovDegrees * 3.14159265358979323846 / 180.0);
    const double lx = -1.0 + 2.0 * (x + 0.5) / cam.width, ly = double(cam.height) / cam.width - 2.0 * (y + 0.5) / cam.width;
    const double cosZ = plane / std::sqrt(lx * lx + ly * ly + plane * plane);
    const double tauAxis = ly > 0 ? 1.2 : 3.0 * (1.0 - std::exp(-3.0)) / 3.0;
    return std::exp(-tauAxis / cosZ);
}

// Work x MSE of a render: render seconds (pipeline compiled before timing) times the mean over
// pixels of the squared error against the closed form (slab) or of the variance of the mean
// (smoke box: unbiased estimators only, whose MSE is their variance).
// One render of the scene at spp (seed 7): the film and the render's wall seconds.
Film timedRender(const Scene& scene, uint64_t spp, double& seconds) {
    Renderer renderer(context(), resolveScene(context(), scene, 1).scene, 7);
    RenderRequest request;
    request.spp = spp;
    renderer.render(request);
    seconds = renderer.stats().wallSeconds;
    return renderer.film();
}

void renderEfficiency(benchmark::State& state, const std::string& sceneName, const std::string& estimator) {
    const bool slab = sceneName == "absorbing-slab";
    std::vector<SceneOverride> overrides = {{"camera.resolution", slab ? "[64,64]" : "[48,36]"},
                                            {"integrator.transmittance_estimator", kEstimators.at(estimator)}};
    Scene scene = loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/" + sceneName + ".json", overrides);
    const uint64_t spp = slab ? 64 : 16;
    double seconds = 0.0, workMse = 0.0, mse = 0.0;
    for (auto _ : state) {
        Film film = timedRender(scene, spp, seconds);
        double sum = 0.0;
        for (uint32_t y = 0; y < film.height(); ++y)
            for (uint32_t x = 0; x < film.width(); ++x) {
                const size_t i = size_t(y) * film.width() + x;
                if (slab) {
                    const double e = film.mean(0, i).x - slabClosedForm(scene.camera, x, y);
                    sum += e * e;
                } else {
                    const glm::dvec3 v = film.varianceOfMean(i);
                    sum += (v.x + v.y + v.z) / 3.0;
                }
            }
        mse = sum / double(film.pixelCount());
        workMse = seconds * mse;
        state.SetIterationTime(seconds);
    }
    state.counters["render_s"] = seconds;
    state.counters["mse"] = mse;
    state.counters["work_x_mse"] = workMse;
}

// Expected loop iterations of the grid trackers (shaders/medium.glsl, trTrackGrid) per segment,
// from the majorant grid alone: tentative collisions (the cells' majorant optical depth along the
// segment) and cells entered (one DDA step each), over 4096 segments from uniform points in the grid
// box in uniform directions to the box's face (a shadow ray from inside the cloud). Marched in steps
// of 1/16 of a voxel, so a cell clipped at a corner may be missed. A model of the loop's cost, not
// a measurement on the device.
glm::dvec2 trackingLoopSteps(const DensityGrid& grid, glm::dvec3 sigmaT) {
    const std::vector<glm::vec2> cells = majorantGrid(grid);
    const glm::uvec3 res = majorantResolution(grid);
    const glm::dvec3 scale = grid.majorantCell == 0 ? glm::dvec3(1.0)
                                                     : glm::dvec3(grid.resolution) / double(grid.majorantCell);
    const glm::dmat4 toWorld(grid.unitToWorld);
    const double sMax = std::max(sigmaT.x, std::max(sigmaT.y, sigmaT.z));
    uint64_t state = 12345;
    auto uniform = [&] {
        state = state * 6364136223846793005ull + 1442695040888963407ull;
        return double(state >> 11) * 0x1.0p-53;
    };
    double collisions = 0.0, entered = 0.0;
    const int rays = 4096;
    const double du = 1.0 / (16.0 * std::max(grid.resolution.x, std::max(grid.resolution.y, grid.resolution.z)));
    for (int r = 0; r < rays; ++r) {
        glm::dvec3 u(uniform(), uniform(), uniform());
        const double z = 1.0 - 2.0 * uniform(), phi = 6.283185307179586 * uniform(), sr = std::sqrt(1.0 - z * z);
        const glm::dvec3 worldDir(sr * std::cos(phi), sr * std::sin(phi), z);
        // the direction in unit-box coordinates and the world length of one unit-box step along it
        glm::dvec3 ud = glm::inverse(glm::dmat3(toWorld)) * worldDir;
        const double perUnit = 1.0 / glm::length(ud);
        ud *= perUnit;  // unit-box step of world length perUnit
        glm::ivec3 last(-1);
        while (u.x >= 0.0 && u.y >= 0.0 && u.z >= 0.0 && u.x <= 1.0 && u.y <= 1.0 && u.z <= 1.0) {
            const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor(u * scale)), glm::ivec3(0), glm::ivec3(res) - 1);
            if (c != last) entered += 1.0;
            last = c;
            const double mu = sMax * cells[(size_t(c.z) * res.y + c.y) * res.x + c.x].y;
            collisions += mu * du * perUnit;
            u += ud * du;
        }
    }
    return {collisions / rays, entered / rays};
}

// The majorant grid against one global majorant (docs/MEDIA.md): the Davis cloud (a sparse
// procedural grid) with exponential transmittance so that the trackers apply, rendered with
// majorant cells of `cell` voxels (0: one majorant for the grid). MSE = variance of the pixel mean
// (unbiased estimators); also the mean over the grid's volume of the cell majorant relative to the
// global one (the expected tentative collisions per unit length, relative).
// `absorbing`: sigma_s 0 and sigma_a 5 (the cloud's extinction), so that paths are straight lines
// through the cloud and the transmittance estimates are most of the work and all of the noise.
// `extinction`: sigma_a of the absorbing variants (5.05: the cloud's own extinction; 50.5: ten
// times denser, where the global majorant's optical depth is large against the cells crossed).
void majorantEfficiency(benchmark::State& state, const std::string& estimator, uint32_t cell, bool absorbing,
                        double extinction) {
    std::vector<SceneOverride> overrides = {{"camera.resolution", "[48,32]"},
                                            {"media[0].transmittance", R"({"type":"exponential"})"},
                                            {"media[0].grid.majorant_cell", std::to_string(cell)},
                                            {"integrator.transmittance_estimator", kEstimators.at(estimator)}};
    if (absorbing) {
        overrides.push_back({"media[0].sigma_s", "0"});
        overrides.push_back({"media[0].sigma_a", fmt::format("{}", extinction)});
    }
    Scene scene = loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/davis-cloud.json", overrides);
    const uint64_t spp = 64;
    double seconds = 0.0, mse = 0.0;
    for (auto _ : state) {
        Film film = timedRender(scene, spp, seconds);
        double sum = 0.0;
        for (size_t i = 0; i < film.pixelCount(); ++i) {
            const glm::dvec3 v = film.varianceOfMean(i);
            sum += (v.x + v.y + v.z) / 3.0;
        }
        mse = sum / double(film.pixelCount());
        state.SetIterationTime(seconds);
    }
    const DensityGrid& grid = scene.media[0].grid;
    const std::vector<glm::vec2> cells = majorantGrid(grid);
    const glm::uvec3 res = majorantResolution(grid);
    double volume = 0.0, weighted = 0.0, global = 0.0;
    for (float d : grid.density) global = std::max(global, double(d));
    for (uint32_t z = 0; z < res.z; ++z)
        for (uint32_t y = 0; y < res.y; ++y)
            for (uint32_t x = 0; x < res.x; ++x) {
                // the cell's share of the grid (the last cell along an axis may be partial)
                glm::dvec3 size(1.0);
                if (cell > 0)
                    for (int a = 0; a < 3; ++a)
                        size[a] = double(std::min((glm::uvec3(x, y, z)[a] + 1) * cell, grid.resolution[a]) -
                                         glm::uvec3(x, y, z)[a] * cell);
                const double v = size.x * size.y * size.z;
                volume += v;
                weighted += v * cells[(size_t(z) * res.y + y) * res.x + x].y;
            }
    size_t empty = 0;
    for (float d : grid.density) empty += d == 0.0f;
    const glm::dvec2 steps = trackingLoopSteps(grid, glm::dvec3(scene.media[0].sigmaA + scene.media[0].sigmaS));
    state.counters["render_s"] = seconds;
    state.counters["mse"] = mse;
    state.counters["work_x_mse"] = seconds * mse;
    state.counters["majorant_ratio"] = weighted / volume / global;
    state.counters["empty_voxels"] = double(empty) / double(grid.density.size());
    state.counters["collisions"] = steps.x;
    state.counters["cells"] = steps.y;
}

// Density lookups per second of the shared estimator code on the CPU (one thread): a segment of
// Tungsten's exponential medium, optical depth 1.5, exponential transmittance.
void lookupsPerSecond(benchmark::State& state, uint32_t type) {
    using namespace shader;
    TrSegment s{};
    s.profile = makeProfile(kProfileExponential, 1.5f * 3.0f / (1.0f - std::exp(-3.0f)), 3.0f, 0.0f);
    s.sigmaT = glm::vec3(1.0f);
    s.len = 1.0f;
    glm::vec2 b = profileBounds(s.profile, 0.0f, 1.0f);
    s.densityMin = b.x;
    s.densityMax = b.y;
    const TransmittanceEstimatorSettings defaults;
    TrEstimator e{type, 1, LevelPmf{kPmfGeometric, 0.65f, 0.0f}, defaults.terms, defaults.points};
    TrModel m = trSimple(kTrExponential, glm::vec4(0.0f));
    uint32_t lookups = 0, i = 0;
    float sink = 0.0f;
    for (auto _ : state) {
        Rng rng = rngCreate(i++, 3u, 5u);
        sink += trEstimate(e, m, kFormSurfaceSurface, s, rng, lookups).x;
    }
    benchmark::DoNotOptimize(sink);
    state.counters["lookups_per_s"] = benchmark::Counter(double(lookups), benchmark::Counter::kIsRate);
    state.counters["lookups_per_estimate"] = double(lookups) / double(state.iterations());
}

// MSE of the mean of N debiased estimates against the closed form, N = 2^4 .. 2^14 (200
// repetitions each); the least-squares slope of log MSE against log N (theory: -1).
void debiasedMseSlope(benchmark::State& state) {
    using namespace shader;
    TrSegment s{};
    s.profile = makeProfile(kProfileSine, 2.0f, 0.9f, 2.3f);
    s.sigmaT = glm::vec3(1.0f);
    s.len = 1.0f;
    glm::vec2 b = profileBounds(s.profile, 0.0f, 1.0f);
    s.densityMin = b.x;
    s.densityMax = b.y;
    TrModel m = trSimple(kTrDavis, glm::vec4(1.5625f, 0, 0, 0));
    const double truth = trForm(m, kFormSurfaceSurface, float(profileIntegral(s.profile, 0.0, 1.0)));
    TrEstimator e{kTrEstDebiasedRayMarch, 1, LevelPmf{kPmfGeometric, 0.65f, 0.0f}};
    double slope = 0.0;
    for (auto _ : state) {
        std::vector<double> xs, ys;
        uint32_t stream = 0;
        for (uint32_t logN = 4; logN <= 14; logN += 2) {
            const uint32_t n = 1u << logN;
            double sq = 0.0;
            const int reps = 200;
            for (int r = 0; r < reps; ++r) {
                double sum = 0.0;
                uint32_t lookups = 0;
                for (uint32_t i = 0; i < n; ++i) {
                    Rng rng = rngCreate(i, stream, 17u);
                    sum += trEstimate(e, m, kFormSurfaceSurface, s, rng, lookups).x;
                }
                ++stream;
                const double err = sum / n - truth;
                sq += err * err;
            }
            xs.push_back(std::log(double(n)));
            ys.push_back(std::log(sq / reps));
        }
        double mx = 0, my = 0;
        for (size_t i = 0; i < xs.size(); ++i) { mx += xs[i] / xs.size(); my += ys[i] / ys.size(); }
        double sxy = 0, sxx = 0;
        for (size_t i = 0; i < xs.size(); ++i) { sxy += (xs[i] - mx) * (ys[i] - my); sxx += (xs[i] - mx) * (xs[i] - mx); }
        slope = sxy / sxx;
    }
    state.counters["mse_slope"] = slope;
}

}  // namespace

#define RENDER_BENCH(scene, est)                                                                       \
    BENCHMARK_CAPTURE(renderEfficiency, scene##_##est, std::string(#scene) == "slab" ? "absorbing-slab" \
                                                                                      : "smoke-box",    \
                      #est)                                                                            \
        ->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond)
RENDER_BENCH(slab, ray_march_k1);
RENDER_BENCH(slab, debiased_ray_march);
RENDER_BENCH(slab, delta_tracking);
RENDER_BENCH(slab, ratio_tracking);
RENDER_BENCH(slab, residual_ratio_tracking);
RENDER_BENCH(slab, unbiased_ray_march);
RENDER_BENCH(slab, taylor);
RENDER_BENCH(smoke, debiased_ray_march);
RENDER_BENCH(smoke, delta_tracking);
RENDER_BENCH(smoke, ratio_tracking);
RENDER_BENCH(smoke, residual_ratio_tracking);
RENDER_BENCH(smoke, unbiased_ray_march);
RENDER_BENCH(smoke, taylor);

#define MAJORANT_BENCH(kind, absorbing, extinction, est, cell)                                           \
    BENCHMARK_CAPTURE(majorantEfficiency, kind##_##est##_cell##cell, #est, cell, absorbing, extinction)  \
        ->Iterations(1)->UseManualTime()->Unit(benchmark::kMillisecond)
#define MAJORANT_BENCHES(kind, absorbing, extinction)                          \
    MAJORANT_BENCH(kind, absorbing, extinction, delta_tracking, 0);          \
    MAJORANT_BENCH(kind, absorbing, extinction, delta_tracking, 8);          \
    MAJORANT_BENCH(kind, absorbing, extinction, delta_tracking, 4);          \
    MAJORANT_BENCH(kind, absorbing, extinction, ratio_tracking, 0);          \
    MAJORANT_BENCH(kind, absorbing, extinction, ratio_tracking, 8);          \
    MAJORANT_BENCH(kind, absorbing, extinction, ratio_tracking, 4);          \
    MAJORANT_BENCH(kind, absorbing, extinction, residual_ratio_tracking, 0); \
    MAJORANT_BENCH(kind, absorbing, extinction, residual_ratio_tracking, 8); \
    MAJORANT_BENCH(kind, absorbing, extinction, residual_ratio_tracking, 4)
MAJORANT_BENCHES(absorbing, true, 5.05);
MAJORANT_BENCHES(dense, true, 50.5);
MAJORANT_BENCHES(scattering, false, 0.0);

BENCHMARK_CAPTURE(lookupsPerSecond, ray_march_k1, shader::kTrEstRayMarch);
BENCHMARK_CAPTURE(lookupsPerSecond, debiased_ray_march, shader::kTrEstDebiasedRayMarch);
BENCHMARK_CAPTURE(lookupsPerSecond, delta_tracking, shader::kTrEstDeltaTracking);
BENCHMARK_CAPTURE(lookupsPerSecond, ratio_tracking, shader::kTrEstRatioTracking);
BENCHMARK_CAPTURE(lookupsPerSecond, residual_ratio_tracking, shader::kTrEstResidualRatioTracking);
BENCHMARK_CAPTURE(lookupsPerSecond, unbiased_ray_march, shader::kTrEstUnbiasedRayMarch);
BENCHMARK_CAPTURE(lookupsPerSecond, taylor, shader::kTrEstTaylor);
BENCHMARK(debiasedMseSlope)->Iterations(1)->Unit(benchmark::kSecond);

// ---- Markdown tables of the results ----
namespace {

std::string tables(const bench::Runs& runs) {
    using Run = benchmark::BenchmarkReporter::Run;
    auto counter = [](const Run& r, const char* name) {
        auto it = r.counters.find(name);
        return it == r.counters.end() ? 0.0 : double(it->second);
    };
    auto label = [](const Run& r) {
        std::string n = r.benchmark_name();
        std::string s = n.substr(n.find('/') + 1);
        return s.substr(0, s.find('/'));
    };
    std::string s;
    for (const char* scene : {"slab_", "smoke_"}) {
        double ratio = 0.0;
        for (const auto& r : runs)
            if (label(r) == std::string(scene) + "ratio_tracking") ratio = counter(r, "work_x_mse");
        s += std::string(scene) == "slab_"
                 ? "\n**Absorbing slab** (64x64, 64 spp; MSE per pixel against the closed form):\n\n"
                 : "\n**Smoke box** (48x36, 16 spp; MSE = variance of the pixel mean, unbiased estimators):\n\n";
        s += "| estimator | render s | MSE | work x MSE | / ratio tracking |\n|---|---|---|---|---|\n";
        for (const auto& r : runs) {
            std::string l = label(r);
            if (l.rfind(scene, 0) != 0) continue;
            double w = counter(r, "work_x_mse");
            s += fmt::format("| {} | {:.3f} | {:.3g} | {:.3g} | {:.2f} |\n", l.substr(std::string(scene).size()),
                             counter(r, "render_s"), counter(r, "mse"), w, ratio > 0 ? w / ratio : 0.0);
        }
    }
    bool majorantHeader = false;
    for (const auto& r : runs) {
        if (r.benchmark_name().rfind("majorantEfficiency", 0) != 0) continue;
        const std::string l = label(r);
        const std::string kind = l.substr(0, l.find('_'));
        const std::string est = l.substr(kind.size() + 1, l.rfind("_cell") - kind.size() - 1),
                          cell = l.substr(l.rfind("_cell") + 5);
        double global = 0.0;
        for (const auto& g : runs)
            if (label(g) == kind + "_" + est + "_cell0") global = counter(g, "work_x_mse");
        if (!majorantHeader) {
            s += fmt::format("\n**Majorant grid against one global majorant** (Davis cloud with exponential "
                             "transmittance, 48x32, 64 spp; {:.0f}% of its voxels empty; absorbing: sigma_s 0, sigma_a "
                             "5.05, so paths are straight and the trackers are the noise; dense: sigma_a 50.5; "
                             "scattering: the scene's "
                             "sigma_s 5; MSE = variance of the pixel mean; mean majorant = the cells' majorant "
                             "averaged over the grid's volume, relative to the global one, i.e. the tentative "
                             "collisions per unit length; collisions + cells: the loop iterations of delta and ratio "
                             "tracking per segment from a point in the box to its face, from the majorant grid alone "
                             "(a host model, `trackingLoopSteps`), residual ratio tracking collides at half the "
                             "cells' max - min instead):\n\n",
                             100.0 * counter(r, "empty_voxels"));
            s += "| cloud | estimator | majorant cell (voxels) | mean majorant | collisions + cells per segment (model) | render s | MSE | work x MSE | / global |\n"
                 "|---|---|---|---|---|---|---|---|---|\n";
            majorantHeader = true;
        }
        const double w = counter(r, "work_x_mse");
        s += fmt::format("| {} | {} | {} | {:.3f} | {:.1f} + {:.1f} | {:.3f} | {:.3g} | {:.3g} | {:.2f} |\n", kind, est,
                         cell == "0" ? std::string("global") : cell, counter(r, "majorant_ratio"),
                         counter(r, "collisions"), counter(r, "cells"), counter(r, "render_s"), counter(r, "mse"), w,
                         global > 0 ? w / global : 0.0);
    }
    s += "\n**Density lookups per second** (shared estimator code on one CPU thread, exponential falloff "
         "segment, tau = 1.5):\n\n| estimator | Mlookups/s | lookups per estimate |\n|---|---|---|\n";
    for (const auto& r : runs)
        if (r.benchmark_name().rfind("lookupsPerSecond", 0) == 0)
            s += fmt::format("| {} | {:.1f} | {:.2f} |\n", label(r), counter(r, "lookups_per_s") * 1e-6,
                             counter(r, "lookups_per_estimate"));
    for (const auto& r : runs)
        if (r.benchmark_name().rfind("debiasedMseSlope", 0) == 0)
            s += fmt::format("\n**MSE slope of debiased marching** (Davis c = 0.8, sine density, N = 2^4..2^14 "
                             "estimates, 200 repetitions each): {:.3f} (theory: -1).\n",
                             counter(r, "mse_slope"));
    return s;
}

}  // namespace

int main(int argc, char** argv) { return bench::runWithMarkdown(argc, argv, tables); }
