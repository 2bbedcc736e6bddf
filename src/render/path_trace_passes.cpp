// The path tracer's passes: one path_trace dispatch per unit, several samples per pixel each.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>

#include "render/sample_passes.h"
#include "shared/gpu_types.h"

namespace telescope {

// ---- Plan ----
void planPathTrace(const Scene& scene, const SceneFeatures& f, RenderPlan& plan) {
    using namespace shader;
    const IntegratorSettings& in = scene.integrator;

    plan.passes.push_back({"path_trace", "path_trace",
                           "integrator 'path_tracer': camera paths with next-event estimation and MIS, "
                           "accumulated per pixel"});
    plan.skipped.push_back({"photon_trace, hash_grid_build, gather", "the integrator does not use photons"});

    // ---- Estimator ----
    if (in.debias.estimator != DebiasEstimator::None && in.debias.pmf.type == PmfType::Auto)
        plan.passes.insert(plan.passes.begin(),
                           {"pmf_pilot", "path_trace",
                            fmt::format("pmf 'auto': before the render, {} spp at each of {} fixed levels measure the "
                                        "second moment and cost of the correction",
                                        in.debias.pmf.pilotSpp, in.debias.pmf.pilotLevels)});
    if (in.pilotLevel != kNoPilotLevel) {
        plan.estimator = fmt::format("pmf pilot: unweighted correction D_j at level j = k + {}, k = {}", in.pilotLevel,
                                     in.maxBounces);
    } else if (in.debias.estimator == DebiasEstimator::None) {
        plan.estimator = fmt::format("biased path tracing I(k), k = max_bounces = {}", in.maxBounces);
    } else {
        plan.estimator = fmt::format(
            "debiased path depth ({} estimator), base k = {}, {}, level drawn per pixel sample in the shader",
            in.debias.estimator == DebiasEstimator::SingleTerm ? "single-term" : "Russian-roulette sum",
            in.maxBounces, pmfDescription(in.debias.pmf));
    }

    // ---- Feature switches folded into the pipeline ----
    auto feature = [&](const char* name, bool on, const char* yes, const char* no) {
        plan.features.push_back({name, on, on ? yes : no});
    };
    feature("spheres", f.spheres, "sphere primitives present", "no sphere primitives");
    feature("disks", f.disks, "disk primitives present", "no disk primitives");
    feature("specular", f.specular, "mirror or dielectric materials present", "no mirror or dielectric materials");
    feature("light sampling", in.enableLightSampling && f.lightCount > 0, "next-event estimation",
            in.enableLightSampling ? "no lights" : "enable_light_sampling is false");
    feature("environment", f.environment, "infinite_sphere emitter", "no environment emitter");
    feature("debias", in.debias.estimator != DebiasEstimator::None, "debias block in the integrator",
            "no debias block: plain I(k)");

    const uint32_t maxTraceDepth = 4096;
    plan.featuresOf = "path_trace";
    plan.pathTraceSpec = {
        {kSpecMaxBounces, in.maxBounces},
        {kSpecMinBounces, in.minBounces},
        {kSpecDebiasMode, uint32_t(in.debias.estimator)},
        {kSpecPmfType, uint32_t(in.debias.pmf.type)},
        {kSpecPmfR, gpu::specFloat(in.debias.pmf.r)},
        {kSpecPmfAlpha, gpu::specFloat(in.debias.pmf.alpha)},
        {kSpecHasSpheres, f.spheres},
        {kSpecHasDisks, f.disks},
        {kSpecHasSpecular, f.specular},
        {kSpecLightCount, f.lightCount},
        {kSpecLightSampling, in.enableLightSampling && f.lightCount > 0},
        {kSpecTwoSided, in.enableTwoSidedShading},
        {kSpecFilter, filterConstant(scene.camera)},
        {kSpecEnvironmentLight, f.environmentLight},
        {kSpecMaxTraceDepth, std::max(maxTraceDepth, in.maxBounces + 1)},
        {kSpecRayEpsilon, gpu::specFloat(1e-5f * f.sceneExtent)},
        {kSpecPilot, in.pilotLevel != kNoPilotLevel},
    };
}

// ---- Passes ----
namespace {

class PathTracePasses : public SamplePasses {
public:
    PathTracePasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan, const RenderBuffers& b,
                    uint32_t seed)
        : pipeline_(context, "path_trace", shader::kPathTraceBindingCount, uint32_t(sizeof(shader::PathTracePush)),
                    plan.pathTraceSpec) {
        pipeline_.bindBuffers({b.prims, b.nodes, b.materials, b.lights});
        const Camera& cam = scene.camera;
        push_.cameraPosition = cam.position;
        push_.cameraRight = cam.right;
        push_.cameraUp = cam.up;
        push_.cameraForward = cam.forward;
        push_.planeDistance = 1.0f / std::tan(0.5f * glm::radians(cam.fovDegrees));
        push_.width = cam.width;
        push_.height = cam.height;
        push_.seed = seed;
        push_.pilotLevel = scene.integrator.pilotLevel;
        push_.accumAddressLo = uint32_t(b.accum->address());
        push_.accumAddressHi = uint32_t(b.accum->address() >> 32);
        groupsX_ = (cam.width + shader::kPathTraceGroupSize - 1) / shader::kPathTraceGroupSize;
        groupsY_ = (cam.height + shader::kPathTraceGroupSize - 1) / shader::kPathTraceGroupSize;
        // About a million paths per dispatch, at most 16 samples per pixel in one thread.
        const uint64_t pixels = uint64_t(cam.width) * cam.height;
        samplesPerUnit_ = uint32_t(std::clamp<uint64_t>((1u << 20) / std::max<uint64_t>(pixels, 1), 1, 16));
    }

    uint32_t samplesPerUnit() const override { return samplesPerUnit_; }
    uint32_t maxUnitsPerBatch() const override { return 64; }

    void recordUnit(gpu::CommandBatch& batch, uint64_t sampleBase, uint32_t samples) override {
        push_.sampleBase = uint32_t(sampleBase);
        push_.sampleCount = samples;
        batch.dispatch(pipeline_, &push_, sizeof(push_), groupsX_, groupsY_, 1, "path_trace");
    }

    void recordWarmUp(gpu::CommandBatch& batch) override {
        shader::PathTracePush warm = push_;
        warm.sampleCount = 0;
        batch.dispatch(pipeline_, &warm, sizeof(warm), 1, 1, 1, "warm-up");
    }

private:
    gpu::ComputePipeline pipeline_;
    shader::PathTracePush push_{};
    uint32_t groupsX_ = 1, groupsY_ = 1, samplesPerUnit_ = 1;
};

}  // namespace

std::unique_ptr<SamplePasses> makePathTracePasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan,
                                                  const RenderBuffers& buffers, uint32_t seed) {
    return std::make_unique<PathTracePasses>(context, scene, plan, buffers, seed);
}

}  // namespace telescope
