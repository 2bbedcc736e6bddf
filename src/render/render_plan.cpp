#include "render/render_plan.h"

#include <algorithm>

#include <fmt/format.h>

#include "shared/gpu_types.h"

namespace telescope {

std::string pmfDescription(const PmfSettings& pmf) {
    if (pmf.type == PmfType::Auto) return "auto pmf (pilot)";
    if (pmf.type == PmfType::Geometric) return fmt::format("geometric pmf, r = {:g}", pmf.r);
    return fmt::format("power-law pmf, alpha = {:g}", pmf.alpha);
}

// The transmittance model type every medium shares (simple models only), else 0xffffffff.
uint32_t sharedTransmittanceModel(const Scene& scene) {
    if (scene.media.empty()) return 0;
    uint32_t type = scene.media[0].transmittance.type;
    for (const Medium& m : scene.media)
        if (m.transmittance.type != type) return 0xffffffffu;
    return type == shader::kTrInterpolated ? 0xffffffffu : type;
}

RenderPlan makeRenderPlan(const Scene& scene, const SceneFeatures& f) {
    using namespace shader;
    RenderPlan plan;
    const IntegratorSettings& in = scene.integrator;

    // ---- Passes ----
    plan.passes.push_back({"path_trace", "path_trace",
                           "integrator 'path_tracer': camera paths with next-event estimation and MIS, "
                           "accumulated per pixel"});
    plan.skipped.push_back({"photon_trace, hash_grid_build, gather", "the integrator does not use photons"});
    if (f.media) {
        const auto& t = in.transmittance;
        std::string how = transmittanceEstimatorName(t.type);
        if (t.type == TransmittanceEstimatorType::RayMarch) how += fmt::format(" (2^{} points, biased)", t.level);
        if (t.type == TransmittanceEstimatorType::DebiasedRayMarch)
            how += fmt::format(" (base level {}, {})", t.level, pmfDescription(t.pmf));
        plan.passes[0].why += fmt::format("; volumetric path tracing through {} medi{} (single and multiple scattering, "
                                          "next-event estimation), every transmittance by {}",
                                          f.mediumCount, f.mediumCount == 1 ? "um" : "a", how);
    } else {
        plan.skipped.push_back({"volume tracking", "the scene has no participating media: volume code folded out of path_trace"});
    }

    // ---- Level schedule: only a debiased render (not the pilot) has levels to schedule ----
    if (in.debias.estimator != DebiasEstimator::None && in.pilotLevel == kNoPilotLevel)
        plan.levelSchedule = in.debias.schedule;
    if (plan.levelSchedule == LevelSchedule::Queued) {
        plan.passes.insert(plan.passes.begin(),
                           {{"level_count", "level_count", "level_schedule 'queued': histogram of the drawn levels"},
                            {"level_scan", "level_scan", "prefix sum of the level histogram"},
                            {"level_scatter", "level_scatter", "(pixel, sample) items sorted by level into a queue"}});
        plan.passes.back().why += "; lanes take items from the level queue";
        plan.passes.push_back({"path_resolve", "path_resolve", "accumulates the queued results per pixel in sample order"});
    }

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
            "debiased path depth ({} estimator), base k = {}, {}, {}",
            in.debias.estimator == DebiasEstimator::SingleTerm ? "single-term" : "Russian-roulette sum",
            in.maxBounces, pmfDescription(in.debias.pmf),
            plan.levelSchedule == LevelSchedule::Uniform
                ? "one level per sample index shared by all pixels (level_schedule 'uniform')"
            : plan.levelSchedule == LevelSchedule::Queued
                ? "level drawn per pixel sample, work sorted by level (level_schedule 'queued')"
                : "level drawn per pixel sample in the shader");
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
    feature("media", f.media, "media or forward boundaries present", "no participating media");
    feature("grid media", f.grids, "voxel grid media present", "no grid media");

    const uint32_t filter = scene.camera.filter == "dirac" ? kFilterDirac
                            : scene.camera.filter == "box" ? kFilterBox
                                                           : kFilterTent;
    const uint32_t maxTraceDepth = 4096;
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
        {kSpecFilter, filter},
        {kSpecEnvironmentLight, f.environmentLight},
        {kSpecMaxTraceDepth, std::max(maxTraceDepth, in.maxBounces + 1)},
        {kSpecRayEpsilon, gpu::specFloat(1e-5f * f.sceneExtent)},
        {kSpecPilot, in.pilotLevel != kNoPilotLevel},
        {kSpecHasMedia, f.media},
        {kSpecTrEstimator, uint32_t(in.transmittance.type)},
        {kSpecTrLevel, in.transmittance.level},
        {kSpecTrPmfType, uint32_t(in.transmittance.pmf.type)},
        {kSpecTrPmfR, gpu::specFloat(in.transmittance.pmf.r)},
        {kSpecTrPmfAlpha, gpu::specFloat(in.transmittance.pmf.alpha)},
        {kSpecCameraMedium, uint32_t(scene.camera.medium + 1)},
        {kSpecHasGrids, f.grids},
        {kSpecTrModel, sharedTransmittanceModel(scene)},
        {kSpecLevelSchedule, uint32_t(plan.levelSchedule)},
    };
    return plan;
}

std::string describePlan(const Scene& scene, const RenderPlan& plan) {
    std::string s = fmt::format("scene: {}\nintegrator: {}\n", scene.path, plan.estimator);
    s += "passes, per batch of samples:\n";
    for (const auto& p : plan.passes) s += fmt::format("  {:<16} {}\n", p.name, p.why);
    s += "not scheduled:\n";
    for (const auto& p : plan.skipped) s += fmt::format("  {:<16} {}\n", p.name, p.why);
    s += "compiled into the path_trace pipeline:\n";
    for (const auto& f : plan.features) s += fmt::format("  {:<16} {:<4} {}\n", f.name, f.on ? "on" : "off", f.why);
    if (!scene.ignoredKeys.empty()) {
        s += "ignored scene keys:\n";
        for (const auto& k : scene.ignoredKeys) s += "  " + k + "\n";
    }
    return s;
}

}  // namespace telescope
