// The path tracer's passes: one path_trace dispatch per unit, several samples per pixel each.
#include <algorithm>
#include <array>
#include <cstdlib>
#include <string>
#include <cmath>
#include <tuple>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>

#include "render/sample_passes.h"
#include "shared/gpu_types.h"

namespace telescope {

// ---- Plan ----
namespace {
// Bit t set where some medium uses transmittance model t (an interpolated model: its own bit and
// its two models'); the shaders fold out the models whose bit is clear (medium.glsl).
uint32_t transmittanceModelMask(const Scene& scene) {
    uint32_t mask = scene.media.empty() ? 1u << shader::kTrExponential : 0u;
    for (const Medium& m : scene.media) {
        mask |= 1u << m.transmittance.type;
        if (m.transmittance.type == shader::kTrInterpolated) mask |= 1u << m.transmittance.typeA | 1u << m.transmittance.typeB;
    }
    return mask;
}

// Every medium's sigma_t has three equal channels (as the shader computes it: sigma_a + sigma_s).
bool greyMedia(const Scene& scene) {
    for (const Medium& m : scene.media) {
        const glm::vec3 t = m.sigmaA + m.sigmaS;
        if (t.x != t.y || t.y != t.z) return false;
    }
    return true;
}
}  // namespace

void planPathTrace(const Scene& scene, const SceneFeatures& f, RenderPlan& plan) {
    using namespace shader;
    const IntegratorSettings& in = scene.integrator;

    plan.passes.push_back(plannedPass(PassKind::PathTrace,
                                      "integrator 'path_tracer': camera paths with next-event estimation and MIS, "
                                      "accumulated per pixel"));
    plan.skipped.push_back({fmt::format("{}, {}, {}", passName(PassKind::PhotonTrace), passName(PassKind::HashGridBuild),
                                        passName(PassKind::Gather)),
                            "the integrator does not use photons"});
    if (f.media) {
        const auto& t = in.transmittance;
        std::string how = transmittanceEstimatorName(t.type);
        if (t.type == TransmittanceEstimatorType::RayMarch) how += fmt::format(" (2^{} points, biased)", t.level);
        if (t.type == TransmittanceEstimatorType::DebiasedRayMarch)
            how += fmt::format(" (base level {}, {})", t.level, pmfDescription(t.pmf));
        if (t.type == TransmittanceEstimatorType::Taylor)
            how += fmt::format(" (pivot of at least 2^{} points, factors of {}, {} forced term{}, then the recipe's "
                               "roulette)", t.level, t.points ? fmt::format("{} points", t.points) : "points from the density bounds",
                               t.terms, t.terms == 1 ? "" : "s");
        plan.passes[0].why += fmt::format("; volumetric path tracing through {} medi{} (single and multiple scattering, "
                                          "next-event estimation), every transmittance by {}",
                                          f.mediumCount, f.mediumCount == 1 ? "um" : "a", how);
    } else {
        plan.skipped.push_back({"volume tracking", "the scene has no participating media: volume code folded out of path_trace"});
    }

    // ---- Level schedule: only a debiased render (not the pilot) has levels to schedule ----
    if (in.debias.estimator != DebiasEstimator::None && plan.pilotLevel == kNoPilotLevel)
        plan.levelSchedule = in.debias.schedule;
    if (plan.levelSchedule == LevelSchedule::Queued) {
        plan.passes.insert(plan.passes.begin(),
                           {plannedPass(PassKind::LevelCount, "level_schedule 'queued': histogram of the drawn levels"),
                            plannedPass(PassKind::LevelScan, "prefix sum of the level histogram"),
                            plannedPass(PassKind::LevelScatter, "(pixel, sample) items sorted by level into a queue")});
        plan.passes.back().why += "; lanes take items from the level queue";
        plan.passes.push_back(
            plannedPass(PassKind::PathResolve, "accumulates the queued results per pixel in sample order"));
    }

    // ---- Estimator ----
    if (debiasPmfIsAuto(in))
        plan.passes.insert(plan.passes.begin(),
                           {PassKind::PathTrace, "pmf_pilot", "path_trace",
                            fmt::format("pmf 'auto': before the render, {} spp at each of {} fixed levels measure the "
                                        "second moment and cost of the correction",
                                        in.debias.pmf.pilotSpp, in.debias.pmf.pilotLevels),
                            true});
    if (f.media && transmittancePmfIsAuto(in))
        plan.passes.insert(plan.passes.begin(),
                           {PassKind::PathTrace, "transmittance_pilot", "path_trace",
                            fmt::format("transmittance pmf 'auto': before the render, {} spp at each of {} fixed marching "
                                        "levels (correction weighted by 1 and by 2) measure the second moment and cost "
                                        "of the correction",
                                        in.transmittance.pmf.pilotSpp, in.transmittance.pmf.pilotLevels),
                            true});
    if (plan.pilotLevel != kNoPilotLevel && plan.pilotKind == PilotKind::Transmittance) {
        plan.estimator = fmt::format("transmittance pmf pilot: debiased ray marching at the fixed level j = k + {}, "
                                     "k = {}, the correction weighted by 1 or 2", plan.pilotLevel & ~shader::kTrPilotHalfWeight,
                                     in.transmittance.level);
    } else if (plan.pilotLevel != kNoPilotLevel) {
        plan.estimator = fmt::format("pmf pilot: unweighted correction D_j at level j = k + {}, k = {}", plan.pilotLevel,
                                     pathDepthK(in));
    } else if (in.debias.estimator == DebiasEstimator::None) {
        plan.estimator = fmt::format("biased path tracing I(k), k = max_bounces - 1 = {}", pathDepthK(in));
    } else {
        plan.estimator = fmt::format(
            "debiased path depth ({} estimator), base k = {}, {}, {}",
            in.debias.estimator == DebiasEstimator::SingleTerm ? "single-term" : "Russian-roulette sum",
            pathDepthK(in),
            in.debias.testPmfWeight == 1.0f ? pmfDescription(in.debias.pmf)
                                            : fmt::format("{} with every 1 / p(j) scaled by {:g} (TEST ONLY, biased)",
                                                          pmfDescription(in.debias.pmf), in.debias.testPmfWeight),
            plan.levelSchedule == LevelSchedule::Uniform
                ? "one level per sample index shared by all pixels (level_schedule 'uniform')"
            : plan.levelSchedule == LevelSchedule::Queued
                ? "level drawn per pixel sample, work sorted by level (level_schedule 'queued')"
                : "level drawn per pixel sample in the shader");
    }

    plan.featuresOf = "path_trace";
    // Scenes with glossy materials get the path tracer that has their code (path_trace_glossy.comp);
    // the others keep the smaller pipeline. (The pilots' entries run the render's path_trace too.)
    if (f.bsdfFamilies != 0u)
        for (PlannedPass& p : plan.passes)
            if (p.kind == PassKind::PathTrace) p.shader = "path_trace_glossy";
    // Brute-force rays in the path tracer for the smallest scenes alone (kMaxBruteForcePathPrims).
    const uint32_t bruteForce = f.bruteForcePrims <= kMaxBruteForcePathPrims ? f.bruteForcePrims : 0u;
    plan.pathTraceSpec = {
        {kSpecMaxBounces, pathDepthK(in)},
        {kSpecMinBounces, in.minBounces},
        {kSpecRoulette, in.russianRoulette},
        {kSpecDebiasMode, uint32_t(in.debias.estimator)},
        {kSpecPmfType, uint32_t(in.debias.pmf.type)},
        {kSpecPmfR, gpu::specFloat(in.debias.pmf.r)},
        {kSpecPmfAlpha, gpu::specFloat(in.debias.pmf.alpha)},
        {kSpecHasSpheres, f.spheres},
        {kSpecHasDisks, f.disks},
        {kSpecHasSpecular, f.specular},
        {kSpecLightCount, f.lightCount},
        {kSpecPointLights, f.pointLights},
        {kSpecLightSampling, in.enableLightSampling && f.lightCount > 0},
        {kSpecTwoSided, in.enableTwoSidedShading},
        {kSpecFilter, filterConstant(scene.camera)},
        {kSpecEnvironmentLight, f.environmentLight},
        {kSpecCapLight, f.capLight},
        {kSpecMaxTraceDepth, std::max(shader::kTraceDepthCap, pathDepthK(in) + 1)},
        {kSpecRayEpsilon, gpu::specFloat(1e-5f * f.sceneExtent)},
        {kSpecPilot, plan.pilotLevel != kNoPilotLevel && plan.pilotKind == PilotKind::PathDepth},
        {kSpecTrPilot, plan.pilotLevel != kNoPilotLevel && plan.pilotKind == PilotKind::Transmittance},
        {kSpecLevelSchedule, uint32_t(plan.levelSchedule)},
        {kSpecTestPmfWeight, gpu::specFloat(in.debias.testPmfWeight)},
        // The uniform scene only for brute-force rays (their loads are scalar); BVH walks read nodes
        // at each lane's own index, which lavapipe gathers faster from texels (vector loads) than
        // from a uniform buffer (a load per component): non-exponential 256x256, 64 spp, taking
        // turns, 1.51 / 1.73, 1.65 / 1.88, 1.74 / 2.02 M paths/s (uniform / texels), 2026-12-06.
        {kSpecSceneInUniforms, f.fitsUniforms && bruteForce > 0},
        {kSpecSceneTexels, 1u},  // (where the uniform scene is not read) off beyond the device's texel limit
        {kSpecBruteForcePrims, bruteForce},
        {kSpecBruteForceCurved, bruteForce > 0 ? f.bruteForceCurved : 0u},
        {kSpecBvhStackNeed, f.bvhStackNeed <= kMaxRegisterBvhStack ? std::max(f.bvhStackNeed, 1u) : 0u},
        {kSpecTieRanks, f.interfaces},
        {kSpecTablesInUniforms, f.tablesFitUniforms},
        {kSpecBsdfFamilies, f.bsdfFamilies},
        {kSpecHasTextures, f.textures},
        {kSpecSmoothNormals, f.smoothNormals},
        {kSpecEnvironmentMap, f.environmentMap},
        {kSpecHasMedia, f.media},
        {kSpecTrEstimator, uint32_t(in.transmittance.type)},
        {kSpecTrLevel, in.transmittance.level},
        {kSpecTrPmfType, uint32_t(in.transmittance.pmf.type)},
        {kSpecTrPmfR, gpu::specFloat(in.transmittance.pmf.r)},
        {kSpecTrPmfAlpha, gpu::specFloat(in.transmittance.pmf.alpha)},
        {kSpecTrTaylorTerms, in.transmittance.terms},
        {kSpecTrTaylorPoints, in.transmittance.points},
        {kSpecCameraMedium, uint32_t(scene.camera.medium + 1)},
        {kSpecHasGrids, f.grids},
        {kSpecHasInhomogeneousMedia, f.inhomogeneous},
        {kSpecTrModels, transmittanceModelMask(scene)},
        {kSpecGreyMedia, greyMedia(scene)},
        // Lavapipe's loop cap: lanes carry their paths on (deviceSceneSpec sets it per device);
        // the queued schedule's lanes take items from a queue rebuilt every unit: no budget.
        {kSpecLoopBudget, plan.levelSchedule == LevelSchedule::Queued ? 0u : kDefaultLoopBudget},
    };

    // ---- What the pipeline is compiled with, read off its specialisation ----
    const std::vector<gpu::SpecConstant>& spec = plan.pathTraceSpec;
    plan.features = sceneFeatureSwitches(spec, f);
    // Glossy material families (shared/bsdf.h): each one the scene lacks is folded out.
    const uint32_t families = specValue(spec, kSpecBsdfFamilies);
    for (const auto& [bit, name, detail] :
         {std::tuple{shader::kFamilyRoughConductor, "rough_conductor", ""}, std::tuple{shader::kFamilyPlastic, "plastic", ""},
          std::tuple{shader::kFamilyRoughPlastic, "rough_plastic", ""}, std::tuple{shader::kFamilyOrenNayar, "oren_nayar", ""},
          std::tuple{shader::kFamilyRoughDielectric, "rough_dielectric", ""},
          std::tuple{shader::kFamilyThinSheet, "thinsheet", " (shadow rays pass them)"},
          std::tuple{shader::kFamilyMixed, "mixed", ""},
          std::tuple{shader::kFamilyTransparency, "transparency", " (shadow rays pass them)"}}) {
        const bool on = (families & bit) != 0u;
        const std::string why = on ? fmt::format("{} materials present{}", name, detail) : fmt::format("no {} materials", name);
        plan.features.push_back({name, on, fmt::format("{} (kBsdfFamilies bit {:#x})", why, bit)});
    }
    plan.features.insert(
        plan.features.end(),
        {specSwitch(spec, "light sampling", kSpecLightSampling, in.enableLightSampling ? "no lights" : "enable_light_sampling is false"),
          specSwitch(spec, "environment", kSpecEnvironmentLight, "no environment emitter", 0xffffffffu),
          specSwitch(spec, "environment map", kSpecEnvironmentMap, "no environment image", 0,
                     "infinite_sphere with an image, importance-sampled"),
          specSwitch(spec, "sphere cap", kSpecCapLight, "no infinite_sphere_cap emitter", 0xffffffffu),
          specSwitch(spec, "russian roulette", kSpecRoulette, "off: a derivative render's evaluations must take the same survival decisions",
                     0, "paths end with probability 1 - max(throughput) from the second bounce"),
          specSwitch(spec, "debias", kSpecDebiasMode, "no debias block: plain I(k)"),
          specSwitch(spec, "media", kSpecHasMedia, "no participating media"),
          specSwitch(spec, "grid media", kSpecHasGrids, "no grid media"),
          specSwitch(spec, "inhomogeneous media", kSpecHasInhomogeneousMedia,
                     f.media ? "every medium homogeneous: comb estimators are exact, their code folded out" : "no participating media"),
          specSwitch(spec, "loop budget", kSpecLoopBudget,
                     "queued schedule: lanes are not carried across dispatches; a path ended by lavapipe's loop cap "
                     "is counted and reported",
                     0,
                     "loop iterations per lane and dispatch: on lavapipe a lane stops there and carries its path to "
                     "the next dispatch (its 65535-iteration loop cap ends loops silently); other devices run "
                     "without a budget")});
}

uint32_t deviceLoopBudget(const gpu::Context& context) {
    if (const char* v = std::getenv("TELESCOPE_LOOP_BUDGET"); v && *v) return uint32_t(std::strtoul(v, nullptr, 10));
    const bool llvmpipe = context.cpuDevice() && std::string(context.properties().deviceName).find("llvmpipe") !=
                                                     std::string::npos;
    return llvmpipe ? shader::kDefaultLoopBudget : 0u;
}

// ---- Passes ----
namespace {

class PathTracePasses : public SamplePasses {
public:
    PathTracePasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan, const RenderBuffers& b,
                    uint32_t seed)
        : PathTracePasses(context, scene, plan, b, seed, deviceSceneSpec(context, plan.pathTraceSpec, b)) {}

    // `spec`: the plan's specialisation for this device, the pipeline's and the unit's.
    PathTracePasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan, const RenderBuffers& b,
                    uint32_t seed, const std::vector<gpu::SpecConstant>& spec)
        : pipeline_(context, plannedEntry(plan, PassKind::PathTrace).shader, shader::kPathTraceBindingCount, uint32_t(sizeof(shader::PathTracePush)),
                    spec, kPathTraceUniformBindings, kSceneTexelBindings) {
        pipeline_.bindBuffers(b.sceneBindings(context, true));
        uint32_t bruteForcePrims = 0;  // > 0: rays test every primitive (no BVH walk)
        for (const auto& s : spec) {
            if (s.id == shader::kSpecLoopBudget && s.value != 0) loopBudget_ = s.value;
            if (s.id == shader::kSpecBruteForcePrims) bruteForcePrims = s.value;
        }
        const Camera& cam = scene.camera;
        setPushCamera(push_, cam);
        push_.width = cam.width;
        push_.height = cam.height;
        push_.seed = seed;
        push_.pilotLevel = plan.pilotLevel;
        push_.accumAddressLo = uint32_t(b.accum->address());
        push_.accumAddressHi = uint32_t(b.accum->address() >> 32);
        pixels_ = size_t(cam.width) * cam.height;
        if (plan.pilotLevel != kNoPilotLevel && plan.pilotKind == PilotKind::PathDepth) {
            pilot_ = gpu::Buffer(context, pixels_ * shader::kPilotChannelCount * 2 * sizeof(glm::vec4), "pmf pilot sums");
            pilot_.fill(0);
            push_.pilotAddressLo = uint32_t(pilot_.address());
            push_.pilotAddressHi = uint32_t(pilot_.address() >> 32);
        }
        // Loop statistics, and continuation records where lanes carry paths (a budget).
        loopStats_ = gpu::Buffer(context, shader::kLoopStatCount * sizeof(uint32_t), "loop statistics");
        loopStats_.fill(0);
        push_.statsAddressLo = uint32_t(loopStats_.address());
        push_.statsAddressHi = uint32_t(loopStats_.address() >> 32);
        if (loopBudget_ != 0) {
            // The lanes' flags first, zeroed; the records after them, not (shared/gpu_types.h).
            const VkDeviceSize flagBytes = shader::continuationFlagBytes(uint32_t(pixels_));
            records_ = gpu::Buffer(context, flagBytes + pixels_ * shader::kContinuationVec4s * sizeof(glm::vec4),
                                   "continuation records");
            records_.fill(0, 0, flagBytes);
            push_.stateAddressLo = uint32_t(records_.address());
            push_.stateAddressHi = uint32_t(records_.address() >> 32);
            drain_ = std::make_unique<gpu::CommandBatch>(context, 1);
        }
        groupsX_ = (cam.width + shader::kPathTraceGroupSize - 1) / shader::kPathTraceGroupSize;
        groupsY_ = (cam.height + shader::kPathTraceGroupSize - 1) / shader::kPathTraceGroupSize;
        // Samples per pixel in one dispatch (one thread per pixel, looping over its samples). On a
        // CPU device about four million paths, and as many samples per thread as the loop budget
        // leaves room for (at most 64): lavapipe runs 8 lanes in step until the one with the most
        // steps over all its samples is done, and the more samples a lane sums, the less the
        // lanes' totals differ (and the dispatch's end comes fewer times). The room: paths of 8
        // steps, each counting its own 8 ticks and two rays (brute force: a tick per primitive;
        // a BVH walk: kRayLoopTicks), so 64 samples with brute-force rays, 28 with BVH walks.
        // Measured against 16, interleaved (docs/BENCHMARKS.tungsten-notes.md): the volumetric
        // caustic 1.10x paths/s at 64; the Cornell box 1.12x at 28 (1.14x at 64, a few paths
        // carried); Tungsten's water surface 1.03-1.12x at 32 but 0.79-0.96x at 64, where a
        // third of its paths passed the budget and were carried
        // (Stability.DispatchUnitIsTheLoopBudgetsRoom). Elsewhere, and for renders stopped by
        // time (an unfinished dispatch overshoots the limit), about a million paths, at most 16.
        const uint64_t pixels = uint64_t(cam.width) * cam.height;
        auto perDispatch = [&](uint64_t paths, uint64_t most) {
            return uint32_t(std::clamp<uint64_t>(paths / std::max<uint64_t>(pixels, 1), 1, most));
        };
        samplesPerTimedUnit_ = perDispatch(uint64_t(1) << 20, 16);
        const uint64_t stepTicks = 8 + 2 * uint64_t(bruteForcePrims ? bruteForcePrims : shader::kRayLoopTicks);
        const uint64_t room = loopBudget_ ? std::clamp<uint64_t>(loopBudget_ / (8 * stepTicks), 16, 64) : 64;
        // The level queue holds a unit's items (makeLevelQueue): it keeps the small unit.
        const bool large = context.cpuDevice() && plan.levelSchedule != LevelSchedule::Queued;
        samplesPerUnit_ = large ? perDispatch(uint64_t(1) << 22, room) : samplesPerTimedUnit_;
        // $TELESCOPE_SAMPLES_PER_DISPATCH: a test knob (the loop budget's tests vary it).
        if (const char* v = std::getenv("TELESCOPE_SAMPLES_PER_DISPATCH"); v && *v)
            samplesPerUnit_ = samplesPerTimedUnit_ = std::clamp<uint32_t>(uint32_t(std::strtoul(v, nullptr, 10)), 1, 1024);
        if (plan.levelSchedule == LevelSchedule::Queued) makeLevelQueue(context, plan, pixels * samplesPerUnit_);
    }

    bool setCamera(const Camera& cam) override {
        setPushCamera(push_, cam);
        return true;
    }

    uint32_t samplesPerUnit() const override { return samplesPerUnit_; }
    uint32_t samplesPerTimedUnit() const override { return samplesPerTimedUnit_; }
    // A CommandBatch holds 64 dispatches x the passes of the integrator (see Renderer).
    uint32_t maxUnitsPerBatch() const override { return levelCount_ ? 12 : 64; }

    uint32_t recordUnit(gpu::CommandBatch& batch, uint64_t sampleBase, uint32_t samples) override {
        push_.sampleBase = uint32_t(sampleBase);
        push_.sampleCount = samples;
        record(batch, push_, false);
        return samples;
    }

    // Paths carried past the batch's last dispatch are finished here, one dispatch at a time (each
    // takes every carried path at least one step further), so that the film holds every sample
    // the batch counted.
    bool batchComplete(std::vector<gpu::DispatchTiming>& extra) override {
        std::array<uint32_t, shader::kLoopStatCount>& s = lastLoopStats_;
        s = readLoopStats();
        shader::PathTracePush drain = push_;
        drain.sampleBase += drain.sampleCount;  // the end of the batch's samples: no new ones
        drain.sampleCount = 0;
        while (s[shader::kLoopStatCarried] != s[shader::kLoopStatResumed]) {
            drain_->reserve(1);
            drain_->begin();
            drain_->dispatch(pipeline_, &drain, sizeof(drain), groupsX_, groupsY_, 1, carriedLabel_.c_str());
            for (auto& t : drain_->submitAndWait()) extra.push_back(std::move(t));
            ++drainDispatches_;
            s = readLoopStats();
        }
        return true;
    }

    // As read by the last batchComplete (no second read per batch).
    LoopStats loopStats() const override {
        const std::array<uint32_t, shader::kLoopStatCount>& s = lastLoopStats_;
        LoopStats out;
        out.capHits = s[shader::kLoopStatCapHits];
        out.carried = s[shader::kLoopStatCarried];
        out.resumed = s[shader::kLoopStatResumed];
        out.retried = s[shader::kLoopStatRetried];
        out.overlong = s[shader::kLoopStatOverlong];
        out.drainDispatches = drainDispatches_;
        return out;
    }

    void setPilotLevel(uint32_t level) override {
        if (push_.pilotLevel == kNoPilotLevel) throw std::logic_error("setPilotLevel on a render that is not a pilot");
        push_.pilotLevel = level;
        if (pilot_.valid()) pilot_.fill(0);
    }

    PilotSums pilotSums(uint64_t samples) const override {
        if (!pilot_.valid()) throw std::logic_error("pilotSums on a render that is not a pilot");
        const std::vector<glm::vec4> raw = pilot_.downloadAll<glm::vec4>();
        PilotSums out;
        out.samples = samples;
        for (uint32_t c = 0; c < shader::kPilotChannelCount; ++c) {
            out.sums[c].resize(pixels_);
            for (size_t i = 0; i < pixels_; ++i) {
                const size_t hi = (c * pixels_ + i) * 2;
                out.sums[c][i] = glm::dvec4(raw[hi]) + glm::dvec4(raw[hi + 1]);
            }
        }
        return out;
    }

    void recordWarmUp(gpu::CommandBatch& batch) override {
        shader::PathTracePush warm = push_;
        warm.sampleCount = 0;
        record(batch, warm, true);
    }

private:
    // ---- Queued level schedule: the level queue and its passes (gpu_types.h) ----
    void makeLevelQueue(gpu::Context& context, const RenderPlan& plan, uint64_t capacity) {
        if (capacity >= (uint64_t(1) << 27))
            throw std::runtime_error(fmt::format("{} samples per dispatch is too many for the queued level schedule",
                                                 capacity));
        auto align4 = [](uint64_t n) { return (n + 3) / 4 * 4; };
        const uint64_t chunks = (capacity + shader::kLevelChunk - 1) / shader::kLevelChunk;
        const uint64_t bytes = (align4(chunks * shader::kLevelBuckets) + align4(capacity)) * 4 + capacity * 32;
        levelQueue_ = gpu::Buffer(context, bytes, "level queue");
        levelQueue_.fill(0);
        push_.queueAddressLo = uint32_t(levelQueue_.address());
        push_.queueAddressHi = uint32_t(levelQueue_.address() >> 32);
        push_.queueCapacity = uint32_t(capacity);
        const uint32_t pushBytes = uint32_t(sizeof(shader::PathTracePush));
        auto desc = [&](PassKind kind) {
            return gpu::PipelineDesc{plannedEntry(plan, kind).shader, 0, pushBytes, plan.pathTraceSpec};
        };
        std::vector<std::unique_ptr<gpu::ComputePipeline>> passes = gpu::createComputePipelines(
            context, {desc(PassKind::LevelCount), desc(PassKind::LevelScan), desc(PassKind::LevelScatter),
                      desc(PassKind::PathResolve)});
        levelCount_ = std::move(passes[0]);
        levelScan_ = std::move(passes[1]);
        levelScatter_ = std::move(passes[2]);
        pathResolve_ = std::move(passes[3]);
    }

    void record(gpu::CommandBatch& batch, const shader::PathTracePush& push, bool warm) {
        if (!levelCount_) {
            batch.dispatch(pipeline_, &push, sizeof(push), warm ? 1 : groupsX_, warm ? 1 : groupsY_, 1,
                           warm ? "warm-up" : passName(PassKind::PathTrace));
            return;
        }
        // Sort this unit's (pixel, sample) items by level, trace them, resolve per pixel.
        const uint64_t items = uint64_t(push.width) * push.height * push.sampleCount;
        const uint64_t chunks = (items + shader::kLevelChunk - 1) / shader::kLevelChunk;
        const uint32_t chunkGroups = uint32_t(
            std::max<uint64_t>((chunks + shader::kLevelQueueGroupSize - 1) / shader::kLevelQueueGroupSize, 1));
        auto name = [warm](PassKind pass) { return warm ? "warm-up" : passName(pass); };
        batch.dispatch(*levelCount_, &push, sizeof(push), chunkGroups, 1, 1, name(PassKind::LevelCount));
        batch.dispatch(*levelScan_, &push, sizeof(push), 1, 1, 1, name(PassKind::LevelScan));
        batch.dispatch(*levelScatter_, &push, sizeof(push), chunkGroups, 1, 1, name(PassKind::LevelScatter));
        batch.dispatch(pipeline_, &push, sizeof(push), groupsX_, groupsY_, 1, name(PassKind::PathTrace));
        batch.dispatch(*pathResolve_, &push, sizeof(push), groupsX_, groupsY_, 1, name(PassKind::PathResolve));
    }

    std::unique_ptr<gpu::ComputePipeline> levelCount_, levelScan_, levelScatter_, pathResolve_;
    gpu::Buffer levelQueue_;
    std::array<uint32_t, shader::kLoopStatCount> readLoopStats() const {
        std::array<uint32_t, shader::kLoopStatCount> s{};
        loopStats_.download(s.data(), sizeof(s));
        return s;
    }

    gpu::Buffer loopStats_;  // kLoopStat* counters
    std::array<uint32_t, shader::kLoopStatCount> lastLoopStats_{};
    gpu::Buffer records_;    // continuation records (a loop budget only)
    std::unique_ptr<gpu::CommandBatch> drain_;
    uint32_t loopBudget_ = 0;
    uint64_t drainDispatches_ = 0;
    gpu::Buffer pilot_;  // pmf pilot only: kPilot* sums
    size_t pixels_ = 0;
    gpu::ComputePipeline pipeline_;
    // The drains' timing label: path_trace's, marked (the plan test counts it as path_trace).
    const std::string carriedLabel_ = std::string(passName(PassKind::PathTrace)) + " (carried)";
    shader::PathTracePush push_{};
    uint32_t groupsX_ = 1, groupsY_ = 1, samplesPerUnit_ = 1, samplesPerTimedUnit_ = 1;
};

}  // namespace

std::unique_ptr<SamplePasses> makePathTracePasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan,
                                                  const RenderBuffers& buffers, uint32_t seed) {
    return std::make_unique<PathTracePasses>(context, scene, plan, buffers, seed);
}

}  // namespace telescope
