// Photon mapping on the point light over a diffuse plane (scenes/point-plane-photon.json, all
// light from photons): throughput of the three passes against the photon count, and the RMSE
// against the analytic answer versus passes and time for progressive photon mapping and the
// unbiased estimators, with fitted log-log slopes. Run through bench/run, which writes the
// "Photon mapping" section of docs/BENCHMARKS.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "bench_main.h"
#include "gpu/context.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

using namespace telescope;
using telescope::bench::context;

namespace {

Scene planeScene(uint32_t resolution, const std::string& integrator) {
    return loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/point-plane-photon.json",
                     {{"camera.resolution", fmt::format("[{},{}]", resolution, resolution)}, {"integrator", integrator}});
}

// ---- Pass throughput against the photon count ----
// The radius shrinks as 1/sqrt(N), so a gather visits about the same number of photons at every
// count (as a k-nearest-neighbour gather would); 64x64 pixels.
std::map<int64_t, std::map<std::string, double>> gPassRows;

void photonPass(benchmark::State& state) {
    const int64_t n = state.range(0);
    const double radius = 0.05 * std::sqrt(double(1 << 20) / double(n));
    Scene scene = planeScene(64, fmt::format(R"({{"type":"photon_map","photon_count":{},"gather_radius":{},
        "direct_lighting":"photons","debias":{{"estimator":"single_term"}}}})", n, radius));
    Renderer renderer(context(), scene, 1);
    RenderRequest one;
    one.spp = 1;
    renderer.render(one);  // sizes the photon map
    const RenderStats before = renderer.stats();
    for (auto _ : state) renderer.render(one);
    const RenderStats& after = renderer.stats();
    const double passes = double(state.iterations());
    auto ms = [&](const char* pass) { return (after.passes.at(pass).gpuMs - before.passes.at(pass).gpuMs) / passes; };
    const double stored = double(after.photonsStored - before.photonsStored) / passes;
    auto& row = gPassRows[n];
    row["trace_ms"] = ms("photon_trace");
    row["grid_ms"] = ms("hash_grid_build");
    row["gather_ms"] = ms("gather");
    row["stored"] = stored;
    row["paths_per_s"] = double(n) / (row["trace_ms"] * 1e-3);
    row["stored_per_s"] = stored / (row["trace_ms"] * 1e-3);
    row["grid_photons_per_s"] = stored / (row["grid_ms"] * 1e-3);
    row["gathers_per_s"] = 64.0 * 64.0 / (row["gather_ms"] * 1e-3);
    row["bytes_per_photon"] = double(after.photonMapBytes) / stored;
    for (const auto& [k, v] : row) state.counters[k] = v;
    state.SetLabel(context().info().name);
}

// ---- RMSE against the analytic plane versus passes ----
constexpr uint32_t kRes = 32;

// Box-filtered pixel values of L = (0.5 / pi) / (1 + x^2 + z^2)^1.5 over [-2, 2]^2.
const std::vector<double>& analytic() {
    static std::vector<double> v = [] {
        std::vector<double> out(kRes * kRes);
        const int sub = 16;
        for (uint32_t py = 0; py < kRes; ++py)
            for (uint32_t px = 0; px < kRes; ++px) {
                double s = 0.0;
                for (int i = 0; i < sub; ++i)
                    for (int k = 0; k < sub; ++k) {
                        double x = -2.0 + 4.0 * (px + (i + 0.5) / sub) / kRes, z = -2.0 + 4.0 * (py + (k + 0.5) / sub) / kRes;
                        s += 0.5 / M_PI * std::pow(1.0 + x * x + z * z, -1.5);
                    }
                out[py * kRes + px] = s / (sub * sub);
            }
        return out;
    }();
    return v;
}

struct ConvergencePoint {
    uint64_t passes;
    double mse, seconds;
};

std::vector<ConvergencePoint> converge(const std::string& integrator, uint32_t seed, uint64_t maxPasses) {
    Scene scene = planeScene(kRes, integrator);
    Renderer renderer(context(), scene, seed);
    std::vector<ConvergencePoint> out;
    for (uint64_t passes = 4; passes <= maxPasses; passes *= 2) {
        RenderRequest r;
        r.spp = passes - renderer.stats().samplesPerPixel;
        renderer.render(r);
        Film film = renderer.film();
        double se = 0.0;
        for (size_t i = 0; i < film.pixelCount(); ++i) {
            double d = film.mean(shader::kChannelEstimate, i).x - analytic()[i];
            se += d * d;
        }
        out.push_back({passes, se / double(film.pixelCount()), renderer.stats().wallSeconds});
    }
    return out;
}

// Least-squares slope of log(y) against log(x).
double logLogSlope(const std::vector<double>& x, const std::vector<double>& y) {
    double mx = 0, my = 0;
    for (size_t i = 0; i < x.size(); ++i) mx += std::log(x[i]) / x.size(), my += std::log(y[i]) / y.size();
    double sxy = 0, sxx = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        sxy += (std::log(x[i]) - mx) * (std::log(y[i]) - my);
        sxx += (std::log(x[i]) - mx) * (std::log(x[i]) - mx);
    }
    return sxy / sxx;
}

struct ConvergenceResult {
    std::string label;
    std::vector<uint64_t> passes;
    std::vector<double> meanMse, medianMse, seconds;
    double slopeMean = 0, slopeMedian = 0, slopeTime = 0;
};
std::vector<ConvergenceResult> gConvergence;

void convergence(benchmark::State& state, std::string label, std::string integrator) {
    const uint64_t maxPasses = 256;
    const uint32_t seeds = 8;
    ConvergenceResult res;
    res.label = label;
    for (auto _ : state) {
        std::vector<std::vector<ConvergencePoint>> runs;
        for (uint32_t s = 0; s < seeds; ++s) runs.push_back(converge(integrator, 1000 + 17 * s, maxPasses));
        for (size_t i = 0; i < runs[0].size(); ++i) {
            std::vector<double> mses;
            double secs = 0;
            for (auto& r : runs) mses.push_back(r[i].mse), secs += r[i].seconds / seeds;
            std::sort(mses.begin(), mses.end());
            double mean = 0;
            for (double m : mses) mean += m / seeds;
            res.passes.push_back(runs[0][i].passes);
            res.meanMse.push_back(mean);
            res.medianMse.push_back(0.5 * (mses[seeds / 2 - 1] + mses[seeds / 2]));
            res.seconds.push_back(secs);
        }
    }
    // Slopes over 16..256 passes (the first points are dominated by the start-up radius).
    std::vector<double> x, ym, yd, t, ymt;
    for (size_t i = 0; i < res.passes.size(); ++i)
        if (res.passes[i] >= 16) {
            x.push_back(double(res.passes[i]));
            ym.push_back(res.meanMse[i]);
            yd.push_back(res.medianMse[i]);
            t.push_back(res.seconds[i]);
        }
    res.slopeMean = logLogSlope(x, ym);
    res.slopeMedian = logLogSlope(x, yd);
    res.slopeTime = logLogSlope(t, ym);
    state.counters["mse_slope_mean"] = res.slopeMean;
    state.counters["mse_slope_median"] = res.slopeMedian;
    state.counters["mse_slope_time"] = res.slopeTime;
    gConvergence.push_back(res);
}

const char* kPpm = R"({"type":"progressive_photon_map","photon_count":20000,"gather_radius":0.25,"direct_lighting":"photons"})";
const char* kUnbiased = R"({"type":"photon_map","photon_count":20000,"gather_radius":0.25,"direct_lighting":"photons",
    "debias":{"estimator":"single_term"}})";
const char* kUnbiasedProgressive = R"({"type":"progressive_photon_map","photon_count":20000,"gather_radius":0.25,
    "direct_lighting":"photons","debias":{"estimator":"single_term"}})";

}  // namespace

BENCHMARK(photonPass)->Arg(1 << 20)->Arg(1 << 21)->Arg(1 << 22)->Arg(1 << 23)->Arg(1 << 24)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(convergence, ppm, std::string("progressive photon mapping"), std::string(kPpm))->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(convergence, unbiased, std::string("unbiased photon mapping"), std::string(kUnbiased))->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(convergence, unbiased_progressive, std::string("unbiased progressive photon mapping"), std::string(kUnbiasedProgressive))->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

// ---- Markdown tables (from the rows the benchmarks recorded) ----
namespace {

std::string tables(const bench::Runs&) {
    std::string out = "\n";
    if (!gPassRows.empty()) {
        out += "| photon paths N | stored photons | photon_trace ms | Mpaths/s | hash_grid_build ms | Mphotons/s sorted | "
               "gather ms (64x64) | gathers/s | bytes per stored photon |\n|---|---|---|---|---|---|---|---|---|\n";
        for (const auto& [n, r] : gPassRows)
            out += fmt::format("| {} | {:.0f} | {:.1f} | {:.2f} | {:.1f} | {:.1f} | {:.1f} | {:.0f} | {:.1f} |\n", n,
                               r.at("stored"), r.at("trace_ms"), r.at("paths_per_s") * 1e-6, r.at("grid_ms"),
                               r.at("grid_photons_per_s") * 1e-6, r.at("gather_ms"), r.at("gathers_per_s"),
                               r.at("bytes_per_photon"));
        out += "\n";
    }
    if (!gConvergence.empty()) {
        out += "| method | passes | mean MSE (8 seeds) | median MSE | seconds |\n|---|---|---|---|---|\n";
        for (const auto& c : gConvergence)
            for (size_t i = 0; i < c.passes.size(); ++i)
                out += fmt::format("| {} | {} | {:.3e} | {:.3e} | {:.2f} |\n", c.label, c.passes[i], c.meanMse[i],
                                   c.medianMse[i], c.seconds[i]);
        out += "\n| method | MSE slope vs passes (mean) | (median) | MSE slope vs time (mean) |\n|---|---|---|---|\n";
        for (const auto& c : gConvergence)
            out += fmt::format("| {} | {:.2f} | {:.2f} | {:.2f} |\n", c.label, c.slopeMean, c.slopeMedian, c.slopeTime);
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) { return bench::runWithMarkdown(argc, argv, tables); }
