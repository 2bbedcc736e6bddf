// telescope: command-line front end.
//
//   telescope render SCENE -o OUT.exr [--spp N | --time SECONDS] [--seed S] [--set key=value ...]
//   telescope plan SCENE [--set key=value ...]
//   telescope devices
//
// Exit codes: 0 success, 2 bad input (one line naming the file and the key), 1 runtime failure.
#include <OpenImageIO/imageio.h>  // before anything that may pull in X11

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "gpu/context.h"
#include "render/image_output.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"

namespace fs = std::filesystem;
using namespace telescope;

namespace {

constexpr uint32_t kDefaultSeed = 0xBA5EBA11u;  // Tungsten's default seed

struct CommonOptions {
    std::string scenePath;
    std::vector<std::string> sets;
    int device = -1;
    bool validation = false;
};

Scene loadWithOverrides(const CommonOptions& o) {
    std::vector<SceneOverride> overrides;
    for (const auto& s : o.sets) overrides.push_back(parseOverride(s));
    return loadScene(o.scenePath, overrides);
}

// ---- Progress: a bar on a terminal, a plain line every ~10% otherwise ----
class ProgressReporter {
public:
    explicit ProgressReporter(bool quiet) : quiet_(quiet), tty_(isatty(fileno(stderr))) {}

    void operator()(const RenderProgress& p) {
        if (quiet_) return;
        double fraction = p.samplesTarget ? double(p.samplesDone) / double(p.samplesTarget)
                                          : (p.timeLimit > 0 ? p.seconds / p.timeLimit : 0.0);
        fraction = std::min(fraction, 1.0);
        double eta = fraction > 0 ? p.seconds * (1.0 - fraction) / fraction : 0.0;
        std::string line = fmt::format("{:>3.0f}% {} spp  {:.2f} Mpaths/s  {:.1f} s  ETA {:.1f} s", 100 * fraction,
                                       p.samplesDone, p.pathsPerSecond * 1e-6, p.seconds, eta);
        if (tty_) {
            int width = 30, filled = int(fraction * width);
            fmt::print(stderr, "\r[{}{}] {}", std::string(filled, '#'), std::string(width - filled, ' '), line);
            std::fflush(stderr);
            printedBar_ = true;
        } else if (fraction >= nextReport_ || fraction >= 1.0) {
            fmt::print(stderr, "render: {}\n", line);
            while (nextReport_ <= fraction) nextReport_ += 0.1;
        }
    }
    void finish() {
        if (printedBar_) fmt::print(stderr, "\n");
    }

private:
    bool quiet_, tty_;
    bool printedBar_ = false;
    double nextReport_ = 0.1;
};

// ---- Output path checks, before any work is done ----
void checkOutputPath(const std::string& path, const char* option, const char* extension) {
    fs::path p(path);
    if (p.extension() != extension)
        throw InputError("", option, fmt::format("'{}' must end in {}", path, extension));
    fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    if (!fs::is_directory(dir))
        throw InputError("", option, fmt::format("directory '{}' does not exist", dir.string()));
}

void checkValidation(const gpu::Context& context) {
    if (context.validationMessageCount() > 0)
        throw std::runtime_error(
            fmt::format("{} Vulkan validation message(s) were reported", context.validationMessageCount()));
}

int runRender(const CommonOptions& common, const std::string& outPath, std::string pngPath, bool noPng,
              uint64_t sppOption, double timeLimit, uint32_t seed, const std::string& statsPath, bool quiet) {
    Scene scene = loadWithOverrides(common);
    checkOutputPath(outPath, "-o", ".exr");
    if (!noPng) {
        if (pngPath.empty()) pngPath = fs::path(outPath).replace_extension(".png").string();
        checkOutputPath(pngPath, "--png", ".png");
    }
    if (!statsPath.empty()) checkOutputPath(statsPath, "--stats-json", ".json");
    if (!quiet)
        for (const auto& key : scene.ignoredKeys) fmt::print(stderr, "{}: ignoring '{}' (not used by Telescope)\n", scene.path, key);

    gpu::ContextOptions ctxOptions;
    ctxOptions.deviceIndex = common.device;
    ctxOptions.validation = common.validation;
    gpu::Context context(ctxOptions);
    Renderer renderer(context, scene, seed);

    RenderRequest request;
    request.timeLimit = timeLimit;
    request.spp = timeLimit > 0 ? 0 : (sppOption ? sppOption : scene.renderer.spp);
    ProgressReporter progress(quiet);
    request.progress = [&](const RenderProgress& p) { progress(p); };
    renderer.render(request);
    progress.finish();
    checkValidation(context);

    Film film = renderer.film();
    const RenderStats& stats = renderer.stats();
    const double paths = double(film.samplesPerPixel()) * double(film.pixelCount());

    ImageMetadata meta;
    meta.entries = {
        {"telescope:version", TELESCOPE_VERSION},
        {"telescope:scene_file", scene.path},
        {"telescope:scene", scene.document.dump()},
        {"telescope:estimator", renderer.plan().estimator},
        {"telescope:seed", std::to_string(seed)},
        {"telescope:spp", std::to_string(film.samplesPerPixel())},
        {"telescope:render_seconds", fmt::format("{:.6f}", stats.wallSeconds)},
        {"telescope:device", context.info().name},
        {"telescope:non_finite_samples", std::to_string(film.nonFiniteSamples())},
    };
    writeExr(outPath, film, meta);
    if (!noPng) writePngPreview(pngPath, film);

    if (!statsPath.empty()) {
        nlohmann::json j;
        j["scene"] = scene.path;
        j["device"] = context.info().name;
        j["seed"] = seed;
        j["spp"] = film.samplesPerPixel();
        j["resolution"] = {film.width(), film.height()};
        j["wall_seconds"] = stats.wallSeconds;
        j["setup_seconds"] = stats.setupSeconds;
        j["submits"] = stats.submits;
        j["paths_per_second"] = stats.wallSeconds > 0 ? paths / stats.wallSeconds : 0.0;
        j["non_finite_samples"] = film.nonFiniteSamples();
        j["validation_messages"] = context.validationMessageCount();
        j["estimator"] = renderer.plan().estimator;
        for (const auto& [name, p] : stats.passes)
            j["passes"][name] = {{"dispatches", p.dispatches}, {"gpu_ms", p.gpuMs}};
        std::string tmp = statsPath + ".partial";
        {
            std::ofstream f(tmp);
            f << j.dump(2) << "\n";
            if (!f) throw std::runtime_error(fmt::format("{}: write failed", statsPath));
        }
        fs::rename(tmp, statsPath);
    }
    if (!quiet)
        fmt::print(stderr, "wrote {} ({}x{}, {} spp, {:.2f} s, {:.2f} Mpaths/s on {})\n", outPath, film.width(),
                   film.height(), film.samplesPerPixel(), stats.wallSeconds,
                   stats.wallSeconds > 0 ? paths / stats.wallSeconds * 1e-6 : 0.0, context.info().name);
    return 0;
}

int runPlan(const CommonOptions& common) {
    Scene scene = loadWithOverrides(common);
    GpuScene gpuScene = buildGpuScene(scene);
    fmt::print("{}", describePlan(scene, makeRenderPlan(scene, gpuScene.features)));
    return 0;
}

int runDevices() {
    auto devices = gpu::Context::listDevices();
    if (devices.empty()) fmt::print("no Vulkan devices\n");
    for (const auto& d : devices)
        fmt::print("{}: {} ({}, Vulkan {}.{}, {}){}\n", d.index, d.name, d.type, VK_API_VERSION_MAJOR(d.apiVersion),
                   VK_API_VERSION_MINOR(d.apiVersion), d.driver, d.suitable ? "" : " - unsuitable: " + d.whyNot);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Telescope: unbiased and consistent rendering from biased estimators (Vulkan compute)"};
    app.require_subcommand(1);
    CommonOptions common;

    auto addCommon = [&](CLI::App* cmd) {
        cmd->add_option("scene", common.scenePath, "Scene file (Tungsten JSON)")->required();
        cmd->add_option("--set", common.sets, "Override a scene key: key.path=value (JSON value)");
        cmd->add_option("--device", common.device, "Vulkan device index (see 'telescope devices')");
        cmd->add_flag("--validation", common.validation, "Enable Vulkan validation layers (or TELESCOPE_VALIDATION=1)");
    };

    std::string outPath, pngPath, statsPath;
    uint64_t spp = 0;
    double timeLimit = 0;
    uint32_t seed = kDefaultSeed;
    bool noPng = false, quiet = false;
    auto* render = app.add_subcommand("render", "Render a scene to a float EXR and a PNG preview");
    addCommon(render);
    render->add_option("-o,--output", outPath, "Output EXR")->required();
    auto* sppOpt = render->add_option("--spp", spp, "Samples per pixel (default: renderer.spp)")
                       ->check(CLI::PositiveNumber);
    render->add_option("--time", timeLimit, "Render for this many seconds instead of a fixed spp")
        ->check(CLI::PositiveNumber)
        ->excludes(sppOpt);
    render->add_option("--seed", seed, "Random seed");
    render->add_option("--png", pngPath, "Preview PNG (default: OUT with .png)");
    render->add_flag("--no-png", noPng, "Do not write a PNG preview");
    render->add_option("--stats-json", statsPath, "Write per-pass times, dispatch counts and device to this file");
    render->add_flag("-q,--quiet", quiet, "No progress output");

    auto* plan = app.add_subcommand("plan", "Print the passes a render of the scene would run, and why");
    addCommon(plan);
    app.add_subcommand("devices", "List Vulkan devices");

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        fmt::print(stderr, "telescope: command line: {}\n", e.what());
        return 2;
    }

    try {
        if (render->parsed()) return runRender(common, outPath, pngPath, noPng, spp, timeLimit, seed, statsPath, quiet);
        if (plan->parsed()) return runPlan(common);
        return runDevices();
    } catch (const InputError& e) {
        fmt::print(stderr, "telescope: {}\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        fmt::print(stderr, "telescope: error: {}\n", e.what());
        return 1;
    }
}
