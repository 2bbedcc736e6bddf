// What makes a scene's integrator unbiased, for `telescope reference`: a typed patch on its
// settings (the scene document stays as given; the outputs record the patched settings).
#pragma once

#include <string>

#include "scene/scene.h"

namespace telescope {

struct UnbiasedSetup {
    IntegratorSettings integrator;  // the scene's, patched (unchanged when unbiased as given)
    std::string why;                // one line for the log
};

// The path tracer gets the Russian-roulette sum estimator over path depth at its own max_bounces
// (plain path tracing with Russian roulette: it only adds the rare deeper paths) unless it has a
// debias block already. Photon scenes are rendered by the path tracer with that sum estimator:
// unbiased photon mapping has a Cauchy-like per-pixel error (docs/PHOTON-MAPPING.md).
UnbiasedSetup unbiasedSetup(const Scene& scene);

}  // namespace telescope
