// Paths per second of the path tracer on the Cornell box at 256x256, biased I(k) and debiased,
// for several k. Run through bench/run, which writes docs/BENCHMARKS.md.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "gpu/context.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

using namespace telescope;

namespace {

gpu::Context& context() {
    static gpu::Context ctx{gpu::ContextOptions{}};
    return ctx;
}

void pathTracing(benchmark::State& state, const std::string& debias) {
    const int k = int(state.range(0));
    std::vector<SceneOverride> overrides = {{"camera.resolution", "[256,256]"},
                                            {"integrator.max_bounces", std::to_string(k)}};
    if (!debias.empty())
        overrides.push_back({"integrator.debias", R"({"estimator":")" + debias + R"(","pmf":{"type":"geometric","r":0.65}})"});
    Scene scene = loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/cornell-box.json", overrides);
    Renderer renderer(context(), scene, 1);
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
    state.counters["device"] = 0;
    state.SetLabel(context().info().name);
}

}  // namespace

BENCHMARK_CAPTURE(pathTracing, biased, std::string())->Arg(1)->Arg(4)->Arg(16)->Arg(64)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(pathTracing, single_term, std::string("single_term"))->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(pathTracing, sum, std::string("sum"))->Arg(1)->Arg(4)->Arg(16)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
