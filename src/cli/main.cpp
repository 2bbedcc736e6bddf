// telescope: command-line front end.
//
//   telescope render SCENE -o OUT.exr [--spp N | --time SECONDS] [--seed S] [--set key=value ...]
//                          [--checkpoint FILE] [--resume FILE]
//   telescope reference SCENE -o REF.exr (--spp N | --time SECONDS)    unbiased, resumable
//   telescope merge A.checkpoint B.checkpoint ... -o OUT.exr            independent renders
//   telescope shard SCENE --shards N --spp-per-shard S -o DIR            scale-out (cli/shard.h)
//   telescope shard-render DIR [--task I]   telescope shard-merge DIR -o OUT.exr
//   telescope converge SCENE --reference REF.exr --methods A,B (--time T | --spp LIST) -o DIR
//   telescope plan SCENE [--set key=value ...]
//   telescope view SCENE [--set key=value ...] [-o SAVE.exr] [--spp N]   interactive (GLFW window)
//   telescope study transmittance -o DIR [--samples N] [--level K]    the 1-D transmittance study
//   telescope devices
//
// Exit codes: 0 success, 2 bad input (one line naming the file and the key), 1 runtime failure.

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "cli/commands.h"
#include "session/interrupt.h"
#include "cli/shard.h"
#include "core/error.h"
#include "study/methods.h"
#include "viewer/view_command.h"

using namespace telescope;
using namespace telescope::cli;

int main(int argc, char** argv) {
    CLI::App app{"Telescope: unbiased and consistent rendering from biased estimators (Vulkan compute)"};
    app.require_subcommand(1);
    CommonOptions common;

    auto addCommon = [&](CLI::App* cmd, bool scene = true) {
        if (scene) {
            cmd->add_option("scene", common.scenePath, "Scene file (Tungsten JSON)")->required();
            cmd->add_option("--set", common.sets, "Override a scene key: key.path=value (JSON value)");
        }
        cmd->add_option("--device", common.device, "Vulkan device index (see 'telescope devices')");
        cmd->add_flag("--validation", common.validation, "Enable Vulkan validation layers (or TELESCOPE_VALIDATION=1)");
        cmd->add_flag("-q,--quiet", common.quiet, "No progress output");
    };
    auto addImageOutput = [](CLI::App* cmd, ImageOutputOptions& o, const char* checkpointHelp) {
        cmd->add_option("-o,--output", o.exrPath, "Output EXR")->required();
        cmd->add_option("--png", o.pngPath, "Preview PNG (default: OUT with .png)");
        cmd->add_flag("--no-png", o.noPng, "Do not write a PNG preview");
        cmd->add_option("--checkpoint", o.checkpointPath, checkpointHelp);
    };
    // The budget of a render: --spp or --time, not both.
    auto addBudget = [](CLI::App* cmd, uint64_t& spp, double& seconds, const char* sppHelp, const char* timeHelp) {
        auto* sppOpt = cmd->add_option("--spp", spp, sppHelp)->check(CLI::PositiveNumber);
        cmd->add_option("--time", seconds, timeHelp)->check(CLI::PositiveNumber)->excludes(sppOpt);
    };

    // ---- render ----
    RenderOptions renderOptions;
    auto* render = app.add_subcommand("render", "Render a scene to a float EXR and a PNG preview");
    addCommon(render);
    addImageOutput(render, renderOptions.output, "Also write the exact render state here (to resume or merge)");
    addBudget(render, renderOptions.spp, renderOptions.timeLimit, "Samples per pixel (default: renderer.spp)",
              "Render for this many seconds instead of a fixed spp");
    render->add_option("--time-policy", renderOptions.timePolicy,
                       "With --time: finish-block (default; a photon block running at the limit is finished, which "
                       "can overrun) or deadline (stop at the limit; the block goes to the checkpoint, and the image "
                       "of the completed blocks leans towards short blocks: see 'telescope plan --time')")
        ->check(CLI::IsMember({"finish-block", "deadline"}));
    auto* seedOpt = render->add_option("--seed", renderOptions.seed, "Random seed");
    render->add_option("--stats-json", renderOptions.statsPath, "Write per-pass times, dispatch counts and device here");
    render->add_option("--resume", renderOptions.resumePath,
                       "Continue the render in this checkpoint (same scene and overrides), adding --spp or --time");
    auto addDerivative = [](CLI::App* cmd, DerivativeCli& d) {
        cmd->add_option("--derivative", d.key,
                        "Render the derivative image with respect to this numeric scene value (a --set key path)");
        cmd->add_option("--step", d.step, "The derivative's largest finite-difference step h_0 (default: |value| / 16)");
        cmd->add_option("--derivative-estimator", d.estimator,
                        "forward, central, single_term (default), sum or progressive");
        cmd->add_option("--derivative-levels", d.levels, "Levels of the telescoping series (default 8: h down to h_0 / 256)");
        cmd->add_option("--derivative-pmf", d.pmf,
                        "Level pmf, JSON: {\"type\": \"geometric\", \"r\": 0.5} (default), power_law with alpha, or {\"type\": \"auto\"} (a pilot measures the recipe)");
    };
    addDerivative(render, renderOptions.derivative);
    render->add_option("--checkpoint-every", renderOptions.checkpointEvery,
                       "Also write the checkpoint every SECONDS while rendering (default file: OUT.exr.checkpoint)")
        ->check(CLI::PositiveNumber);

    // ---- reference ----
    ReferenceOptions referenceOptions;
    auto* reference = app.add_subcommand(
        "reference", "Render an unbiased reference, resumable: rerunning continues from OUT.exr.checkpoint");
    addCommon(reference);
    addImageOutput(reference, referenceOptions.output, "Checkpoint file (default: OUT.exr.checkpoint)");
    addBudget(reference, referenceOptions.spp, referenceOptions.timeLimit, "Samples per pixel to add", "Seconds to add");
    reference->add_option("--seed", referenceOptions.seed, "Random seed");
    addDerivative(reference, referenceOptions.derivative);
    reference->add_option("--checkpoint-every,--checkpoint-interval", referenceOptions.checkpointInterval,
                          "Seconds between checkpoints (default 30)")
        ->check(CLI::PositiveNumber);

    // ---- merge ----
    MergeOptions mergeOptions;
    auto* merge = app.add_subcommand("merge", "Merge checkpoints of independent renders (different seeds) of one scene");
    merge->add_option("inputs", mergeOptions.inputs, "Checkpoints")->required();
    addImageOutput(merge, mergeOptions.output, "Also write the merged state here");
    merge->add_flag("-q,--quiet", mergeOptions.quiet, "No output but errors");

    // ---- shard, shard-render, shard-merge: scale-out (cli/shard.h, tools/slurm/) ----
    ShardPlanOptions shardOptions;
    auto* shard = app.add_subcommand("shard", "Plan a render split into shards of seeds SEED+0..N-1 (a Slurm array: "
                                              "tools/slurm/submit): writes DIR/shards.json");
    addCommon(shard);
    shard->add_option("--shards", shardOptions.shards, "Number of shards (array tasks)")->required()->check(CLI::PositiveNumber);
    auto* shardSpp = shard->add_option("--spp-per-shard", shardOptions.sppPerShard, "Samples per pixel of each shard")
                         ->check(CLI::PositiveNumber);
    shard->add_option("--time-per-shard", shardOptions.timePerShard, "Or: seconds of rendering per shard")
        ->check(CLI::PositiveNumber)
        ->excludes(shardSpp);
    shard->add_option("--seed", shardOptions.seed, "Base seed: shard i renders seed SEED + i");
    addDerivative(shard, shardOptions.derivative);
    shard->add_option("-o,--output", shardOptions.outDir, "Directory for the plan, the shards and their checkpoints")
        ->required();
    ShardRenderOptions shardRenderOptions;
    auto* shardRender = app.add_subcommand("shard-render", "Render one shard of a plan (an array task); resumes its "
                                                           "checkpoint when requeued");
    shardRender->add_option("dir", shardRenderOptions.dir, "The plan's directory")->required();
    shardRender->add_option("--task", shardRenderOptions.task, "Shard index (default: $SLURM_ARRAY_TASK_ID)");
    shardRender->add_option("--checkpoint-every", shardRenderOptions.checkpointEvery,
                            "Seconds between checkpoints (default 60)")
        ->check(CLI::PositiveNumber);
    addCommon(shardRender, false);
    ShardMergeOptions shardMergeOptions;
    auto* shardMerge = app.add_subcommand("shard-merge", "Merge every shard of a plan into one EXR (the dependent job)");
    shardMerge->add_option("dir", shardMergeOptions.dir, "The plan's directory")->required();
    addImageOutput(shardMerge, shardMergeOptions.output, "Also write the merged state here");
    shardMerge->add_flag("--allow-missing", shardMergeOptions.allowMissing,
                         "Merge the shards that have a checkpoint when some have none (failed tasks)");
    shardMerge->add_flag("-q,--quiet", shardMergeOptions.quiet, "No output but errors");

    // ---- converge ----
    ConvergeOptionsCli convergeOptions;
    auto* converge = app.add_subcommand(
        "converge", "Error against a reference as a function of time, per method: CSV, plot, image strip, report");
    addCommon(converge);
    converge->add_option("--reference", convergeOptions.referencePath, "Reference EXR")->required();
    converge->add_option("--methods", convergeOptions.presets, "Presets, comma separated:\n" + describePresets())
        ->delimiter(',');
    converge->add_option("--method", convergeOptions.custom, "A custom method: 'LABEL: key=value; key=value'");
    auto* convTime = converge->add_option("--time", convergeOptions.timeBudget, "Render seconds per method")
                         ->check(CLI::PositiveNumber);
    converge->add_option("--slices", convergeOptions.slices, "Doubling time slices (default 8)");
    converge->add_option("--spp", convergeOptions.sppList, "Or: increasing total sample counts, comma separated")
        ->delimiter(',')
        ->excludes(convTime);
    converge->add_option("--seed", convergeOptions.seed, "Random seed");
    converge->add_option("--seeds", convergeOptions.seeds,
                         "Independent runs per method (seeds SEED, SEED+1, ...); the table and plot show their mean");
    converge->add_option("--region", convergeOptions.region,
                         "Measure the error over pixels X,Y,W,H only (e.g. a caustic); the strip shows that crop")
        ->delimiter(',');
    converge->add_option("-o,--output", convergeOptions.outDir, "Output directory")->required();
    addDerivative(converge, convergeOptions.derivative);

    // ---- study transmittance ----
    StudyTransmittanceCli studyOptions;
    auto* study = app.add_subcommand("study", "Studies that need no scene");
    study->require_subcommand(1);
    auto* studyTr = study->add_subcommand(
        "transmittance", "Every transmittance estimator on 1-D problems on the device: work x MSE as CSV, heat maps, summary");
    addCommon(studyTr, false);
    studyTr->add_option("-o,--output", studyOptions.outDir, "Output directory")->required();
    studyTr->add_option("--samples", studyOptions.samples, "Estimates per estimator and problem (default 16384)")
        ->check(CLI::PositiveNumber);
    studyTr->add_option("--level", studyOptions.level,
                        "Ray-marching level k (2^k points), debiased base and taylor pivot (default 1)");
    studyTr->add_option("--taylor-terms", studyOptions.terms, "Terms taylor always evaluates before its roulette");
    studyTr->add_option("--seed", studyOptions.seed, "Random seed");

    // ---- view: the interactive front end (src/viewer) ----
    viewer::ViewOptions viewOptions;
    auto* view = app.add_subcommand("view", "Render progressively in a window (GLFW; X11 or xvfb-run): estimate, base, "
                                            "correction, its parts and the standard error on keys");
    addCommon(view);
    view->add_option("-o,--output", viewOptions.output.exrPath, "Where the save key (s) writes (default: SCENE-view.exr)");
    view->add_option("--png", viewOptions.output.pngPath, "PNG preview written with it (default: OUT with .png)");
    view->add_flag("--no-png", viewOptions.output.noPng, "Save no PNG preview");
    view->add_option("--seed", viewOptions.seed, "Random seed");
    view->add_option("--spp", viewOptions.spp, "Stop adding samples at this count (default: never)")
        ->check(CLI::PositiveNumber);
    view->add_option("--channel", viewOptions.channel,
                     "Channel shown first: estimate, base, correction, correction_positive, correction_negative, "
                     "standard_error");
    view->add_option("--frames", viewOptions.frames, "Scripting: exit after this many frames")->check(CLI::PositiveNumber);
    view->add_option("--screenshot", viewOptions.screenshot, "Scripting: PNG of the window as last presented, on exit");
    addDerivative(view, viewOptions.derivative);
    view->add_option("--keys", viewOptions.keys,
                     "Scripting: input events KEY@FRAME,... (keys as named in the README; drag:DX:DY, pan:DX:DY, "
                     "scroll:N)");

    // ---- plan, devices ----
    auto* plan = app.add_subcommand("plan", "Print the passes a render of the scene would run, and why");
    addCommon(plan);
    DerivativeCli planDerivative;
    addDerivative(plan, planDerivative);
    double planTime = 0.0;
    plan->add_option("--time", planTime,
                     "Unbiased photon mapping: what a --time budget of this many seconds does to the blocks (times "
                     "a few photon passes on the device first)")
        ->check(CLI::PositiveNumber);
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
        renderOptions.seedGiven = seedOpt->count() > 0;
        if (render->parsed()) return runRender(common, renderOptions);
        if (reference->parsed()) return runReference(common, referenceOptions);
        if (merge->parsed()) return runMerge(mergeOptions);
        if (shard->parsed()) return runShardPlan(common, shardOptions);
        if (shardRender->parsed()) return runShardRender(common, shardRenderOptions);
        if (shardMerge->parsed()) return runShardMerge(shardMergeOptions);
        if (converge->parsed()) return runConverge(common, convergeOptions);
        if (plan->parsed()) return runPlan(common, planDerivative, planTime);
        if (view->parsed()) return viewer::runView(common, viewOptions);
        if (studyTr->parsed()) return runStudyTransmittance(common, studyOptions);
        return runDevices();
    } catch (const InputError& e) {
        fmt::print(stderr, "telescope: {}\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        fmt::print(stderr, "telescope: error: {}{}\n", e.what(), session::keptCheckpointsNote());
        return 1;
    }
}
