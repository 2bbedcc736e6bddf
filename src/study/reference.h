// Which overrides make a scene's integrator unbiased, for `telescope reference`.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"
#include "scene/scene_loader.h"

namespace telescope {

struct UnbiasedSetup {
    std::vector<SceneOverride> overrides;  // empty when the scene's integrator is unbiased as given
    std::string why;                       // one line for the log
};

// The path tracer gets the Russian-roulette sum estimator over path depth at its own max_bounces
// (plain path tracing with Russian roulette: it only adds the rare deeper paths) unless it has a
// debias block already. Photon mapping (biased or progressive) gets its unbiased variant: the
// debias block over radius levels.
UnbiasedSetup unbiasedSetup(const Scene& scene);

}  // namespace telescope
