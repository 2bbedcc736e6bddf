// Schedules the passes of a plan on the device and accumulates samples into a Film.
//
// The integrator contributes its passes (SamplePasses, render/sample_passes.h); the Renderer
// batches their units into submits, times every dispatch by name and stops at a sample count or a
// time limit. It knows no integrator: what one counts beyond samples is IntegratorCounters, and
// ways of running it that are not scene settings are PlanOptions (render/render_plan.h).
//
// A Renderer owns the scene buffers, the accumulation buffer, the pipelines and the camera and
// integrator settings: the Scene it was made from need not outlive it. render() may be
// called repeatedly: samples continue from where the last call stopped (their random numbers
// depend only on pixel, global sample index and seed), so a render can be extended, and renders
// with different seeds can be merged.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "render/film.h"
#include "render/gpu_scene.h"
#include "render/render_plan.h"
#include "render/resolved_scene.h"
#include "render/sample_passes.h"
#include "scene/scene.h"

namespace telescope {

struct RenderProgress {
    uint64_t samplesDone = 0;     // per pixel, this call
    uint64_t samplesTarget = 0;   // per pixel, 0 when time-limited
    double seconds = 0.0;
    double timeLimit = 0.0;
    double pathsPerSecond = 0.0;
};

struct RenderRequest {
    uint64_t spp = 0;          // samples per pixel to add (used when timeLimit is 0)
    double timeLimit = 0.0;    // seconds; renders whole dispatches until it is reached
    // At the time limit, a sample that takes several units (SamplePasses::sampleInProgress) is
    // finished (true: the render overruns by up to that sample, and the sample count is a stopping
    // time, so their sum is unbiased by Wald's identity) or left in progress (false: the render
    // stops at the deadline; the sample stays in film().pending() for a checkpoint; an image of
    // the completed samples alone leans towards short ones: "Time limits" in the integrator's doc).
    bool finishSampleAtTimeLimit = true;
    std::function<void(const RenderProgress&)> progress;  // called after every batch
    // Asked before every batch: true ends the render there (a signal). A sample in progress
    // stays in film().pending(), so a checkpoint of it resumes the sample where it stopped; every
    // completed sample is in the film.
    std::function<bool()> stop;
};

// The progress report of a render that has added `done` samples per pixel in `seconds`.
inline RenderProgress progressOf(const RenderRequest& request, uint64_t done, double seconds, double pixels) {
    RenderProgress p;
    p.samplesDone = done;
    p.samplesTarget = request.timeLimit > 0.0 ? 0 : request.spp;
    p.seconds = seconds;
    p.timeLimit = request.timeLimit;
    p.pathsPerSecond = seconds > 0.0 ? double(done) * pixels / seconds : 0.0;
    return p;
}

struct PassStats {
    uint64_t dispatches = 0;
    double gpuMs = 0.0;
};

struct RenderStats {
    double wallSeconds = 0.0;
    double setupSeconds = 0.0;  // scene upload and pipeline creation
    // The setup's parts: BVH and GPU scene build, buffer upload, pipeline creation (SPIR-V to the
    // driver's IR), and the warm-up dispatches (lavapipe compiles a pipeline at its first dispatch).
    double sceneSeconds = 0.0, uploadSeconds = 0.0, pipelineSeconds = 0.0, warmUpSeconds = 0.0;
    // Seconds from the start of the process (shared libraries loaded, device created, scene read,
    // setup) until the first batch of samples was done; 0 before it, negative where unknown.
    double firstSampleSeconds = 0.0;
    uint64_t samplesPerPixel = 0;
    uint64_t submits = 0;
    IntegratorCounters integrator;  // what the integrator's passes count (render/sample_passes.h)
    // path_trace's loop budget (shared/gpu_types.h): capHits and overlong nonzero mean wrong pixels.
    LoopStats loops;
    std::map<std::string, PassStats> passes;
};

class Renderer {
public:
    // options: how the plan runs the integrator beyond the scene's settings (render_plan.h); the
    // default for a render. The scene's pmfs are explicit (render/resolved_scene.h).
    Renderer(gpu::Context& context, const ResolvedScene& scene, uint32_t seed, const PlanOptions& options = {});
    ~Renderer();

    const RenderPlan& plan() const { return plan_; }
    void render(const RenderRequest& request);
    // Continues a render from a checkpointed film of this scene and seed: later samples continue
    // the same random sequence, so stopping and resuming equals one long render. Only before the
    // first render() call.
    void resume(const Film& film);
    Film film() const;  // downloads the accumulation
    // A Renderer whose plan fixes the level (PlanOptions) only: starts again from an empty film at
    // another fixed level, with the same pipelines and the same random numbers (sample indices
    // restart at 0). Stats restart too, except the setup time.
    void restartAtFixedLevel(uint32_t level);
    // The integrator's passes, for what only some integrators or plans have (their own sums).
    const SamplePasses& passes() const { return *passes_; }
    uint64_t nextSampleIndex() const { return sampleIndex_; }  // the global index of the next sample
    // Starts again from an empty film with another camera of the same resolution and field of
    // view (the viewer's orbit): sample indices restart at 0 and stats restart, except the setup
    // time. No new pipelines. Returns false (and changes nothing) when the integrator cannot
    // change its camera in place.
    bool restartWithCamera(const Camera& camera);
    // Derivative renders (render/derivative.h): replaces the scene buffers' content by that of a
    // version of the same scene with one parameter changed (same plan and buffer sizes: the caller
    // checks; std::invalid_argument otherwise) and moves the camera to the version's.
    void setSceneVersion(const GpuScene& version, const Camera& camera);
    // Derivative renders: renders the one sample of global index `index` alone, after the
    // accumulation is cleared, and returns its per-pixel estimate (rgb; w 1 where the sample was
    // non-finite and dropped). Stats accumulate; film() afterwards holds that sample only.
    std::vector<glm::vec4> renderSample(uint64_t index);
    const GpuScene& gpuScene() const { return gpuScene_; }
    const RenderStats& stats() const { return stats_; }
    // Samples per pixel one dispatch adds at most; renders split at multiples of it add their
    // samples in the same dispatches as one render of the total, so their sums are bit-identical.
    uint32_t samplesPerUnit() const;
    uint32_t seed() const { return seed_; }
    // The accumulation on the device (layout: shared/gpu_types.h), for passes that display it
    // while the render runs; samples in it: stats().samplesPerPixel.
    const gpu::Buffer& accumulation() const { return accum_; }

private:
    gpu::Context& context_;
    // What a render reads of the scene after construction, owned (the scene buffers hold the
    // rest): a Renderer may outlive the Scene it was made from.
    Camera camera_;
    IntegratorSettings integrator_;
    uint32_t seed_;
    GpuScene gpuScene_;
    RenderPlan plan_;
    gpu::Buffer prims_, nodes_, materials_, lights_, accum_;
    gpu::Buffer media_, gridData_, primMedia_;  // participating media (path tracer only)
    gpu::Buffer textures_;                       // textures and uv records (path tracer only)
    gpu::Buffer shadingNormals_;                 // smooth triangles' vertex normals
    gpu::Buffer environment_;                   // environment image (path tracer only)
    std::unique_ptr<SamplePasses> passes_;  // the integrator's passes
    std::unique_ptr<gpu::CommandBatch> batch_;
    uint64_t sampleIndex_ = 0;  // next global sample index
    RenderStats stats_;
};

}  // namespace telescope
