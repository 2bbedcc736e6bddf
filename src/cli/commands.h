// The telescope subcommands. main.cpp parses the command line into these option structs;
// each run* function returns the process exit code and throws InputError for bad input.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "session/options.h"

namespace telescope::cli {

// The options shared with the viewer live in the session layer.
using session::CommonOptions;
using session::ImageOutputOptions;
using session::kDefaultSeed;
using DerivativeCli = session::DerivativeOptions;

struct RenderOptions {
    DerivativeCli derivative;
    ImageOutputOptions output;
    uint64_t spp = 0;        // 0: the scene's renderer.spp
    double timeLimit = 0.0;  // seconds, instead of spp
    // --time-policy: "finish-block" (default) finishes a photon block running at the time limit;
    // "deadline" stops there and keeps the block in the checkpoint (RenderRequest).
    std::string timePolicy = "finish-block";
    uint32_t seed = kDefaultSeed;
    bool seedGiven = false;  // with --resume the checkpoint's seed is used unless --seed says otherwise
    std::string statsPath;
    std::string resumePath;  // a checkpoint to continue
    double checkpointEvery = 0.0;  // seconds between periodic checkpoints (0: only at the end)
};

struct ReferenceOptions {
    DerivativeCli derivative;   // --derivative KEY: a resumable derivative reference
    ImageOutputOptions output;  // checkpoint defaults to OUT.exr.checkpoint
    uint64_t spp = 0;
    double timeLimit = 0.0;
    uint32_t seed = kDefaultSeed;
    double checkpointInterval = 30.0;  // seconds between checkpoints
};

struct MergeOptions {
    std::vector<std::string> inputs;  // checkpoints
    ImageOutputOptions output;
    bool quiet = false;
};

struct ConvergeOptionsCli {
    DerivativeCli derivative;  // --derivative KEY: the methods are derivative estimators
    std::string referencePath;
    std::vector<std::string> presets;  // --methods A,B
    std::vector<std::string> custom;   // --method 'LABEL: key=value; ...'
    double timeBudget = 0.0;
    uint32_t slices = 8;
    std::vector<uint64_t> sppList;
    uint32_t seed = 1;
    uint32_t seeds = 1;
    std::vector<int> region;  // --region X,Y,W,H
    std::string outDir;
};

struct StudyTransmittanceCli {
    std::string outDir;
    uint32_t samples = 16384;
    uint32_t level = 1;
    uint32_t terms = 1;  // taylor's forced terms, as in TransmittanceEstimatorSettings
    uint32_t seed = 1;
};

int runRender(const CommonOptions& common, const RenderOptions& options);
int runStudyTransmittance(const CommonOptions& common, const StudyTransmittanceCli& options);
int runReference(const CommonOptions& common, const ReferenceOptions& options);
int runMerge(const MergeOptions& options);
int runConverge(const CommonOptions& common, const ConvergeOptionsCli& options);
// timeLimit > 0: for unbiased photon mapping's uniform blocks, times photon passes and prints
// what a budget of that many seconds does (scene/photon_budget.h).
int runPlan(const CommonOptions& common, const DerivativeCli& derivative = {}, double timeLimit = 0.0);
int runDevices();

}  // namespace telescope::cli
