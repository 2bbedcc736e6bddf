// Checkpoints: the exact state of a render (a Film's double-precision sums, its sample count, the
// seed and the scene it belongs to) in one binary file. A checkpoint lets a render stop and resume
// (Renderer::resume continues the same random sequence, so a resumed render equals one long
// render), and lets independent renders of one scene with different seeds be merged.
#pragma once

#include <cstdint>
#include <string>

#include "render/film.h"

namespace telescope {

struct Checkpoint {
    Film film;
    uint32_t seed = 0;
    std::string scene;      // the scene document (after overrides), as JSON text
    std::string estimator;  // the plan's one-line estimator description
};

// Written to a temporary name and renamed: an interrupted write leaves the old file intact.
void saveCheckpoint(const std::string& path, const Checkpoint& checkpoint);
// Throws InputError naming the file when it is missing, truncated or not a checkpoint.
Checkpoint loadCheckpoint(const std::string& path);

}  // namespace telescope
