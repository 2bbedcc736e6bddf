// Checkpoints: the exact state of a render (a Film's double-precision sums, its sample count, the
// seed and the scene it belongs to) in one binary file. A checkpoint lets a render stop and resume
// (Renderer::resume continues the same random sequence, so a resumed render equals one long
// render), and lets independent renders of one scene with different seeds be merged.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "render/film.h"

namespace telescope {

struct Checkpoint {
    Film film;
    uint32_t seed = 0;
    std::string scene;      // the scene document (after overrides), as JSON text
    std::string estimator;  // the plan's one-line estimator description
    // The settings as run (resolvedSettings(): defaults filled in, pmf "auto" resolved), as JSON
    // text; empty in version-1 checkpoints, which did not record them.
    std::string settings;
    // The seeds of the renders whose samples the film holds: {seed} for one render, every
    // shard's seed for a merge. A merge refuses two checkpoints that share a seed.
    std::vector<uint32_t> seeds;
};

// Written to a temporary name and renamed (core/atomic_file.h): an interrupted write leaves the
// old file intact. Version 2 adds the settings, the seeds and the film's per-pixel-count flag;
// version 3 the samples in progress (Film::pending: a photon block that has run some passes).
void saveCheckpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws InputError naming the file when it is missing, truncated or not a checkpoint.
Checkpoint loadCheckpoint(const std::string& path);

// What a checkpoint records about itself, without reading its pixel sums (a merge of many
// large checkpoints checks them all before it holds more than two films in memory). Checks
// that the file is as long as its header says.
struct CheckpointHeader {
    uint32_t width = 0, height = 0;
    uint64_t samplesPerPixel = 0;
    uint32_t seed = 0;
    std::string scene, estimator, settings;
    std::vector<uint32_t> seeds;
    bool perPixelCounts = false;
    // The samples in progress (version 3; film.h PendingSamples): units done of the block, its
    // units and level, and the bytes of its device state.
    uint32_t pendingUnits = 0, pendingUnitsTotal = 0, pendingLevel = 0;
    uint64_t pendingBytes = 0;
};
CheckpointHeader readCheckpointHeader(const std::string& path);

}  // namespace telescope
