// Photon mapping's passes (docs/PHOTON-MAPPING.md). A photon pass is photon_trace (photon_count
// paths into the shared photon buffer), hash_grid_build (the hash grid over them) and gather (every
// pixel once; in slices when a bucket holds more than kGatherSlicePhotons photons).
//
// Radii:
//   photon_map:                         r = gather_radius, one pass = one sample
//   progressive_photon_map:             pass i (0-based, s = i + 1): r_s^2 = r_1^2 prod_{k=1}^{s-1} (k + alpha) / (k + 1)
//                                       (Knaus & Zwicker), one pass = one sample
//   photon_map + debias:                a sample is a block of m^k passes at level k, base radius
//                                       r_b = gather_radius, r_k^2 = r_b^2 s^k (scene/photon_levels.h)
//   progressive_photon_map + debias:    the same, with block i's base radius r_b = r_{i+1} of the
//                                       PPM schedule
// The hash grid's cell size is 2 r_b, the largest gather diameter of the pass.
//
// Schedules of the blocks: uniform (the host draws one level per block for the whole image; a
// unit is one pass and the last pass of a block completes one sample per pixel) or per_pixel
// (each pixel draws its own level in the gather and keeps its own block; one pass is one unit and
// one film sample index, pixels count their own completed blocks).
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>

#include "render/photon_map.h"
#include "render/sample_passes.h"
#include "scene/photon_levels.h"
#include "shared/gpu_types.h"
#include "shared/photon_density.h"
#include "shared/rng.h"
#include "scene/enum_names.h"

namespace telescope {

namespace {

bool unbiased(const IntegratorSettings& in) { return in.debias.estimator != DebiasEstimator::None; }
bool progressive(const IntegratorSettings& in) { return in.type == IntegratorType::ProgressivePhotonMap; }
bool perPixel(const IntegratorSettings& in) { return unbiased(in) && in.debias.schedule == LevelSchedule::PerPixel; }

const char* kernelName(PhotonKernel k) { return nameOf(kPhotonKernelNames, k); }

shader::PhotonLevels photonLevels(const DebiasSettings& d) {
    return {d.pmf.r, std::log(d.photon.areaRatio), d.photon.photonGrowth, d.photon.levelCap};
}

// Base radius of sample i (a pass, or a block of the uniform schedule).
double baseRadius(const IntegratorSettings& in, uint64_t sample) {
    const double r1 = in.photon.gatherRadius;
    if (!progressive(in)) return r1;
    // prod_{k=1}^{s-1} (k + alpha) / (k + 1) = Gamma(s + alpha) / (Gamma(1 + alpha) Gamma(s + 1))
    const double s = double(sample) + 1.0, a = in.photon.alpha;
    const double logScale = std::lgamma(s + a) - std::lgamma(1.0 + a) - std::lgamma(s + 1.0);
    return r1 * std::exp(0.5 * logScale);
}

// The level of block `block` under the uniform schedule: drawn on the host from its own stream.
uint32_t uniformBlockLevel(const DebiasSettings& d, uint64_t block, uint32_t seed) {
    shader::Rng rng = shader::rngCreate(0x9e3779b9u, uint32_t(block), seed ^ 0x68bc21ebu);
    const float u1 = shader::rngNext(rng), u2 = shader::rngNext(rng);
    return shader::photonLevelSample(photonLevels(d), u1, u2);
}

// ---- Photon budget ----
// Tungsten's photon_count caps both the paths of a pass and the photons it stores: its threads
// trace paths until their share of the photon buffer is full, and the powers are divided by the
// paths traced. Biased and progressive photon mapping keep that meaning, in rounds: round r traces
// the paths r * lanes ... (r + 1) * lanes - 1 (below photon_count), and a round starts only while
// the earlier rounds stored fewer than photon_count photons. The paths traced, their photons and
// the image then depend on the seed alone, and the pass stores photon_count photons plus part of
// one round (at most 1/64 of photon_count paths' photons). The stop depends on what the earlier
// rounds stored, which makes the pass a ratio whose bias is of the order of 1 / paths (Tungsten's
// has the same); unbiased photon mapping traces photon_count paths and keeps every photon.
struct PhotonBudget {
    bool capped = false;
    uint32_t lanes = 0, rounds = 1, roundBits = 0;
};

PhotonBudget photonBudget(const IntegratorSettings& in) {
    PhotonBudget b;
    const uint32_t n = in.photon.photonCount;
    if (unbiased(in)) {
        b.lanes = n;
        return b;
    }
    b.capped = true;
    // At most 64 rounds (a dispatch each) of at least 1024 paths.
    b.rounds = std::clamp<uint32_t>(n / shader::kPhotonCapRoundPaths, 1u, shader::kPhotonCapRounds);
    b.lanes = (n + b.rounds - 1) / b.rounds;
    b.rounds = (n + b.lanes - 1) / b.lanes;
    while ((1u << b.roundBits) < b.rounds) ++b.roundBits;
    return b;
}

}  // namespace

uint32_t photonBlockLevel(const DebiasSettings& debias, uint64_t block, uint32_t seed) {
    return uniformBlockLevel(debias, block, seed);
}

// ---- Plan ----
void planPhotons(const Scene& scene, const SceneFeatures& f, RenderPlan& plan) {
    using namespace shader;
    const IntegratorSettings& in = scene.integrator;
    const PhotonSettings& ph = in.photon;
    const bool nee = ph.directLighting == DirectLighting::NextEvent;

    const PhotonBudget budget = photonBudget(in);
    plan.passes.push_back(plannedPass(
        PassKind::PhotonTrace,
        budget.capped
            ? fmt::format("photon paths from the lights (picked by power), stored at diffuse hits{} in one photon "
                          "buffer, in rounds of {} paths until {} photons are stored or {} paths traced (Tungsten's "
                          "photon_count); powers divided by the paths traced",
                          nee ? " after the first bounce" : "", budget.lanes, ph.photonCount, ph.photonCount)
            : fmt::format("{} photon paths per pass from the lights (picked by power), stored at diffuse hits{} in "
                          "one photon buffer (grown, never truncated: the unbiased blocks keep every photon)",
                          ph.photonCount, nee ? " after the first bounce" : "")));
    plan.passes.push_back(plannedPass(PassKind::HashGridBuild,
                           "count photons per hash bucket, exclusive prefix sum, scatter; cell size = the largest "
                           "gather diameter of the pass"));
    plan.passes.push_back(plannedPass(PassKind::Gather,
                           fmt::format("camera paths through specular bounces to the first diffuse vertex (radiance "
                                       "scaled by 1/eta^2 at each refraction), one traversal of the 2x2x2 cells ({}{} "
                                       "kernel){}",
                                       ph.gatherCount > 0 ? fmt::format("the {} nearest photons within the radius, ",
                                                                        ph.gatherCount)
                                                          : std::string(),
                                       kernelName(ph.kernel), nee ? ", direct light by next-event estimation" : "")));
    plan.skipped.push_back({"volume tracking", "photon mapping scenes have no participating media (the loader rejects them)"});
    plan.skipped.push_back(
        {passName(PassKind::PathTrace), fmt::format("the integrator is '{}'", nameOf(kIntegratorTypeNames, in.type))});

    // ---- Estimator ----
    if (!unbiased(in) && !progressive(in)) {
        plan.estimator = fmt::format("biased photon mapping K_r, fixed radius r = {:g}", ph.gatherRadius);
    } else if (!unbiased(in)) {
        plan.estimator = fmt::format("progressive photon mapping (Knaus & Zwicker), r_1 = {:g}, alpha = {:g}",
                                     ph.gatherRadius, ph.alpha);
    } else {
        const DebiasSettings& d = in.debias;
        const PhotonBlockSettings& b = d.photon;
        const PhotonBlockTheory t = photonBlockTheory(d.pmf.r, b.areaRatio, b.photonGrowth);
        const double truncation = std::pow(double(b.areaRatio), double(b.levelCap));
        plan.estimator = fmt::format(
            "unbiased{} photon mapping in blocks: Z = mean K_r_b + mean (K_r(k+1) - K_r(k)) / p(k) over the m^k photon "
            "passes of a level-k block; r_b = {:g}{}, r_k^2 = r_b^2 s^k with area_ratio s = {:g}, photon_growth m = {}, "
            "p(k) = r (1-r)^k with r = {:g} (continues with q = {:g}) truncated to k < level_cap K = {}\n"
            "  expected {:.3g} photon passes per sample ({:.3g} untruncated; heavy-tailed: a block at k = {} takes {} "
            "passes); tail index of the sample error a = {:.3g} (finite mean, infinite variance); typical error ~ "
            "cost^-{:.3g}\n"
            "  truncation: unbiased for the kernel estimate at r_K; its bias is s^K = {:.2g} of the base bias\n"
            "  schedule {}",
            progressive(in) ? " progressive" : "", ph.gatherRadius,
            progressive(in) ? fmt::format(" shrinking per block as progressive photon mapping's (alpha = {:g})", ph.alpha)
                            : "",
            b.areaRatio, b.photonGrowth, d.pmf.r, t.q, b.levelCap, photonExpectedPasses(d.pmf.r, b.photonGrowth, b.levelCap),
            t.expectedPasses, b.levelCap - 1, std::pow(double(b.photonGrowth), double(b.levelCap - 1)), t.tailIndex,
            t.errorExponent, truncation,
            d.schedule == LevelSchedule::PerPixel
                ? "per_pixel: each pixel draws its own level in the gather and keeps its own block across passes; "
                  "--spp counts photon passes; blocks unfinished at the end are dropped, so the image is consistent, "
                  "not unbiased (a bias towards short blocks that vanishes as passes grow)"
                : "uniform: the host draws one level per block for the whole image; --spp counts blocks, --time "
                  "finishes the running block; unbiased up to the truncation");
    }

    plan.featuresOf = "photon_trace and gather";
    plan.photonSceneCentre = f.sceneCentre;
    plan.photonSceneRadius = 0.5f * f.sceneExtent;  // the same disk as the light selection's power (gpu_scene.cpp)

    plan.photonSpec = {
        {kSpecHasSpheres, f.spheres},
        {kSpecHasDisks, f.disks},
        {kSpecHasSpecular, f.specular},
        {kSpecLightCount, f.lightCount},
        {kSpecPointLights, f.pointLights},
        {kSpecTwoSided, in.enableTwoSidedShading},
        {kSpecFilter, filterConstant(scene.camera)},
        {kSpecRayEpsilon, gpu::specFloat(1e-5f * f.sceneExtent)},
        {kSpecPhotonEstimator, unbiased(in) ? kPhotonUnbiased : kPhotonBiased},
        {kSpecPhotonKernel, uint32_t(ph.kernel)},
        {kSpecPhotonSchedule, perPixel(in) ? kLevelSchedulePerPixel : kLevelScheduleUniform},
        {kSpecPhotonNextEvent, nee},
        {kSpecPhotonGatherCount, ph.gatherCount},
        {kSpecPhotonRadianceScaling, ph.testRadianceScaling},
        {kSpecPhotonTestCosine, ph.testGatherCosine},
        {kSpecPhotonMaxBounces, in.maxBounces},
        {kSpecSceneInUniforms, f.fitsUniforms},
        {kSpecSceneTexels, 1u},  // (where the uniform scene is not read) off beyond the device's texel limit
        {kSpecTablesInUniforms, f.tablesFitUniforms},
        {kSpecBruteForcePrims, f.bruteForcePrims},
        {kSpecBruteForceCurved, f.bruteForceCurved},
        {kSpecSmoothNormals, f.smoothNormals},
        {kSpecTieRanks, f.interfaces && ph.testCoincidentSurfaces},
        {kSpecBsdfFamilies, f.bsdfFamilies},
        {kSpecHasTextures, f.textures},
        {kSpecEnvironmentLight, f.environmentLight},
        {kSpecCapLight, f.capLight},
        {kSpecEnvironmentMap, f.environmentMap},
    };

    // ---- What the pipelines are compiled with, read off their specialisation ----
    const std::vector<gpu::SpecConstant>& spec = plan.photonSpec;
    plan.features = sceneFeatureSwitches(spec, f);
    const bool atInfinity = specValue(spec, kSpecEnvironmentLight) != 0xffffffffu || specValue(spec, kSpecCapLight) != 0xffffffffu;
    plan.features.insert(
        plan.features.end(),
        {specSwitch(spec, "glossy", kSpecBsdfFamilies, "Lambert and delta materials only", 0,
                    "glossy, plastic or mixed materials present: photons sample them, gathers weight each photon by "
                    "the BSDF"),
         FeatureSwitch{"lights at infinity", atInfinity,
                       atInfinity ? "infinite_sphere or infinite_sphere_cap: photons enter through the disk of the scene's "
                                    "bounding sphere (kEnvironmentLight, kCapLight)"
                                  : "no infinite_sphere or infinite_sphere_cap (kEnvironmentLight, kCapLight = 0xffffffff)"},
         specSwitch(spec, "environment map", kSpecEnvironmentMap, "no environment image", 0,
                     "infinite_sphere with an image, importance-sampled"),
         specSwitch(spec, "next event", kSpecPhotonNextEvent, "direct_lighting = photons: all light from photons"),
         specSwitch(spec, "debias", kSpecPhotonEstimator, "no debias block: biased K_r", kPhotonBiased,
                    "debias block: blocks of passes, K_r_b + correction")});
}

// ---- Passes ----
namespace {

class PhotonPasses : public SamplePasses {
public:
    PhotonPasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan, const RenderBuffers& b,
                 uint32_t seed)
        : integrator_(scene.integrator),
          camera_(scene.camera),
          seed_(seed),
          budget_(photonBudget(scene.integrator)),
          // a capped pass stores photon_count photons and part of one round more
          map_(context, uint64_t(scene.integrator.photon.photonCount) * (budget_.capped ? 9 : 8) / 8),
          gatherShader_(plannedEntry(plan, PassKind::Gather).shader),
          gatherSpec_(deviceSceneSpec(context, plan.photonSpec, b, false)),
          pipelines_(gpu::createComputePipelines(
              context, {{plannedEntry(plan, PassKind::PhotonTrace).shader, shader::kSceneBindingCount,
                         uint32_t(sizeof(shader::PhotonTracePush)),
                         deviceSceneSpec(context, plan.photonSpec, b), kSceneUniformBindings, kSceneTexelBindings},
                        gatherDesc(map_.texelsFit())})),
          trace_(*pipelines_[0]),
          blockBuffer_(context,
                       uint64_t(scene.camera.width) * scene.camera.height *
                           (shader::kGatherBlockVec4s + (scene.integrator.photon.gatherCount + 1) / 2) * 16,
                       "gather blocks") {
        blockBuffer_.fill(0);
        scene_ = b.sceneBindings(context, false);
        trace_.bindBuffers(scene_);
        gatherTexels_ = map_.texelsFit();  // as the gather pipeline was created
        bindGather();
        const Camera& cam = scene.camera;
        const uint32_t paths = scene.integrator.photon.photonCount;
        tracePush_.pathCount = paths;
        tracePush_.seed = seed;
        tracePush_.pathScale = 1.0f / float(paths);
        tracePush_.sceneCentre = plan.photonSceneCentre;
        tracePush_.sceneRadius = plan.photonSceneRadius;
        tracePush_.laneCount = budget_.lanes;
        tracePush_.roundBits = budget_.roundBits;
        tracePush_.storeCap = budget_.capped ? paths : 0xffffffffu;
        // A thread for every lane (photon_trace.comp traceLanes), 2D when the lanes need more workgroups
        // than one dimension allows.
        const uint32_t groups = (budget_.lanes + shader::kPhotonTraceGroupSize - 1) / shader::kPhotonTraceGroupSize;
        traceGroups_.x = std::min<uint32_t>(groups, 32768);
        traceGroups_.y = (groups + traceGroups_.x - 1) / traceGroups_.x;
        setPushCamera(gatherPush_, cam);
        gatherPush_.width = cam.width;
        gatherPush_.height = cam.height;
        gatherPush_.seed = seed;
        gatherPush_.accumLo = uint32_t(b.accum->address());
        gatherPush_.accumHi = uint32_t(b.accum->address() >> 32);
        gatherPush_.blockLo = uint32_t(blockBuffer_.address());
        gatherPush_.blockHi = uint32_t(blockBuffer_.address() >> 32);
        const shader::PhotonLevels levels = photonLevels(scene.integrator.debias);
        gatherPush_.pmfR = levels.r;
        gatherPush_.logAreaRatio = levels.logAreaRatio;
        gatherPush_.photonGrowth = levels.growth;
        gatherPush_.levelCap = levels.cap;
    }

    bool setCamera(const Camera& cam) override {
        setPushCamera(gatherPush_, cam);
        passInBlock_ = 0;  // blocks of the old camera are dropped, never mixed into the new one
        blockBuffer_.fill(0);
        return true;
    }

    uint32_t samplesPerUnit() const override { return 1; }
    uint32_t maxUnitsPerBatch() const override { return 1; }
    uint32_t dispatchesPerUnit() const override {
        return 15 + budget_.rounds + slices_;
    }
    bool sampleInProgress() const override { return blocks() && passInBlock_ != 0; }

    // One photon pass. Returns the samples per pixel it completes: 1, or under the uniform
    // schedule 1 only for the last pass of a block.
    uint32_t recordUnit(gpu::CommandBatch& batch, uint64_t sampleBase, uint32_t samples) override {
        if (samples != 1) throw std::logic_error("a photon pass adds at most one sample per pixel");
        const IntegratorSettings& in = integrator_;
        if (blocks() && passInBlock_ == 0) {
            block_.level = uniformBlockLevel(in.debias, sampleBase, seed_);
            block_.passes = shader::photonBlockPasses(photonLevels(in.debias), block_.level);
        }
        const double radius = baseRadius(in, sampleBase);
        const VkDeviceAddress header = map_.headerAddress();
        if (gatherOnly_) {
            gatherOnly_ = false;  // the photon map of the last attempt is whole; only its gather lacked slices
        } else {
            // Cells of side 2 r_b for the fixed-radius gathers (2x2x2 around x), r_b / 2 for the
            // k-nearest (5x5x5 around x's cell: photon_gather.glsl nearestSearch)
            const double cell = integrator_.photon.gatherCount > 0 ? radius / shader::kNearestCellsPerRadius : 2.0 * radius;
            map_.beginPass(float(cell), budget_.capped ? tracePush_.pathCount : 0u);
            countedCapHits_ = 0;
            tracePush_.headerLo = uint32_t(header);
            tracePush_.headerHi = uint32_t(header >> 32);
            tracePush_.pass = uint32_t(sampleBase);
            tracePush_.passInBlock = passInBlock_;
            if (budget_.capped) {
                shader::Rng rng = shader::rngCreate(0x2c1b3c6du, uint32_t(sampleBase), seed_ ^ 0x297a2d39u);
                tracePush_.curveShift = shader::rngNextUint(rng);
            }
            for (uint32_t r = 0; r < budget_.rounds; ++r) {
                tracePush_.roundIndex = r;
                batch.dispatch(trace_, &tracePush_, sizeof(tracePush_), traceGroups_.x, traceGroups_.y, 1,
                               passName(PassKind::PhotonTrace));
            }
            map_.recordBuild(batch);
        }
        recordGather(batch, sampleBase, radius, header);
        return blocks() && passInBlock_ + 1 < block_.passes ? 0 : 1;
    }

    // The pass's gather in slices_ dispatches over the photon map at `header`.
    void recordGather(gpu::CommandBatch& batch, uint64_t sampleBase, double radius, VkDeviceAddress header) {
        if (gatherBinds_ != map_.generation()) bindGather();  // the photon map was reallocated
        gatherPush_.pass = uint32_t(sampleBase);
        gatherPush_.headerLo = uint32_t(header);
        gatherPush_.headerHi = uint32_t(header >> 32);
        gatherPush_.radius = float(radius);
        gatherPush_.level = blocks() ? block_.level : 0;
        gatherPush_.passInBlock = passInBlock_;
        gatherPush_.sliceCount = slices_;
        const Camera& cam = camera_;
        for (uint32_t slice = 0; slice < slices_; ++slice) {
            gatherPush_.slice = slice;
            batch.dispatch(*pipelines_[1], &gatherPush_, sizeof(gatherPush_), (cam.width + 7) / 8, (cam.height + 7) / 8, 1,
                           passName(PassKind::Gather));
        }
    }

    bool batchComplete(std::vector<gpu::DispatchTiming>& /*extra*/) override {
        const shader::PhotonMapHeader header = map_.header();  // one read for the three counts
        const uint64_t stored = header.storedCount;
        const uint32_t fullest = header.maxBucket;
        // photon_trace and gather of this pass (the header is per pass; a gather-only repeat adds to
        // what the attempt before it counted)
        loopCapHits_ += header.loopCapHits - countedCapHits_;
        countedCapHits_ = header.loopCapHits;
        lastStored_ = stored;
        lastTraced_ = header.tracedPaths;
        const uint32_t slicesNeeded = PhotonMap::slicesFor(fullest, integrator_.photon.gatherCount);
        if (stored > map_.capacity() || slicesNeeded > slices_) {
            // The gather skipped its accumulation: grow what was short and repeat the pass. A map
            // that overflowed built its grid from the photons it kept only, so its fullest bucket
            // is scaled by the photons stored over those kept (else the repeat finds too few
            // slices and traces the pass a third time: the water caustic's first pass did).
            const uint64_t kept = std::min<uint64_t>(stored, map_.capacity());
            const uint64_t expected = kept ? uint64_t(double(fullest) * double(stored) / double(kept)) : fullest;
            // A map that kept every photon has its grid and its fullest bucket: only the gather
            // runs again, with the slices that bucket needs (the water caustic's first pass: 7 s of
            // photon_trace not traced twice).
            gatherOnly_ = stored <= map_.capacity();
            if (stored > map_.capacity()) map_.reserve(stored + stored / 4);
            const uint32_t full = gatherOnly_ ? fullest
                                              : uint32_t(std::min<uint64_t>(expected + expected / 4, UINT32_MAX));
            slices_ = std::max(slices_, PhotonMap::slicesFor(full, integrator_.photon.gatherCount));
            return false;
        }
        map_.shrinkTo(stored + stored / 4);  // the next pass stores about as many
        if (slicesNeeded * 2 < slices_) slices_ = PhotonMap::slicesFor(fullest + fullest / 4, integrator_.photon.gatherCount);
        if (blocks() && ++passInBlock_ == block_.passes) passInBlock_ = 0;
        return true;
    }

    // Uniform schedule: the block's passes done, its length and level, and the per-pixel block
    // sums; per_pixel: every pixel's block. Random numbers are keyed by (block, pass in block), so
    // the restored block continues exactly as if it had never stopped.
    PendingSamples pending() const override {
        PendingSamples p;
        if (blocks() && passInBlock_ == 0) return p;
        if (!blocks() && !perPixel(integrator_)) return p;
        if (blocks()) {
            p.unitsDone = passInBlock_;
            p.unitsTotal = block_.passes;
            p.level = block_.level;
        }
        p.device.resize(blockBuffer_.size());
        blockBuffer_.download(p.device.data(), p.device.size());
        return p;
    }

    void restorePending(const PendingSamples& p, uint64_t nextSample) override {
        if (p.empty()) return;
        if (!blocks() && !perPixel(integrator_))
            throw std::invalid_argument("a block in progress, but this photon estimator has no blocks");
        if (p.device.size() != blockBuffer_.size())
            throw std::invalid_argument(fmt::format("block state of {} bytes, this render keeps {}", p.device.size(),
                                                    blockBuffer_.size()));
        if (blocks()) {
            const uint32_t level = uniformBlockLevel(integrator_.debias, nextSample, seed_);
            const uint32_t passes = shader::photonBlockPasses(photonLevels(integrator_.debias), level);
            if (p.level != level || p.unitsTotal != passes || p.unitsDone == 0 || p.unitsDone >= passes)
                throw std::invalid_argument(fmt::format(
                    "block {} in progress at level {} ({} of {} passes), but this render's block {} is at level {} "
                    "({} passes)", nextSample, p.level, p.unitsDone, p.unitsTotal, nextSample, level, passes));
            block_ = {level, passes};
            passInBlock_ = p.unitsDone;
        }
        blockBuffer_.upload(p.device.data(), p.device.size());
    }

    LoopStats loopStats() const override {
        LoopStats s;
        s.capHits = loopCapHits_;
        return s;
    }
    void countBatch(IntegratorCounters& c, uint32_t units) const override {
        // One unit (a photon pass) per batch (maxUnitsPerBatch).
        c.photonPaths += lastTraced_;
        c.photonPasses += units;
        c.photonsStored += lastStored_;
        c.photonMapBytes = map_.deviceBytes() + blockBuffer_.size();
    }

    void recordWarmUp(gpu::CommandBatch& batch) override {
        map_.recordWarmUp(batch);
        shader::PhotonTracePush t = tracePush_;
        t.pathCount = 0;
        t.laneCount = 0;
        t.headerLo = uint32_t(map_.headerAddress());
        t.headerHi = uint32_t(map_.headerAddress() >> 32);
        batch.dispatch(trace_, &t, sizeof(t), 1, 1, 1, "warm-up");
        shader::GatherPush g = gatherPush_;
        g.width = g.height = 0;
        g.headerLo = t.headerLo;
        g.headerHi = t.headerHi;
        g.sliceCount = 1;
        batch.dispatch(*pipelines_[1], &g, sizeof(g), 1, 1, 1, "warm-up");
    }

private:
    // Not the uniform scene in the gather: it traces one camera ray per pixel, and the uniform
    // scene made its photon loop slower (docs/BENCHMARKS.photon-notes.md).
    gpu::PipelineDesc gatherDesc(bool texels) const {
        std::vector<gpu::SpecConstant> spec = gatherSpec_;
        spec.push_back({shader::kSpecSortedTexels, texels});
        spec.push_back({shader::kSpecGatherSliceLength, PhotonMap::sliceLength(integrator_.photon.gatherCount)});
        return {gatherShader_, shader::kGatherBindingCount, uint32_t(sizeof(shader::GatherPush)), spec,
                kSceneUniformBindings, kSceneTexelBindings | (1u << shader::kBindingSortedTexels)};
    }

    // The scene, and the photon map's sorted photons as texels. A map grown beyond the texel
    // limit (or shrunk back under it) needs the gather built for the other way of reading them.
    void bindGather() {
        const bool texels = map_.texelsFit();
        if (texels != gatherTexels_) {
            const gpu::PipelineDesc d = gatherDesc(texels);
            pipelines_[1] = std::make_unique<gpu::ComputePipeline>(map_.context(), d.shaderName, d.bufferCount,
                                                                   d.pushConstantBytes, d.spec, d.uniformBindings,
                                                                   d.texelBindings, d.storageTexelBindings);
            gatherTexels_ = texels;
        }
        std::vector<const gpu::Buffer*> bound = scene_;
        bound[shader::kBindingSortedTexels] = &map_.gatherTexels();
        pipelines_[1]->bindBuffers(bound);
        gatherBinds_ = map_.generation();
    }

    // The uniform schedule's blocks (per_pixel keeps its blocks in the gather's buffer).
    bool blocks() const { return unbiased(integrator_) && !perPixel(integrator_); }

    struct UniformBlock {
        uint32_t level = 0;
        uint32_t passes = 1;  // m^level
    };

    // What the passes read of the scene, owned: the passes may outlive the caller's Scene.
    IntegratorSettings integrator_;
    Camera camera_;  // resolution only (the gather's dispatch size)
    uint32_t seed_;
    PhotonBudget budget_;
    PhotonMap map_;
    std::string gatherShader_;  // the plan's gather entry's shader
    std::vector<gpu::SpecConstant> gatherSpec_;  // but kSpecSortedTexels
    std::vector<std::unique_ptr<gpu::ComputePipeline>> pipelines_;  // photon_trace, gather; created in parallel
    gpu::ComputePipeline& trace_;
    gpu::Buffer blockBuffer_;  // the gather's per-pixel block sums and slice sums
    std::vector<const gpu::Buffer*> scene_;  // the scene bindings of photon_trace and gather
    uint64_t gatherBinds_ = 0;               // the photon map generation the gather is bound to
    bool gatherTexels_ = true;               // the gather pipeline's kSpecSortedTexels
    UniformBlock block_;
    shader::PhotonTracePush tracePush_{};
    glm::uvec2 traceGroups_{1, 1};  // photon_trace's workgroups (x, y) per round
    shader::GatherPush gatherPush_{};
    uint64_t lastStored_ = 0;
    uint64_t lastTraced_ = 0;
    uint32_t countedCapHits_ = 0;  // the header's loop-cap hits batchComplete has counted this pass
    bool gatherOnly_ = false;      // the next recordUnit repeats only the gather (more slices)
    uint64_t loopCapHits_ = 0;  // lanes of photon_trace and gather that reached lavapipe's loop cap (an error)
    uint32_t passInBlock_ = 0;
    uint32_t slices_ = 1;
};

}  // namespace

std::unique_ptr<SamplePasses> makePhotonPasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan,
                                               const RenderBuffers& buffers, uint32_t seed) {
    return std::make_unique<PhotonPasses>(context, scene, plan, buffers, seed);
}

}  // namespace telescope
