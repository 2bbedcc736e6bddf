// What accuracy costs in time: renders each method of a scene in time (or sample) slices and
// records its error against a reference after every slice.
//
// Output, in one directory: convergence.csv (one row per method and slice: samples, wall and
// GPU seconds, RMSE, relative MSE, mean signed error), convergence.png (gnuplot: relative MSE
// and |bias| against GPU time, log-log, with fitted slopes), strip.png (the same crop of the
// reference and of every method's final image: an equal-time strip when slices are timed),
// report.md (a table of the above and how to read it) and settings.json (the resolved settings of
// every method's runs).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gpu/context.h"
#include "render/derivative.h"
#include "study/error_metrics.h"
#include "study/methods.h"

namespace telescope {

struct ConvergeOptions {
    std::string scenePath;
    // The scene with the command's --set overrides and then a method's (session::loadWithOverrides):
    // one loader for every front end. Throws InputError naming the file and key.
    std::function<Scene(const std::vector<SceneOverride>&)> load;
    std::string referencePath;        // an EXR from `telescope reference` (or `render`)
    std::vector<Method> methods;
    double timeBudget = 0.0;          // render seconds per method, split into `slices` doubling slices
    uint32_t slices = 8;
    std::vector<uint64_t> sppList;    // or: measure after each of these total sample counts
    uint32_t seed = 1;
    uint32_t seedCount = 1;           // independent runs per method: seeds seed, seed + 1, ...
    PixelRegion region;               // errors over these pixels only (w = 0: all); also the strip's crop
    std::string outDir;
    std::function<void(const std::string&)> log;  // progress lines (may be empty)
    // Derivative studies (--derivative KEY): the methods are derivative estimators (one per method,
    // in `derivativeEstimators`), rendered with these settings against a derivative reference.
    bool derivative = false;
    DerivativeSettings derivativeSettings;
    std::vector<DerivativeEstimator> derivativeEstimators;
};

// One slice of one method: of one seed's run, or (seed = kAllSeeds) the mean over the seeds of
// the slices every run reached (times, samples and errors averaged; the relative MSE of the mean
// over seeds is an unbiased estimate of the expected relative MSE).
constexpr uint32_t kAllSeeds = 0xffffffffu;

struct ConvergePoint {
    std::string method;
    uint32_t seed = kAllSeeds;
    uint32_t slice = 0;
    uint64_t spp = 0;
    double wallSeconds = 0.0;  // render time, pipeline creation excluded
    double gpuSeconds = 0.0;   // sum of the passes' timestamp intervals
    ErrorMetrics error;
};

struct MethodSummary {
    Method method;
    std::string estimator;        // the plan's description
    ConvergePoint last;
    double slope = 0.0;           // log-log slope of relative MSE against GPU time, all slices
    double slopeLateHalf = 0.0;   // the same over the second half of the slices
    double secondsTo1e2 = -1.0;   // GPU seconds to relative MSE 1e-2 (-1: not within the budget)
    double secondsTo1e3 = -1.0;
    uint64_t nonFiniteSamples = 0;
    double pilotGpuSeconds = 0.0;   // pmf pilot (pmf "auto"), included in the times above
    double pilotWallSeconds = 0.0;  // (means over the seeds)
    std::string pilotChoices;       // pmf "auto": the pmf each seed's pilot chose
    std::vector<double> seedWorkTimesMse;  // GPU seconds x relative MSE at the end, per seed
    std::vector<nlohmann::json> settings;  // resolvedSettings per seed (an auto pmf resolved)
};

struct ConvergeReport {
    std::vector<ConvergePoint> points;  // every seed's slices, then (seed kAllSeeds) their means
    std::vector<MethodSummary> methods;
    std::vector<std::string> files;  // written, in order
};

// Bad input (scene, method overrides, reference of the wrong size) throws InputError before
// anything is rendered or written.
ConvergeReport runConverge(gpu::Context& context, const ConvergeOptions& options);

}  // namespace telescope
