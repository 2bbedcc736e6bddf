// A scene every level pmf of which is explicit: what a Renderer and a DerivativeRenderer are made
// from, so that neither can be built with a pmf "auto" still in it (the type says so; there is no
// check at run time to forget). Only resolveScene makes one (render/pmf_pilot.h): it runs the
// pilot of each "auto" pmf and puts the pmf the pilot chose in the scene; a scene without "auto"
// passes through unchanged. The session (session/outputs.h) calls it for every front end.
#pragma once

#include <cstdint>
#include <utility>

#include "scene/scene.h"

namespace telescope {

namespace gpu {
class Context;
}

struct Resolution;
Resolution resolveScene(gpu::Context& context, Scene scene, uint32_t seed);

class ResolvedScene {
public:
    const Scene& scene() const { return scene_; }

private:
    explicit ResolvedScene(Scene scene) : scene_(std::move(scene)) {}
    friend Resolution resolveScene(gpu::Context& context, Scene scene, uint32_t seed);
    Scene scene_;
};

}  // namespace telescope
