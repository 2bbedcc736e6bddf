// The passes an integrator contributes to a render, scheduled generically by the Renderer.
//
// A render adds samples per pixel in units: a unit is the dispatches that add samplesPerUnit()
// samples (the path tracer: one path_trace dispatch of several samples; photon mapping: one
// photon pass of photon_trace, hash_grid_build and gather, one sample per pixel). The Renderer
// records up to maxUnitsPerBatch() units into one submit, and asks batchComplete() afterwards:
// a batch that must be repeated (photon buffers grown) has added nothing to the accumulation.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "render/film.h"
#include "render/render_plan.h"
#include "scene/scene.h"
#include "shared/camera.h"

namespace telescope {

// The pmf pilot's result buffer read back (shared/gpu_types.h kPilot*): per channel and pixel the
// sum over the pilot's samples, in double.
struct PilotSums {
    uint64_t samples = 0;  // per pixel
    std::array<std::vector<glm::dvec4>, shader::kPilotChannelCount> sums;
    glm::dvec3 mean(uint32_t channel, size_t pixel) const {
        return samples ? glm::dvec3(sums[channel][pixel]) / double(samples) : glm::dvec3(0.0);
    }
};

// The camera part of a camera pass's push constants (PathTracePush, GatherPush).
template <class Push>
void setPushCamera(Push& push, const Camera& cam) {
    push.cameraPosition = cam.position;
    push.cameraRight = cam.right;
    push.cameraUp = cam.up;
    push.cameraForward = cam.forward;
    push.planeDistance = shader::cameraPlaneDistance(cam.fovDegrees);
}

// path_trace's loop budget on this device (shared/gpu_types.h "Lavapipe's loop cap"):
// kDefaultLoopBudget on lavapipe, 0 (none) on devices without its loop cap. $TELESCOPE_LOOP_BUDGET
// overrides it (tests force tiny budgets with it; 0 turns the budget off).
uint32_t deviceLoopBudget(const gpu::Context& context);

// Buffers the integrators read: the scene (bindings 0..3), the accumulation (by address) and the
// media (path tracer only).
struct RenderBuffers {
    const gpu::Buffer* prims = nullptr;
    const gpu::Buffer* nodes = nullptr;
    const gpu::Buffer* materials = nullptr;
    const gpu::Buffer* lights = nullptr;
    const gpu::Buffer* accum = nullptr;
    // Participating media (bindings 4..6 of path_trace).
    const gpu::Buffer* media = nullptr;
    const gpu::Buffer* gridData = nullptr;
    const gpu::Buffer* primMedia = nullptr;
    const gpu::Buffer* textures = nullptr;  // binding 9 of path_trace (shared/texture.h)
    const gpu::Buffer* environment = nullptr;  // binding kBindingEnvironment of path_trace
    const gpu::Buffer* shadingNormals = nullptr;  // binding kBindingShadingNormals of every scene pass

    // Whether the BVH nodes, primitives and shading normals fit the device's texel buffers
    // (kSpecSceneTexels).
    bool sceneTexelsFit(const gpu::Context& context) const {
        return gpu::Buffer::texelViewFits(context, nodes->size()) && gpu::Buffer::texelViewFits(context, prims->size()) &&
               gpu::Buffer::texelViewFits(context, shadingNormals->size());
    }
    // What the texel bindings (kBindingBvhTexels, kBindingPrimsTexels, kBindingShadingNormalTexels)
    // hold: the scene's buffers, or where they do not fit (and no shader reads them) the light
    // table (kUniformSceneBytes: 4096 texels, within every device's limit of at least 65536).
    const gpu::Buffer* texels(const gpu::Context& context, const gpu::Buffer* b) const {
        return sceneTexelsFit(context) ? b : lights;
    }
    // The scene's bindings of path_trace, photon_trace and gather, each slot by its name
    // (shared/gpu_types.h kBinding*). The photon passes declare no media (withMedia false): their
    // list is kSceneBindingCount long, one short of the path tracer's kPathTraceBindingCount (it
    // leaves out kBindingPrimMediaUniform), and their media slots hold the light table, a valid
    // buffer no shader reads (the gather binds its photons' texels at kBindingSortedTexels =
    // kBindingMedia itself).
    std::vector<const gpu::Buffer*> sceneBindings(const gpu::Context& context, bool withMedia) const {
        using namespace shader;
        std::vector<const gpu::Buffer*> list(withMedia ? kPathTraceBindingCount : kSceneBindingCount, nullptr);
        list[kBindingPrims] = prims;
        list[kBindingBvh] = nodes;
        list[kBindingMaterials] = materials;
        list[kBindingLights] = lights;
        list[kBindingMedia] = withMedia ? media : lights;
        list[kBindingGridData] = withMedia ? gridData : lights;
        list[kBindingPrimMedia] = withMedia ? primMedia : lights;
        list[kBindingBvhUniform] = nodes;
        list[kBindingPrimsUniform] = prims;
        list[kBindingTextures] = textures;
        list[kBindingEnvironment] = environment;
        list[kBindingMaterialsUniform] = materials;
        list[kBindingLightsUniform] = lights;
        list[kBindingMediaUniform] = withMedia ? media : lights;
        list[kBindingShadingNormals] = shadingNormals;
        list[kBindingBvhTexels] = texels(context, nodes);
        list[kBindingPrimsTexels] = texels(context, prims);
        list[kBindingShadingNormalTexels] = texels(context, shadingNormals);
        if (withMedia) list[kBindingPrimMediaUniform] = primMedia;
        for (const gpu::Buffer* bound : list)
            if (!bound) throw std::logic_error("a scene binding without a buffer");
        return list;
    }
};

// A plan's specialisation constants for this device: without the uniform scene (and so without
// brute-force rays, which read it) where uniform buffers are smaller than kUniformSceneBytes, or
// where the caller does not want it (uniformScene false); without the scene's texels where they
// exceed the device's texel limit; without the uniform tables where uniform buffers are smaller.
inline std::vector<gpu::SpecConstant> deviceSceneSpec(const gpu::Context& context, std::vector<gpu::SpecConstant> spec,
                                                      const RenderBuffers& b, bool uniformScene = true) {
    const bool small = context.properties().limits.maxUniformBufferRange < shader::kUniformSceneBytes;
    for (auto& s : spec) {
        if ((!uniformScene || small) && (s.id == shader::kSpecSceneInUniforms || s.id == shader::kSpecBruteForcePrims))
            s.value = 0;
        if (s.id == shader::kSpecSceneTexels && !b.sceneTexelsFit(context)) s.value = 0;
        if (small && s.id == shader::kSpecTablesInUniforms) s.value = 0;
        if (s.id == shader::kSpecLoopBudget && s.value != 0) s.value = deviceLoopBudget(context);
    }
    return spec;
}

// The scene's uniform bindings (kBindingBvhUniform, kBindingPrimsUniform, and the materials and
// lights: kSpecTablesInUniforms) of path_trace, photon_trace and gather.
constexpr uint32_t kSceneUniformBindings = (1u << shader::kBindingBvhUniform) | (1u << shader::kBindingPrimsUniform) |
                                           (1u << shader::kBindingMaterialsUniform) |
                                           (1u << shader::kBindingLightsUniform);
// Their texel bindings (kBindingBvhTexels, kBindingPrimsTexels), and the shading normals'.
constexpr uint32_t kSceneTexelBindings = (1u << shader::kBindingBvhTexels) | (1u << shader::kBindingPrimsTexels) |
                                         (1u << shader::kBindingShadingNormalTexels);
// path_trace's: those, the media (kSpecTablesInUniforms) and the prims' media (kSpecSceneInUniforms).
constexpr uint32_t kPathTraceUniformBindings = kSceneUniformBindings | (1u << shader::kBindingMediaUniform) |
                                               (1u << shader::kBindingPrimMediaUniform);

// What an integrator counts beyond samples and dispatches (RenderStats::integrator).
struct IntegratorCounters {
    uint64_t photonPaths = 0;    // photon mapping: photon paths traced, all passes
    uint64_t photonPasses = 0;   // photon mapping: photon passes (a block of the unbiased estimator has several)
    uint64_t photonsStored = 0;  // photon mapping: photons stored, all passes
    uint64_t photonMapBytes = 0; // photon mapping: device memory of the photon map now
};

// Loop-budget counters of a render (shared/gpu_types.h kLoopStat*).
struct LoopStats {
    uint64_t capHits = 0;   // lanes whose invocation reached lavapipe's loop cap: wrong results (an error)
    uint64_t carried = 0;   // paths carried to a later dispatch by the loop budget
    uint64_t resumed = 0;   // carried paths taken up again (equals carried after every batch)
    uint64_t retried = 0;   // lane dispatches undone and retried after reaching the cap or a walk's hard limit
    uint64_t overlong = 0;  // samples dropped because one step of their path passed the budget (an error)
    uint64_t drainDispatches = 0;  // dispatches that only finished carried paths
};

class SamplePasses {
public:
    virtual ~SamplePasses() = default;
    virtual uint32_t samplesPerUnit() const = 0;
    // The unit of a render stopped by time (whose sample count depends on the clock anyway):
    // smaller where a unit is long, so that the render overshoots its limit by less.
    virtual uint32_t samplesPerTimedUnit() const { return samplesPerUnit(); }
    virtual uint32_t maxUnitsPerBatch() const = 0;
    // Dispatches one unit records at most.
    virtual uint32_t dispatchesPerUnit() const { return 1; }
    // Records the dispatches of one unit adding up to `samples` (<= samplesPerUnit()) samples per
    // pixel, whose global indices start at sampleBase; returns the samples it completes (fewer when
    // a sample takes several units: a block of photon passes completes with its last pass).
    virtual uint32_t recordUnit(gpu::CommandBatch& batch, uint64_t sampleBase, uint32_t samples) = 0;
    // True between the units of a sample that takes several (a block of photon passes): a render
    // stopped by time finishes it first.
    virtual bool sampleInProgress() const { return false; }
    // After the batch ran: false when it must be recorded and run again. Dispatches it ran itself
    // (paths carried past the batch's last dispatch, finished) append their timings to `timings`.
    virtual bool batchComplete(std::vector<gpu::DispatchTiming>& timings) { (void)timings; return true; }
    // path_trace's loop statistics so far (shared/gpu_types.h kLoopStat*); zero for other passes.
    virtual LoopStats loopStats() const { return {}; }
    // Adds what the last complete batch (`units` units) counted to the render's counters.
    virtual void countBatch(IntegratorCounters& counters, uint32_t units) const {
        (void)counters;
        (void)units;
    }
    // Empty dispatches of every pipeline: lavapipe compiles a pipeline at its first dispatch.
    virtual void recordWarmUp(gpu::CommandBatch& batch) = 0;
    // The pmf pilot's fixed level (a push constant of a pilot plan); integrators without a pilot
    // throw std::logic_error.
    virtual void setPilotLevel(uint32_t level);
    // The pmf pilot's sums so far (samples: the render's per-pixel count); same as setPilotLevel.
    virtual PilotSums pilotSums(uint64_t samples) const;
    // The samples in progress after the last complete batch (film.h PendingSamples; empty for
    // integrators whose samples finish within a batch), and their restoration on resume, before
    // the first unit, where `nextSample` is the film's sample count. restorePending throws
    // std::invalid_argument when the state is not one this render could have left.
    virtual PendingSamples pending() const { return {}; }
    virtual void restorePending(const PendingSamples& p, uint64_t nextSample);
    // Points the camera passes at another camera of the same resolution (a push constant: no new
    // pipelines). Returns false when the integrator cannot, so the caller builds a new Renderer.
    virtual bool setCamera(const Camera&) { return false; }
};

std::unique_ptr<SamplePasses> makePathTracePasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan,
                                                  const RenderBuffers& buffers, uint32_t seed);
std::unique_ptr<SamplePasses> makePhotonPasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan,
                                               const RenderBuffers& buffers, uint32_t seed);

// Unbiased photon mapping, uniform schedule: the level of block `block` (its sample index).
uint32_t photonBlockLevel(const DebiasSettings& debias, uint64_t block, uint32_t seed);

// The passes, feature switches and specialisation constants each integrator adds to a plan
// (render_plan.cpp calls the one of the scene's integrator).
void planPathTrace(const Scene& scene, const SceneFeatures& features, RenderPlan& plan);
void planPhotons(const Scene& scene, const SceneFeatures& features, RenderPlan& plan);

}  // namespace telescope
