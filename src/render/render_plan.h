// What a render of a scene runs, and why: the start of "simulate only what the scene calls for".
//
// The plan names every pass the host will dispatch and the passes it will not, with the reason
// for each, and the specialisation constants that fold the scene's absent features (spheres,
// disks, specular materials, kinds of light, debiasing) out of the compiled pipelines.
#pragma once

#include <string>
#include <vector>

#include "gpu/pipeline.h"
#include "render/gpu_scene.h"
#include "scene/scene.h"

namespace telescope {

struct PlannedPass {
    std::string name;    // dispatch name, used for timing and stats
    std::string shader;  // .comp file (without extension)
    std::string why;
};

struct SkippedPass {
    std::string name;
    std::string why;
};

struct FeatureSwitch {
    std::string name;
    bool on = false;
    std::string why;
};

// The pmf pilot's renders (render/pmf_pilot.h) take every sample at one fixed level and record the
// unweighted correction D_j instead of the estimate: a way of running the path tracer, not a
// setting of the scene. The path-depth pilot records D_j in its own sums; the transmittance pilot
// fixes debiased marching's level (its pilotLevel may carry shader::kTrPilotHalfWeight) and the
// host differences two renders.
constexpr uint32_t kNoPilotLevel = 0xffffffffu;
enum class PilotKind { PathDepth, Transmittance };

// How a plan runs the integrator beyond the scene's settings: the pmf pilots' fixed levels.
struct PlanOptions {
    uint32_t pilotLevel = kNoPilotLevel;
    PilotKind pilotKind = PilotKind::PathDepth;
};

struct RenderPlan {
    std::vector<PlannedPass> passes;     // in dispatch order, per batch of samples
    std::vector<SkippedPass> skipped;
    std::vector<FeatureSwitch> features;
    std::vector<gpu::SpecConstant> pathTraceSpec;  // path_trace
    std::string pathTraceShader = "path_trace";    // or "path_trace_glossy" (glossy materials present)
    std::vector<gpu::SpecConstant> photonSpec;     // photon_trace and gather
    // photon_trace: a sphere around the geometry (centre, radius); lights at infinity (the
    // environment, a cap) emit their photons through its disk facing each direction.
    glm::vec3 photonSceneCentre{0.0f};
    float photonSceneRadius = 1.0f;
    std::string featuresOf = "path_trace";         // the pipeline(s) the feature switches describe
    std::string estimator;               // one line describing the estimator
    LevelSchedule levelSchedule = LevelSchedule::PerPixel;  // as run (per_pixel unless debiased)
    uint32_t pilotLevel = kNoPilotLevel;  // the pmf pilot's first level (path tracer only)
    PilotKind pilotKind = PilotKind::PathDepth;
};

RenderPlan makeRenderPlan(const Scene& scene, const SceneFeatures& features, uint32_t pilotLevel = kNoPilotLevel,
                          PilotKind pilotKind = PilotKind::PathDepth);

// Human-readable plan, as `telescope plan` prints it.
std::string describePlan(const Scene& scene, const RenderPlan& plan);

std::string pmfDescription(const PmfSettings& pmf);

// A pipeline's specialisation constants, one line each (id, name, value, why) from the table of
// shader features (shared/spec_constants.h), in id order; throws std::logic_error for an id the
// table lacks.
std::string describeSpecialisation(const std::vector<gpu::SpecConstant>& spec);

// The reconstruction filter as the camera passes see it (kFilter*).
uint32_t filterConstant(const Camera& camera);

}  // namespace telescope
