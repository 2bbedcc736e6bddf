// Scale-out: one render split into shards of different seeds, rendered anywhere (a Slurm array,
// tools/slurm/), and merged exactly.
//
//   telescope shard SCENE --shards N (--spp-per-shard S | --time-per-shard T) [--seed B] -o DIR
//       writes DIR/shards.json: the scene (after --set), its settings, N, S or T, and the seeds
//       B, B+1, ... B+N-1 (shard i renders seed B + i)
//   telescope shard-render DIR --task I      (I defaults to $SLURM_ARRAY_TASK_ID)
//       renders shard I into DIR/shard-I.checkpoint and .exr; a checkpoint already there (a
//       requeued task) is resumed up to S samples
//   telescope shard-merge DIR -o OUT.exr
//       merges every shard's checkpoint (telescope merge) after checking that each belongs to
//       the plan
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "render/film.h"

namespace telescope::cli {

struct ShardPlanOptions {
    DerivativeCli derivative;  // --derivative KEY: every shard renders the derivative image
    uint32_t shards = 0;
    uint64_t sppPerShard = 0;
    double timePerShard = 0.0;
    uint32_t seed = kDefaultSeed;
    std::string outDir;
};

struct ShardRenderOptions {
    std::string dir;
    int task = -1;                // -1: $SLURM_ARRAY_TASK_ID
    double checkpointEvery = 60;  // seconds: a preempted or killed task loses at most this
};

struct ShardMergeOptions {
    std::string dir;
    ImageOutputOptions output;
    bool allowMissing = false;  // merge the shards that exist (a failed task) instead of refusing
    bool quiet = false;
};

int runShardPlan(const CommonOptions& common, const ShardPlanOptions& options);
int runShardRender(const CommonOptions& common, const ShardRenderOptions& options);
int runShardMerge(const ShardMergeOptions& options);

// The core of `telescope merge`: loads the checkpoints, refuses (InputError naming both files)
// other scenes, settings, image sizes or a seed two of them share, and adds their sums in the
// order of their seeds, so the result does not depend on the order of the arguments.
struct MergedRender {
    Film film;
    std::string scene, estimator, settings;
    std::vector<uint32_t> seeds;  // sorted
    std::string shards;           // JSON list: file, seeds and spp of each merged checkpoint
    // Checkpoints that held a photon block in progress: their completed blocks are merged, the
    // block is not (Film::merge), and the merge says so.
    std::vector<std::string> blocksLeftOut;
};
MergedRender mergeCheckpointFiles(const std::vector<std::string>& paths);

}  // namespace telescope::cli
