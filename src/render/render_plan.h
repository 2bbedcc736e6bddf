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

// Every pass a render can dispatch, once: its name (the plan's, and the label its dispatches are
// timed under in RenderStats::passes), the shader it runs unless the plan picks a variant, and what
// it binds. The plan lists the passes a render runs (PlannedPass); the integrators' passes create
// their pipelines from those entries and label their dispatches with passName.
enum class PassKind : uint32_t {
    PathTrace,
    LevelCount,
    LevelScan,
    LevelScatter,
    PathResolve,
    PhotonTrace,
    HashGridBuild,
    Gather,
    GridQuery,
};
struct PassInfo {
    PassKind kind;
    const char* name;
    const char* shader;    // .comp file without extension
    const char* bindings;  // in words: what the pass reads and writes
};
inline constexpr PassInfo kPassTable[] = {
    {PassKind::PathTrace, "path_trace", "path_trace",
     "the scene (RenderBuffers::sceneBindings, media included); the film, pilot sums, loop statistics and "
     "continuation records by address"},
    {PassKind::LevelCount, "level_count", "level_count", "the level queue by address"},
    {PassKind::LevelScan, "level_scan", "level_scan", "the level queue by address"},
    {PassKind::LevelScatter, "level_scatter", "level_scatter", "the level queue by address"},
    {PassKind::PathResolve, "path_resolve", "path_resolve", "the level queue and the film by address"},
    {PassKind::PhotonTrace, "photon_trace", "photon_trace",
     "the scene (sceneBindings without media); the photon buffer by address"},
    {PassKind::HashGridBuild, "hash_grid_build", "hash_grid_build",
     "the photon arrays as texels and storage texels (kGridBinding*), or by address"},
    {PassKind::Gather, "gather", "gather",
     "the scene without media, the sorted photons' texels at kBindingSortedTexels; blocks and film by address"},
    {PassKind::GridQuery, "query", "hash_grid_build", "as hash_grid_build; kernel sums at query points (tests only)"},
};
const PassInfo& passInfo(PassKind kind);
inline const char* passName(PassKind kind) { return passInfo(kind).name; }

struct PlannedPass {
    PassKind kind = PassKind::PathTrace;
    std::string name;    // passName(kind), or the pmf pilots' entries (pilot true)
    std::string shader;  // .comp file (without extension): the table's, or the plan's variant of it
    std::string why;
    // Run before the render by the pmf pilots' own Renderers (render/pmf_pilot.h), not by this one.
    bool pilot = false;
};
// The plan's entry for a pass of the table (its shader the table's).
PlannedPass plannedPass(PassKind kind, std::string why);

struct SkippedPass {
    std::string name;
    std::string why;
};

// One line of `plan`'s summary of what a pipeline is compiled with: read off the pipeline's
// specialisation (specSwitch), so the summary cannot disagree with the pipeline.
struct FeatureSwitch {
    std::string name;
    bool on = false;
    std::string why;  // ends with the constant and its value as the table names them
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

// The plan's entry of a pass this render dispatches; std::logic_error when the plan has none.
const PlannedPass& plannedEntry(const RenderPlan& plan, PassKind kind);

RenderPlan makeRenderPlan(const Scene& scene, const SceneFeatures& features, const PlanOptions& options = {});

// Human-readable plan, as `telescope plan` prints it.
std::string describePlan(const Scene& scene, const RenderPlan& plan);

std::string pmfDescription(const PmfSettings& pmf);

// A pipeline's specialisation constants, one line each (id, name, value, why) from the table of
// shader features (shared/spec_constants.h), in id order; throws std::logic_error for an id the
// table lacks.
std::string describeSpecialisation(const std::vector<gpu::SpecConstant>& spec);
// The feature switch `name` of a pipeline specialised with `spec`: on when the constant `id` is
// not `offValue`, explained by `onWhy` (default: the table's why) when on and by `offWhy` when off,
// then by the table's name of the constant and its value. std::logic_error when `spec` does not set
// `id`.
FeatureSwitch specSwitch(const std::vector<gpu::SpecConstant>& spec, const char* name, uint32_t id,
                         const std::string& offWhy, uint32_t offValue = 0, const std::string& onWhy = "");
// The value of constant `id` in `spec` (std::logic_error when it is not set).
uint32_t specValue(const std::vector<gpu::SpecConstant>& spec, uint32_t id);
// The switches of the scene that every integrator's pipelines compile on: primitive kinds, delta
// materials, textures, where the scene is read from, brute-force rays.
std::vector<FeatureSwitch> sceneFeatureSwitches(const std::vector<gpu::SpecConstant>& spec, const SceneFeatures& f);

// The reconstruction filter as the camera passes see it (kFilter*).
uint32_t filterConstant(const Camera& camera);

}  // namespace telescope
