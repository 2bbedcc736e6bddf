
#include "cli/commands.h"
#include "session/interrupt.h"
#include "session/outputs.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "gpu/context.h"
#include "render/derivative.h"
#include "render/film_io.h"
#include "render/image_output.h"
#include "render/renderer.h"
#include "scene/photon_budget.h"
#include "scene/scene_loader.h"
#include "scene/settings_json.h"
#include "study/converge.h"
#include "render/pmf_pilot.h"
#include "study/reference.h"
#include "study/transmittance_study.h"
#include "shared/transmittance_estimators.h"

namespace fs = std::filesystem;

namespace telescope::cli {

using namespace session;  // the session layer: loading, outputs, checks

// ---- Progress: a bar on a terminal, a plain line every ~10% otherwise ----
class ProgressReporter {
public:
    ProgressReporter(bool quiet, const char* what) : quiet_(quiet), tty_(isatty(fileno(stderr))), what_(what) {}

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
            fmt::print(stderr, "{}: {}\n", what_, line);
            while (nextReport_ <= fraction) nextReport_ += 0.1;
        }
    }
    void finish() {
        if (printedBar_) fmt::print(stderr, "\n");
        printedBar_ = false;
    }

private:
    bool quiet_, tty_;
    const char* what_;
    bool printedBar_ = false;
    double nextReport_ = 0.1;
};

// One line when lavapipe's loop cap may have ended loops, or the loop budget dropped samples
// (shared/gpu_types.h "Lavapipe's loop cap"): those pixels are wrong. Printed even with --quiet.
void warnLoopStats(const RenderStats& stats) {
    const LoopStats& l = stats.loops;
    if (l.capHits > 0)
        fmt::print(stderr, "telescope: warning: lavapipe's loop cap was reached in {} lanes: their pixels are wrong "
                   "(set TELESCOPE_LOOP_BUDGET lower, or report the scene)\n", l.capHits);
    if (l.overlong > 0)
        fmt::print(stderr, "telescope: warning: {} samples dropped: one step of their path ran more loop iterations "
                   "than a dispatch allows (TELESCOPE_LOOP_BUDGET)\n", l.overlong);
}

namespace {

// A checkpoint must belong to this scene (after overrides) and seed.
void checkResumable(const Checkpoint& c, const std::string& path, const Scene& scene, uint32_t seed) {
    if (c.scene != scene.document.dump())
        throw InputError(path, "", fmt::format("checkpoint belongs to another scene or other --set overrides than {}",
                                               scene.path));
    if (c.seed != seed)
        throw InputError(path, "", fmt::format("checkpoint was rendered with seed {}, not {}", c.seed, seed));
}

// ... and to its estimator: the settings can differ from the document's (`reference` patches them).
void checkSameEstimator(const Checkpoint& c, const std::string& path, const Renderer& renderer) {
    if (c.estimator != renderer.plan().estimator)
        throw InputError(path, "", fmt::format("checkpoint was rendered with another estimator ({}) than this one ({})",
                                               c.estimator, renderer.plan().estimator));
}

// Continues the checkpoint's render, with its block in progress. The checkpoint must have been
// rendered with the settings this render resolves (defaults filled in, every pmf resolved; the
// key that differs is named); checkpoints older than version 2 record no settings and are compared
// by their estimator. A state this render could not have left is bad input naming the file.
void resumeFrom(Renderer& renderer, const Checkpoint& c, const std::string& path, const Scene& scene) {
    if (!c.settings.empty()) {
        const std::string now = resolvedSettings(scene).dump();
        if (c.settings != now)
            throw InputError(path, firstDifference(c.settings, now),
                             "checkpoint was rendered with other settings than this render resolves");
    }
    checkSameEstimator(c, path, renderer);
    try {
        renderer.resume(c.film);
    } catch (const std::invalid_argument& e) {
        throw InputError(path, "", fmt::format("cannot resume: {}", e.what()));
    }
}

// A time-limited render stopped at its deadline inside a photon block (--time-policy deadline).
void reportDeadlineBlock(const Film& film, const std::string& checkpointPath, bool quiet) {
    const PendingSamples& b = film.pending();
    if (b.unitsDone == 0 || quiet) return;
    fmt::print(stderr,
               "telescope: stopped at the deadline with {}: the image holds the {} completed blocks, which lean "
               "towards short, low-level blocks ('telescope plan --time' says by how much); {}\n",
               pendingBlockText(film.samplesPerPixel(), b.level, b.unitsDone, b.unitsTotal), film.samplesPerPixel(),
               checkpointPath.empty() ? "its passes are lost (no --checkpoint)"
                                      : "the checkpoint " + checkpointPath + " keeps the block for --resume");
}

void writeStatsJson(const std::string& path, const Scene& scene, const gpu::Context& context, const Renderer& renderer,
                    const Film& film) {
    const RenderStats& stats = renderer.stats();
    const double paths = double(film.samplesPerPixel()) * double(film.pixelCount());
    nlohmann::json j;
    j["scene"] = scene.path;
    j["device"] = context.info().name;
    j["seed"] = renderer.seed();
    j["spp"] = film.samplesPerPixel();
    j["resolution"] = {film.width(), film.height()};
    j["wall_seconds"] = stats.wallSeconds;
    j["setup_seconds"] = stats.setupSeconds;
    j["first_sample_seconds"] = stats.firstSampleSeconds;
    j["setup"] = {{"scene_seconds", stats.sceneSeconds},
                  {"upload_seconds", stats.uploadSeconds},
                  {"pipeline_seconds", stats.pipelineSeconds},
                  {"warm_up_seconds", stats.warmUpSeconds}};
    j["submits"] = stats.submits;
    j["paths_per_second"] = stats.wallSeconds > 0 ? paths / stats.wallSeconds : 0.0;
    if (stats.integrator.photonPaths > 0) {
        j["photon_paths"] = stats.integrator.photonPaths;
        j["photons_stored"] = stats.integrator.photonsStored;
        j["photon_passes"] = stats.integrator.photonPasses;
        if (stats.samplesPerPixel > 0) j["photon_passes_per_sample"] = double(stats.integrator.photonPasses) / double(stats.samplesPerPixel);
    }
    j["non_finite_samples"] = film.nonFiniteSamples();
    j["loop_budget"] = {{"cap_hits", stats.loops.capHits},
                        {"carried_paths", stats.loops.carried},
                        {"resumed_paths", stats.loops.resumed},
                        {"retried_lanes", stats.loops.retried},
                        {"dropped_overlong", stats.loops.overlong},
                        {"drain_dispatches", stats.loops.drainDispatches}};
    j["validation_messages"] = context.validationMessageCount();
    j["estimator"] = renderer.plan().estimator;
    j["settings"] = resolvedSettings(scene);
    for (const auto& [name, p] : stats.passes) j["passes"][name] = {{"dispatches", p.dispatches}, {"gpu_ms", p.gpuMs}};
    writeTextAtomically(path, j.dump(2) + "\n");
}

}  // namespace

namespace {

// `render --derivative KEY`: a derivative image (render/derivative.h). Checkpoints, --resume and
// `merge` work as for radiance renders (a checkpoint names the derivative in its estimator).
int runDerivativeRender(const CommonOptions& common, const RenderOptions& optionsIn, Scene& scene) {
    RenderOptions o = optionsIn;
    InterruptGuard interrupts;
    const DerivativeSettings settings = derivativeSettings(o.derivative);
    ImageOutputOptions output = o.output;
    if (output.checkpointPath.empty() && o.checkpointEvery > 0) output.checkpointPath = output.exrPath + ".checkpoint";
    checkImageOutputs(output);
    if (!o.statsPath.empty()) checkOutputPath(o.statsPath, "--stats-json", ".json");
    if (const char* key = autoPmfKey(scene.integrator); *key)
        throw InputError(scene.path, key,
                         "a derivative render needs a fixed pmf: put the one the pilot of a radiance render chose in the scene");
    std::optional<Checkpoint> resume;
    if (!o.resumePath.empty()) {
        resume = loadCheckpoint(o.resumePath);
        if (!o.seedGiven) o.seed = resume->seed;
        checkResumable(*resume, o.resumePath, scene, o.seed);
    }
    reportIgnoredKeys(scene, common.quiet);
    keepCheckpointsOnFailure({output.checkpointPath, o.resumePath});
    gpu::Context context(contextOptions(common));
    DerivativeRenderer renderer(context, resolve(context, scene, o.seed, common.quiet), settings, o.seed);
    const std::string settingsNow = derivativeSettingsAsRun(scene, renderer);
    if (resume) {
        // Compared on the settings as run (a key that differs is named); checkpoints that do not
        // record the derivative's settings (older ones) by the estimator's description.
        if (!splitDerivativeSettings(resume->settings).derivative.is_null()) {
            if (resume->settings != settingsNow)
                throw InputError(o.resumePath, firstDifference(resume->settings, settingsNow),
                                 "checkpoint was rendered with other settings than this derivative render resolves");
        } else if (resume->estimator != renderer.description()) {
            throw InputError(o.resumePath, "", fmt::format("checkpoint was rendered with another estimator ({}) than this one ({})",
                                                           resume->estimator, renderer.description()));
        }
        renderer.resume(resume->film);
    }
    if (!common.quiet) fmt::print(stderr, "{}", renderer.planText());
    const DerivativeParameter& p = renderer.parameter();
    OutputInfo info{scene.path, scene.document.dump(), renderer.description(), context.info().name, settingsNow,
                    o.seed, 0.0};
    info.extra = derivativeMetadata(renderer);

    RenderRequest request;
    request.timeLimit = o.timeLimit;
    request.spp = o.timeLimit > 0 ? 0 : (o.spp ? o.spp : scene.renderer.spp);
    ProgressReporter progress(common.quiet, "derivative");
    PeriodicCheckpoint periodic(o.checkpointEvery, output.checkpointPath,
                                [&] { return checkpointOf(renderer.film(), info); });
    request.progress = [&](const RenderProgress& pr) {
        progress(pr);
        periodic.afterBatch();
    };
    request.stop = [] { return InterruptGuard::requested(); };
    renderer.render(request);
    progress.finish();
    checkValidation(context);
    warnLoopStats(renderer.renderer().stats());
    const Film& film = renderer.film();
    info.seconds = renderer.seconds();
    const uint64_t resumedSpp = resume ? resume->film.samplesPerPixel() : 0;
    if (InterruptGuard::requested())
        return saveInterrupted(output, film, info, film.samplesPerPixel() - resumedSpp,
                               "continue with --resume " +
                                   (output.checkpointPath.empty() ? output.exrPath + ".checkpoint" : output.checkpointPath));
    ImageOutputOptions exr = output;
    exr.noPng = true;  // the preview is signed false colour
    writeImages(exr, film, info);
    if (!output.noPng) writeSignedPngPreview(output.pngPath, film);
    if (!o.statsPath.empty()) {
        nlohmann::json j;
        j["scene"] = scene.path;
        j["device"] = context.info().name;
        j["seed"] = o.seed;
        j["spp"] = film.samplesPerPixel();
        j["wall_seconds"] = renderer.seconds();
        j["version_seconds"] = renderer.versionSeconds();
        j["evaluations"] = renderer.evaluations();
        j["estimator"] = renderer.description();
        j["non_finite_samples"] = film.nonFiniteSamples();
        j["validation_messages"] = context.validationMessageCount();
        j["derivative"] = {{"key", p.key}, {"value", p.value}, {"step", p.step}};
        writeTextAtomically(o.statsPath, j.dump(2) + "\n");
    }
    if (!common.quiet)
        fmt::print(stderr, "wrote {} (d/d {}: {}x{}, {} spp, {} evaluations, {:.2f} s on {})\n", output.exrPath, p.key,
                   film.width(), film.height(), film.samplesPerPixel(), renderer.evaluations(), renderer.seconds(),
                   context.info().name);
    return 0;
}

}  // namespace

int runRender(const CommonOptions& common, const RenderOptions& optionsIn) {
    RenderOptions o = optionsIn;
    Scene loaded = loadWithOverrides(common);
    if (!o.derivative.key.empty()) return runDerivativeRender(common, o, loaded);
    InterruptGuard interrupts;
    if (o.output.checkpointPath.empty() && o.checkpointEvery > 0) o.output.checkpointPath = o.output.exrPath + ".checkpoint";
    checkImageOutputs(o.output);
    if (!o.statsPath.empty()) checkOutputPath(o.statsPath, "--stats-json", ".json");
    std::optional<Checkpoint> resume;
    if (!o.resumePath.empty()) {
        resume = loadCheckpoint(o.resumePath);
        if (!o.seedGiven) o.seed = resume->seed;
        checkResumable(*resume, o.resumePath, loaded, o.seed);
        takeRecordedPmfs(loaded, *resume, o.resumePath);  // pmf "auto": the checkpoint's pilot's
    }
    reportIgnoredKeys(loaded, common.quiet);

    // A runtime failure (device lost, out of memory) names the checkpoints it leaves (main.cpp).
    keepCheckpointsOnFailure({o.output.checkpointPath, o.resumePath});
    gpu::Context context(contextOptions(common));
    const ResolvedScene resolved = resolve(context, std::move(loaded), o.seed, common.quiet);
    const Scene& scene = resolved.scene();
    Renderer renderer(context, resolved, o.seed);
    if (resume) {
        resumeFrom(renderer, *resume, o.resumePath, scene);
    }
    const OutputInfo info{scene.path, scene.document.dump(), renderer.plan().estimator, context.info().name,
                          resolvedSettings(scene).dump(), o.seed, 0.0};

    RenderRequest request;
    request.timeLimit = o.timeLimit;
    request.finishSampleAtTimeLimit = o.timePolicy != "deadline";
    request.spp = o.timeLimit > 0 ? 0 : (o.spp ? o.spp : scene.renderer.spp);
    ProgressReporter progress(common.quiet, "render");
    PeriodicCheckpoint periodic(o.checkpointEvery, o.output.checkpointPath,
                                [&] { return checkpointOf(renderer.film(), info); });
    request.progress = [&](const RenderProgress& p) {
        progress(p);
        periodic.afterBatch();
    };
    request.stop = [] { return InterruptGuard::requested(); };
    renderer.render(request);
    progress.finish();
    checkValidation(context);
    warnLoopStats(renderer.stats());

    Film film = renderer.film();
    const RenderStats& stats = renderer.stats();
    OutputInfo done = info;
    done.seconds = stats.wallSeconds;
    const uint64_t resumedSpp = resume ? resume->film.samplesPerPixel() : 0;
    if (InterruptGuard::requested())
        return saveInterrupted(o.output, film, done, film.samplesPerPixel() - resumedSpp,
                               "continue with --resume " +
                                   (o.output.checkpointPath.empty() ? o.output.exrPath + ".checkpoint"
                                                                    : o.output.checkpointPath));
    writeImages(o.output, film, done);
    reportDeadlineBlock(film, o.output.checkpointPath, common.quiet);
    if (!o.statsPath.empty()) writeStatsJson(o.statsPath, scene, context, renderer, film);
    if (!common.quiet) {
        const double paths = double(stats.samplesPerPixel - resumedSpp) * double(film.pixelCount());
        fmt::print(stderr, "wrote {} ({}x{}, {} spp, {:.2f} s, {:.2f} Mpaths/s on {})\n", o.output.exrPath,
                   film.width(), film.height(), film.samplesPerPixel(), stats.wallSeconds,
                   stats.wallSeconds > 0 ? paths / stats.wallSeconds * 1e-6 : 0.0, context.info().name);
    }
    return 0;
}

int runReference(const CommonOptions& common, const ReferenceOptions& optionsIn) {
    ReferenceOptions o = optionsIn;
    InterruptGuard interrupts;
    if (o.output.checkpointPath.empty()) o.output.checkpointPath = o.output.exrPath + ".checkpoint";
    Scene loaded = loadWithOverrides(common);
    const UnbiasedSetup setup = unbiasedSetup(loaded);
    loaded.integrator = setup.integrator;
    if (!o.derivative.key.empty()) {
        // Each evaluation unbiased (as above), the derivative by the chosen estimator, resumable
        // through the same checkpoint: a derivative render that checkpoints every interval.
        RenderOptions r;
        r.derivative = o.derivative;
        r.output = o.output;
        r.spp = o.spp;
        r.timeLimit = o.timeLimit;
        r.seed = o.seed;
        r.seedGiven = true;
        r.checkpointEvery = o.checkpointInterval;
        if (fs::exists(o.output.checkpointPath)) r.resumePath = o.output.checkpointPath;
        if (!common.quiet) fmt::print(stderr, "reference: {}\n", setup.why);
        return runDerivativeRender(common, r, loaded);
    }
    checkImageOutputs(o.output);
    std::optional<Checkpoint> resume;
    if (fs::exists(o.output.checkpointPath)) {
        resume = loadCheckpoint(o.output.checkpointPath);
        checkResumable(*resume, o.output.checkpointPath, loaded, o.seed);
        takeRecordedPmfs(loaded, *resume, o.output.checkpointPath);  // pmf "auto": the checkpoint's pilot's
    }
    reportIgnoredKeys(loaded, common.quiet);
    if (!common.quiet) {
        fmt::print(stderr, "reference: {}\n", setup.why);
        if (resume)
            fmt::print(stderr, "reference: resuming from {} ({} spp)\n", o.output.checkpointPath,
                       resume->film.samplesPerPixel());
    }

    keepCheckpointsOnFailure({o.output.checkpointPath});
    gpu::Context context(contextOptions(common));
    const ResolvedScene resolved = resolve(context, std::move(loaded), o.seed, common.quiet);
    const Scene& scene = resolved.scene();  // every pmf as run: what the outputs record
    Renderer renderer(context, resolved, o.seed);
    if (resume) {
        resumeFrom(renderer, *resume, o.output.checkpointPath, scene);
    }
    const OutputInfo info{scene.path,          scene.document.dump(),           renderer.plan().estimator,
                          context.info().name, resolvedSettings(scene).dump(), o.seed,
                          0.0};
    const uint64_t startSpp = resume ? resume->film.samplesPerPixel() : 0;
    const uint64_t targetSpp = o.timeLimit > 0 ? 0 : (o.spp ? o.spp : scene.renderer.spp);

    // Render in pieces, checkpointing after each, so an interrupted reference loses one piece.
    ProgressReporter progress(common.quiet, "reference");
    double elapsed = 0.0;
    while (!InterruptGuard::requested()) {
        RenderRequest request;
        request.stop = [] { return InterruptGuard::requested(); };
        const uint64_t added = renderer.stats().samplesPerPixel - startSpp;
        if (o.timeLimit > 0) {
            if (elapsed >= o.timeLimit) break;
            request.timeLimit = std::min(o.checkpointInterval, o.timeLimit - elapsed);
        } else {
            if (added >= targetSpp) break;
            request.spp = targetSpp - added;
            request.timeLimit = 0.0;
        }
        const double before = renderer.stats().wallSeconds;
        request.progress = [&](const RenderProgress& p) {
            RenderProgress q = p;
            q.seconds += elapsed;
            q.timeLimit = o.timeLimit;
            q.samplesDone = renderer.stats().samplesPerPixel - startSpp + p.samplesDone;
            q.samplesTarget = targetSpp;
            progress(q);
        };
        if (o.timeLimit <= 0) {
            // Pieces of about checkpointInterval seconds, sized from the speed so far, in whole
            // units of the renderer (so the sums equal those of one render of the total: the EXR's
            // metadata reproduces the reference bit for bit). The first piece is one unit: until
            // then the speed is unknown, and a piece of the whole count would never checkpoint.
            const uint64_t unit = renderer.samplesPerUnit();
            const double perSample = added > 0 ? before / double(added) : 0.0;
            const uint64_t units = perSample > 0.0 ? std::max<uint64_t>(1, uint64_t(o.checkpointInterval / perSample) / unit) : 1;
            request.spp = std::min<uint64_t>(request.spp, units * unit);
        }
        renderer.render(request);
        elapsed += renderer.stats().wallSeconds - before;
        checkValidation(context);
        warnLoopStats(renderer.stats());
        if (renderer.stats().samplesPerPixel > startSpp) saveCheckpoint(o.output.checkpointPath, checkpointOf(renderer.film(), info));
    }
    progress.finish();
    Film film = renderer.film();
    OutputInfo done = info;
    done.seconds = renderer.stats().wallSeconds;
    if (InterruptGuard::requested())
        return saveInterrupted(o.output, film, done, film.samplesPerPixel() - startSpp,
                               "run the same command again to continue");
    writeImages(o.output, film, done);
    if (!common.quiet)
        fmt::print(stderr, "wrote {} ({} spp, {} non-finite samples; checkpoint {})\n", o.output.exrPath,
                   film.samplesPerPixel(), film.nonFiniteSamples(), o.output.checkpointPath);
    return 0;
}

// runMerge: cli/shard.cpp

int runConverge(const CommonOptions& common, const ConvergeOptionsCli& c) {
    ConvergeOptions o;
    o.scenePath = common.scenePath;
    o.load = [&common](const std::vector<SceneOverride>& method) { return loadWithOverrides(common, method); };
    o.referencePath = c.referencePath;
    if (!c.derivative.key.empty()) {
        // Derivative estimators compared against a derivative reference (render --derivative).
        o.derivative = true;
        o.derivativeSettings = derivativeSettings(c.derivative);
        if (!c.custom.empty()) throw InputError("", "--method", "with --derivative the methods are derivative estimators (--methods)");
        for (const auto& p : c.presets) {
            o.derivativeEstimators.push_back(parseDerivativeEstimator(p, "--methods"));
            o.methods.push_back(Method{p, {}, std::string("derivative estimator ") + p});
        }
    } else {
        for (const auto& p : c.presets) o.methods.push_back(parseMethod(p, "--methods"));
        for (const auto& m : c.custom) o.methods.push_back(parseMethod(m, "--method"));
    }
    o.timeBudget = c.timeBudget;
    o.slices = c.slices;
    o.sppList = c.sppList;
    o.seed = c.seed;
    o.seedCount = c.seeds;
    if (!c.region.empty()) {
        if (c.region.size() != 4 || c.region[2] <= 0 || c.region[3] <= 0)
            throw InputError("", "--region", "expected X,Y,W,H with a positive width and height");
        o.region = PixelRegion{c.region[0], c.region[1], c.region[2], c.region[3]};
    }
    o.outDir = c.outDir;
    if (!common.quiet) o.log = [](const std::string& line) { fmt::print(stderr, "converge: {}\n", line); };

    gpu::Context context(contextOptions(common));
    ConvergeReport report = runConverge(context, o);
    checkValidation(context);
    if (!common.quiet)
        for (const auto& f : report.files) fmt::print(stderr, "wrote {}\n", f);
    return 0;
}

int runStudyTransmittance(const CommonOptions& common, const StudyTransmittanceCli& c) {
    if (c.outDir.empty()) throw InputError("", "-o", "an output directory is required");
    fs::path dir(c.outDir);
    fs::path parent = dir.parent_path().empty() ? fs::path(".") : dir.parent_path();
    if (!fs::is_directory(parent))
        throw InputError("", "-o", fmt::format("directory '{}' does not exist", parent.string()));
    if (c.level > 16) throw InputError("", "--level", "the level must be at most 16");
    if (c.terms > shader::kTrTaylorMaxTerms)
        throw InputError("", "--taylor-terms", fmt::format("at most {} terms", shader::kTrTaylorMaxTerms));
    TransmittanceStudyOptions o;
    o.outDir = c.outDir;
    o.samples = c.samples;
    o.level = c.level;
    o.taylorTerms = c.terms;
    o.seed = c.seed;
    if (!common.quiet) o.log = [](const std::string& line) { fmt::print(stderr, "study: {}\n", line); };
    gpu::Context context(contextOptions(common));
    TransmittanceStudyReport report = runTransmittanceStudy(context, o);
    checkValidation(context);
    if (!common.quiet)
        for (const auto& f : report.files) fmt::print(stderr, "wrote {}\n", f);
    return 0;
}

namespace {

// Unbiased photon mapping with the uniform schedule: blocks whose lengths a time budget meets.
bool uniformPhotonBlocks(const IntegratorSettings& in) {
    return usesPhotons(in) && in.debias.estimator != DebiasEstimator::None && in.debias.schedule == LevelSchedule::Uniform;
}

std::string budgetRow(const PhotonBudget& b) {
    return fmt::format("  {:>9.0f} {:>9.1f} {:>9.0f} {:>7.0f} {:>7.0f} {:>8.0f} {:>9.4f} {:>9.3f}\n", b.budgetPasses,
                       b.expectedBlocks, b.overrunMedian, b.overrun90, b.overrun99, b.overrun999,
                       b.overrunAbove(b.budgetPasses), b.deadlineBias);
}

// What time budgets do to the blocks (scene/photon_budget.h): a table over budgets in passes, and
// with passSeconds > 0 the budget of timeLimit seconds with its level weights at the deadline.
std::string photonBudgetText(const DebiasSettings& d, double timeLimit, double passSeconds) {
    const PhotonBlockDesign design = photonBlockDesign(d);
    std::string s = fmt::format(
        "time limits (uniform blocks, docs/PHOTON-MAPPING.md \"Time limits\"): with --time the render finishes the block "
        "running at the limit (--time-policy finish-block: every level keeps its weight, the render overruns) or stops "
        "there (deadline: no overrun, but blocks longer than what is left never finish, and the image of the completed "
        "blocks keeps part of the base bias). Exact renewal sums over the block lengths m^k, p(k):\n"
        "  {:>9} {:>9} {:>9} {:>7} {:>7} {:>8} {:>9} {:>9}\n",
        "budget", "blocks", "overrun", "90%", "99%", "99.9%", "P(>= 2x)", "deadline");
    for (uint64_t passes : {10u, 100u, 1000u, 10000u, 100000u}) s += budgetRow(photonBudget(design, passes));
    s += "  (budget and overrun in photon passes; blocks: expected blocks started; overrun: median and quantiles of the "
         "passes past the budget with finish-block; P(>= 2x): the render takes more than twice its budget; deadline: "
         "the base bias the deadline policy's image keeps, for a smooth photon density, against the truncation's " +
         fmt::format("{:.2g})\n", std::pow(double(d.photon.areaRatio), double(d.photon.levelCap)));
    if (passSeconds > 0.0) {
        const uint64_t passes = std::max<uint64_t>(1, uint64_t(timeLimit / passSeconds));
        const PhotonBudget b = photonBudget(design, passes);
        s += fmt::format("  --time {:g}: {:.3g} s per photon pass (measured here, a few passes) gives a budget of {} passes{}\n",
                         timeLimit, passSeconds, passes,
                         passes > kPhotonBudgetExactPasses ? " (renewal rate beyond 2^22 passes)" : "");
        s += budgetRow(b);
        s += fmt::format("  finish-block: median overrun {:.3g} s, 99% {:.3g} s, 99.9% {:.3g} s; deadline: level weights "
                         "rho_k of the completed blocks:",
                         b.overrunMedian * passSeconds, b.overrun99 * passSeconds, b.overrun999 * passSeconds);
        for (const PhotonBudgetLevel& l : b.levels) {
            if (l.probability < 1e-6 && l.deadlineWeight == 0.0) break;
            s += fmt::format(" k{} {:.3g}", l.level, l.deadlineWeight);
        }
        s += "\n";
    }
    return s;
}

// Seconds per photon pass of this scene on this device: eight passes after two (the first ones
// size the photon map and may run again), setup not counted.
double measurePhotonPassSeconds(gpu::Context& context, const Scene& scene) {
    Renderer renderer(context, resolve(context, scene, kDefaultSeed, true), kDefaultSeed);
    auto passes = [&](uint32_t batches) {
        RenderRequest request;
        request.spp = 1u << 20;
        uint32_t asked = 0;
        request.stop = [&] { return ++asked > batches; };
        renderer.render(request);
    };
    passes(2);
    const double seconds = renderer.stats().wallSeconds;
    const uint64_t done = renderer.stats().integrator.photonPasses;
    passes(8);
    const uint64_t measured = renderer.stats().integrator.photonPasses - done;
    return measured ? (renderer.stats().wallSeconds - seconds) / double(measured) : 0.0;
}

}  // namespace

int runPlan(const CommonOptions& common, const DerivativeCli& derivative, double timeLimit) {
    Scene scene = loadWithOverrides(common);
    if (!derivative.key.empty()) {
        // The versions' checks need the device (the renderer's buffers): plan builds one.
        const DerivativeSettings settings = derivativeSettings(derivative);
        gpu::Context context(contextOptions(common));
        DerivativeRenderer renderer(context, resolve(context, scene, kDefaultSeed, common.quiet), settings, kDefaultSeed);
        Scene base = scene;
        base.integrator.russianRoulette = false;
        fmt::print("{}{}", describePlan(base, renderer.renderer().plan()), renderer.planText());
        return 0;
    }
    GpuScene gpuScene = buildGpuScene(scene);
    fmt::print("{}", describePlan(scene, makeRenderPlan(scene, gpuScene.features)));
    if (timeLimit > 0.0 && !uniformPhotonBlocks(scene.integrator))
        throw InputError(scene.path, "integrator.debias",
                         "plan --time describes unbiased photon mapping's blocks (level_schedule \"uniform\"); this "
                         "scene has none, so every --time render stops within a batch of its limit");
    if (uniformPhotonBlocks(scene.integrator)) {
        double passSeconds = 0.0;
        if (timeLimit > 0.0) {
            gpu::Context context(contextOptions(common));
            passSeconds = measurePhotonPassSeconds(context, scene);
        }
        fmt::print("{}", photonBudgetText(scene.integrator.debias, timeLimit, passSeconds));
    }
    if (*autoPmfKey(scene.integrator)) {
        // pmf "auto": plan runs the pilots a render would run (they need the device) and prints
        // what they measured, the pmf they chose and its predicted work x variance.
        gpu::Context context(contextOptions(common));
        const Resolution resolution = resolveScene(context, scene, kDefaultSeed);
        const Scene& resolved = resolution.scene.scene();
        const std::vector<PmfPilotResult>& pilots = resolution.pilots;
        fmt::print("pmf pilots (seed {}; a render runs them again with its own seed, and timings vary):\n", kDefaultSeed);
        for (const PmfPilotResult& pilot : pilots) {
            const bool marching = pilot.kind == PilotKind::Transmittance;
            const PmfSettings& p = marching ? resolved.integrator.transmittance.pmf : resolved.integrator.debias.pmf;
            fmt::print("{}{} pmf: {}; {}\n", pilot.summary(), marching ? "transmittance" : "path-depth", pmfDescription(p),
                       p.origin);
        }
    }
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

}  // namespace telescope::cli
