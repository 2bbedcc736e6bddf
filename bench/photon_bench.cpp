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
#include <fstream>

#include "bench_main.h"
#include "gpu/context.h"
#include "render/pmf_pilot.h"
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
        "direct_lighting":"photons"}})", n, radius));
    Renderer renderer(context(), resolveScene(context(), scene, 1).scene, 1);
    RenderRequest one;
    one.spp = 1;
    renderer.render(one);  // sizes the photon map
    const RenderStats before = renderer.stats();
    for (auto _ : state) renderer.render(one);
    const RenderStats& after = renderer.stats();
    const double passes = double(state.iterations());
    auto ms = [&](const char* pass) { return (after.passes.at(pass).gpuMs - before.passes.at(pass).gpuMs) / passes; };
    const double stored = double(after.integrator.photonsStored - before.integrator.photonsStored) / passes;
    auto& row = gPassRows[n];
    row["trace_ms"] = ms("photon_trace");
    row["grid_ms"] = ms("hash_grid_build");
    row["gather_ms"] = ms("gather");
    row["stored"] = stored;
    row["paths_per_s"] = double(n) / (row["trace_ms"] * 1e-3);
    row["stored_per_s"] = stored / (row["trace_ms"] * 1e-3);
    row["grid_photons_per_s"] = stored / (row["grid_ms"] * 1e-3);
    row["gathers_per_s"] = 64.0 * 64.0 / (row["gather_ms"] * 1e-3);
    row["bytes_per_photon"] = double(after.integrator.photonMapBytes) / stored;
    for (const auto& [k, v] : row) state.counters[k] = v;
    state.SetLabel(context().info().name);
}

// ---- Error against the analytic plane versus the photon budget ----
// Progressive photon mapping and unbiased photon mapping (blocks, uniform and per_pixel
// schedules) at equal photon budgets of 2^4 .. 2^14 passes of N photon paths, over several seeds.
// Per pixel the relative error e = (estimate - L) / L; per budget, over pixels and seeds: the
// median and mean of |e| (the typical error), the mean of e^2 (MSE: outlier-dominated, infinite
// in expectation for the unbiased estimator), the mean of e (bias), and for the uniform schedule
// the tail z P(|Z - L| > z L) of the block samples Z of the centre pixels.
constexpr uint32_t kRes = 16;
constexpr uint32_t kPhotons = 10000;
constexpr double kRadius = 0.25;
constexpr uint32_t kMinExp = 4, kMaxExp = 14;

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

bool centre(size_t pixel) {
    const size_t x = pixel % kRes, y = pixel / kRes;
    return x >= kRes / 2 - 2 && x < kRes / 2 + 2 && y >= kRes / 2 - 2 && y < kRes / 2 + 2;
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

struct BudgetStats {
    uint64_t budget = 0;
    double passes = 0.0;  // mean passes actually run (a block may end past the budget)
    std::vector<double> errors;  // relative errors, all pixels and seeds
    double samples = 0.0;        // mean samples (blocks) per pixel
};

struct MethodResult {
    std::string label;
    std::vector<BudgetStats> budgets;
    std::vector<double> tail;  // |Z - L| / L of the centre pixels' block samples (uniform blocks)
    double seconds = 0.0;
    uint64_t passes = 0, samples = 0;
    double slopeMedian = 0, slopeMeanAbs = 0, slopeMse = 0;
};
std::vector<MethodResult> gBudget;

void budgetConvergence(benchmark::State& state, std::string label, std::string integrator, uint32_t seeds, bool blocks) {
    MethodResult res;
    res.label = label;
    for (uint32_t e = kMinExp; e <= kMaxExp; ++e) res.budgets.push_back({uint64_t(1) << e, 0.0, {}, 0.0});
    const auto& want = analytic();
    for (auto _ : state) {
        for (uint32_t s = 0; s < seeds; ++s) {
            Scene scene = planeScene(kRes, integrator);
            Renderer renderer(context(), resolveScene(context(), scene, 1).scene, 7000 + 31 * s);
            size_t next = 0;
            std::vector<double> before(want.size(), 0.0);
            while (next < res.budgets.size()) {
                RenderRequest one;
                one.spp = 1;
                renderer.render(one);
                const uint64_t passes = renderer.stats().integrator.photonPasses;
                const bool record = passes >= res.budgets[next].budget;
                if (!record && !blocks) continue;
                Film film = renderer.film();
                if (blocks)  // the block sample of each centre pixel
                    for (size_t i = 0; i < want.size(); ++i) {
                        const double sum = film.sums(shader::kChannelEstimate)[i].x;
                        if (centre(i)) res.tail.push_back(std::abs(sum - before[i] - want[i]) / want[i]);
                        before[i] = sum;
                    }
                while (next < res.budgets.size() && passes >= res.budgets[next].budget) {
                    BudgetStats& b = res.budgets[next++];
                    b.passes += double(passes) / seeds;
                    double samples = 0.0;
                    for (size_t i = 0; i < want.size(); ++i) {
                        b.errors.push_back(film.mean(shader::kChannelEstimate, i).x / want[i] - 1.0);
                        samples += film.samplesOf(i) / want.size();
                    }
                    b.samples += samples / seeds;
                }
            }
            res.seconds += renderer.stats().wallSeconds;
            res.passes += renderer.stats().integrator.photonPasses;
            res.samples += renderer.stats().samplesPerPixel;
        }
    }
    std::vector<double> x, med, mabs, mse;
    for (const BudgetStats& b : res.budgets) {
        if (b.budget < 64) continue;  // slopes over 2^6 .. 2^14 passes
        std::vector<double> a;
        double m = 0.0, q = 0.0;
        for (double e : b.errors) a.push_back(std::abs(e)), m += std::abs(e) / b.errors.size(), q += e * e / b.errors.size();
        std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
        x.push_back(b.passes);
        med.push_back(a[a.size() / 2]);
        mabs.push_back(m);
        mse.push_back(q);
    }
    res.slopeMedian = logLogSlope(x, med);
    res.slopeMeanAbs = logLogSlope(x, mabs);
    res.slopeMse = logLogSlope(x, mse);
    state.counters["slope_median_abs"] = res.slopeMedian;
    state.counters["slope_mean_abs"] = res.slopeMeanAbs;
    state.counters["slope_mse"] = res.slopeMse;
    gBudget.push_back(std::move(res));
}

const char* kPpm = R"({"type":"progressive_photon_map","photon_count":10000,"gather_radius":0.25,"direct_lighting":"photons"})";
const char* kUnbiased = R"({"type":"photon_map","photon_count":10000,"gather_radius":0.25,"direct_lighting":"photons",
    "debias":{"estimator":"single_term"}})";
const char* kUnbiasedPerPixel = R"({"type":"photon_map","photon_count":10000,"gather_radius":0.25,"direct_lighting":"photons",
    "debias":{"estimator":"single_term","level_schedule":"per_pixel"}})";

}  // namespace

BENCHMARK(photonPass)->Arg(1 << 20)->Arg(1 << 21)->Arg(1 << 22)->Arg(1 << 23)->Arg(1 << 24)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(budgetConvergence, ppm, std::string("progressive photon mapping"), std::string(kPpm), 8u, false)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(budgetConvergence, unbiased, std::string("unbiased photon mapping (uniform)"), std::string(kUnbiased), 8u, true)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();
BENCHMARK_CAPTURE(budgetConvergence, unbiased_per_pixel, std::string("unbiased photon mapping (per_pixel)"), std::string(kUnbiasedPerPixel), 8u, false)->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

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
    if (!gBudget.empty()) {
        out += fmt::format("Point light over a plane, {}x{} pixels, {} photon paths per pass, r_1 = r_b = {:g}, {} seeds; "
                           "relative errors e per pixel, over pixels and seeds.\n\n",
                           kRes, kRes, kPhotons, kRadius, 8);
        out += "| method | budget (passes) | passes run | samples per pixel | median abs error | mean abs error | "
               "mean squared error (outlier-dominated) | mean signed error |\n|---|---|---|---|---|---|---|---|\n";
        std::string csv = "method,budget,passes,samples,median_abs,mean_abs,mse,mean\n";
        for (const auto& m : gBudget)
            for (const auto& b : m.budgets) {
                std::vector<double> a;
                double mean = 0.0, mabs = 0.0, mse = 0.0;
                for (double e : b.errors) {
                    a.push_back(std::abs(e));
                    mean += e / b.errors.size();
                    mabs += std::abs(e) / b.errors.size();
                    mse += e * e / b.errors.size();
                }
                std::nth_element(a.begin(), a.begin() + a.size() / 2, a.end());
                out += fmt::format("| {} | {} | {:.0f} | {:.1f} | {:.4f} | {:.4f} | {:.3e} | {:+.4f} |\n", m.label, b.budget,
                                   b.passes, b.samples, a[a.size() / 2], mabs, mse, mean);
                csv += fmt::format("{},{},{:.1f},{:.2f},{:.6g},{:.6g},{:.6g},{:.6g}\n", m.label, b.budget, b.passes,
                                   b.samples, a[a.size() / 2], mabs, mse, mean);
            }
        out += "\n| method | slope of median abs error | slope of mean abs error | slope of MSE | photon passes per sample "
               "| seconds (all seeds) |\n|---|---|---|---|---|---|\n";
        for (const auto& m : gBudget)
            out += fmt::format("| {} | {:.3f} | {:.3f} | {:.3f} | {:.2f} | {:.0f} |\n", m.label, m.slopeMedian,
                               m.slopeMeanAbs, m.slopeMse, double(m.passes) / double(std::max<uint64_t>(m.samples, 1)),
                               m.seconds);
        out += "\nSlopes: least squares of log error against log passes over budgets 2^6 .. 2^14.\n";
        for (const auto& m : gBudget) {
            if (m.tail.empty()) continue;
            out += fmt::format("\nTail of the block samples of the centre 4x4 pixels ({}: {} samples): z P(|Z - L| > z L)\n\n"
                               "| z | 0.3 | 1 | 3 | 10 | 30 | 100 | 300 |\n|---|---|---|---|---|---|---|---|\n| z P |",
                               m.label, m.tail.size());
            for (double z : {0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0}) {
                double count = 0.0;
                for (double t : m.tail) count += t > z;
                out += fmt::format(" {:.4f} |", z * count / double(m.tail.size()));
            }
            out += "\n";
        }
        std::ofstream(std::string(TELESCOPE_SOURCE_DIR) + "/docs/bench/photon-blocks.csv") << csv;
    }
    return out;
}

}  // namespace

int main(int argc, char** argv) { return bench::runWithMarkdown(argc, argv, tables); }
