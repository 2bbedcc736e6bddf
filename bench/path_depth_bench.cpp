// Paths per second of the path tracer on the Cornell box at 256x256, biased I(k) and debiased,
// for several k. Run through bench/run, which writes docs/BENCHMARKS.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cctype>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include <fmt/format.h>

#include "bench_main.h"
#include "gpu/context.h"
#include "render/pmf_pilot.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

using namespace telescope;
using telescope::bench::context;

namespace {

// Renders 16 spp of a 256x256 scene per iteration and reports paths per second.
void pathsPerSecond(benchmark::State& state, const Scene& scene) {
    Renderer renderer(context(), resolveScene(context(), scene, 1).scene, 1);
    RenderRequest warmup;
    warmup.spp = 4;  // first dispatch compiles the pipeline
    renderer.render(warmup);
    const uint64_t spp = 16;
    for (auto _ : state) {
        RenderRequest request;
        request.spp = spp;
        renderer.render(request);
    }
    const double paths = double(state.iterations()) * spp * 256.0 * 256.0;
    state.counters["paths_per_s"] = benchmark::Counter(paths, benchmark::Counter::kIsRate);
    state.counters["k"] = double(pathDepthK(scene.integrator));
    state.SetLabel(context().info().name);
}

void pathTracing(benchmark::State& state, const std::string& debias) {
    const int k = int(state.range(0));
    std::vector<SceneOverride> overrides = {{"camera.resolution", "[256,256]"},
                                            {"integrator.max_bounces", std::to_string(k + 1)}};  // k bounces
    if (!debias.empty())
        overrides.push_back({"integrator.debias", R"({"estimator":")" + debias + R"(","pmf":{"type":"geometric","r":0.65}})"});
    Scene scene = loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/cornell-box.json", overrides);
    pathsPerSecond(state, scene);
}

// Level scheduling (debias "level_schedule"): the same debiased estimator with levels drawn per
// pixel sample (per_pixel), sorted into a level queue first (queued: identical samples), or one
// level per sample index for all pixels (uniform: same per-pixel variance, correlated pixels).
// The per-pixel variance is the same for the three, so paths/s ratios are work x MSE ratios.
// The three renderers take turns, 16 spp each per iteration, so that the slow drifts of a shared
// machine's speed (tens of percent over minutes here) fall on all three alike; each one's time is
// its own renders' wall time.
const char* const kSchedules[] = {"per_pixel", "queued", "uniform"};

void levelSchedule(benchmark::State& state, const std::string& sceneFile) {
    std::vector<Scene> scenes;
    std::vector<std::unique_ptr<Renderer>> renderers;
    for (const char* schedule : kSchedules) {
        std::vector<SceneOverride> overrides = {
            {"camera.resolution", "[256,256]"},
            {"integrator.max_bounces", "2"},
            {"integrator.debias", std::string(R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.3},)") +
                                      R"("level_schedule":")" + schedule + R"("})"}};
        scenes.push_back(loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/" + sceneFile, overrides));
    }
    for (const Scene& scene : scenes) {
        renderers.push_back(std::make_unique<Renderer>(context(), resolveScene(context(), scene, 1).scene, 1));
        RenderRequest warmup;
        warmup.spp = 4;  // first dispatch compiles the pipeline
        renderers.back()->render(warmup);
    }
    double seconds[3] = {0.0, 0.0, 0.0};
    for (auto _ : state)
        for (size_t i = 0; i < renderers.size(); ++i) {
            RenderRequest request;
            request.spp = 16;
            const double before = renderers[i]->stats().wallSeconds;
            renderers[i]->render(request);
            seconds[i] += renderers[i]->stats().wallSeconds - before;
        }
    const double paths = double(state.iterations()) * 16.0 * 256.0 * 256.0;
    for (size_t i = 0; i < 3; ++i) state.counters[std::string(kSchedules[i]) + "_paths_per_s"] = paths / seconds[i];
    state.counters["k"] = 1.0;
    state.SetLabel(context().info().name);
}

}  // namespace

BENCHMARK_CAPTURE(levelSchedule, cornell, "cornell-box.json")->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(30);
BENCHMARK_CAPTURE(levelSchedule, furnace, "furnace.json")->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(30);

BENCHMARK_CAPTURE(pathTracing, biased, std::string())->Arg(1)->Arg(4)->Arg(16)->Arg(64)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(pathTracing, single_term, std::string("single_term"))->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(pathTracing, sum, std::string("sum"))->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();

// ---- Markdown table of the results ----
namespace {

// "pathTracing/single_term/4/min_time:15.000/real_time" -> "pathTracing/single_term" (k: a counter).
std::string table(const bench::Runs& runs) {
    std::string s = "\n| benchmark | k | Mpaths/s | ms per 16 spp |\n|---|---|---|---|\n";
    std::map<std::string, double> rate;
    for (const auto& r : runs) {
        std::vector<std::string> parts;
        std::stringstream ss(r.benchmark_name());
        auto isNumber = [](const std::string& p) {
            return std::all_of(p.begin(), p.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
        };
        for (std::string p; std::getline(ss, p, '/');)
            if (p != "real_time" && p.find(':') == std::string::npos && !isNumber(p)) parts.push_back(p);
        std::string name;
        for (const auto& p : parts) name += (name.empty() ? "" : "/") + p;
        auto k = r.counters.find("k");
        const int kValue = k == r.counters.end() ? 0 : int(k->second);
        for (const std::string prefix : {"", "per_pixel_", "queued_", "uniform_"}) {
            auto it = r.counters.find(prefix + "paths_per_s");
            if (it == r.counters.end()) continue;
            const std::string row = prefix.empty() ? name : name + "/" + prefix.substr(0, prefix.size() - 1);
            rate[row] = double(it->second);
            s += fmt::format("| {} | {} | {:.2f} | {:.0f} |\n", row, kValue, rate[row] * 1e-6,
                             16.0 * 256.0 * 256.0 / rate[row] * 1e3);
        }
    }
    // Level scheduling: the three schedules have the same per-pixel variance, so a paths/s
    // ratio is the inverse work x MSE ratio.
    std::string ratios;
    for (const char* scene : {"cornell", "furnace"}) {
        const std::string base = fmt::format("levelSchedule/{}/", scene);
        const double perPixel = rate[base + "per_pixel"], queued = rate[base + "queued"],
                     uniform = rate[base + "uniform"];
        if (perPixel > 0.0 && queued > 0.0 && uniform > 0.0)
            ratios += fmt::format("- {}: uniform runs at {:.2f}x the paths/s of per_pixel (what per-pixel levels cost "
                                  "in divergence); queued at {:.2f}x (work x MSE {:.2f}x per_pixel's)\n",
                                  scene, uniform / perPixel, queued / perPixel, perPixel / queued);
    }
    if (!ratios.empty()) s += "\nLevel scheduling, measured in this run:\n\n" + ratios;
    return s;
}

}  // namespace

int main(int argc, char** argv) { return bench::runWithMarkdown(argc, argv, table); }
