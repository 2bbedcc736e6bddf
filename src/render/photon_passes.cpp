// Photon mapping's passes (ESTIMATORS.md section 3). One unit is one photon pass, one sample per
// pixel: photon_trace emits photon_count paths into the shared photon buffer, hash_grid_build
// sorts them into the hash grid, gather evaluates every pixel once.
//
// Radii per pass i (0-based; s = i + 1):
//   photon_map:                         r = gather_radius
//   progressive_photon_map:             r_s^2 = r_1^2 prod_{k=1}^{s-1} (k + alpha) / (k + 1)  (Knaus & Zwicker)
//   photon_map + debias:                base level b = 1, r_b = gather_radius
//   progressive_photon_map + debias:    base level b = s, r_b = r_s of the level schedule, pmf
//                                       renormalised to j >= s (every pass unbiased)
// The hash grid's cell size is 2 r_b, the largest gather diameter of the pass.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>

#include "render/photon_map.h"
#include "render/sample_passes.h"
#include "shared/gpu_types.h"
#include "shared/photon_density.h"

namespace telescope {

namespace {

bool unbiased(const IntegratorSettings& in) { return in.debias.estimator != DebiasEstimator::None; }
bool progressive(const IntegratorSettings& in) { return in.type == IntegratorType::ProgressivePhotonMap; }

const char* kernelName(PhotonKernel k) {
    return k == PhotonKernel::Cone ? "cone" : k == PhotonKernel::Uniform ? "uniform" : "Epanechnikov";
}

shader::LevelPmf levelPmf(const PmfSettings& pmf) {
    return {pmf.type == PmfType::PowerLaw ? shader::kPmfPowerLaw : shader::kPmfGeometric, pmf.r, pmf.alpha};
}

// Base radius and base level of pass i.
struct PassRadius {
    double radius;
    double baseLevel;
};

PassRadius passRadius(const IntegratorSettings& in, uint64_t pass) {
    const double r1 = in.photon.gatherRadius;
    if (!progressive(in)) return {r1, 1.0};
    const double s = double(pass) + 1.0;
    if (unbiased(in)) {
        const double logR2 = shader::levelLogRadius2(levelPmf(in.debias.pmf), float(s), 1.0f);
        return {r1 * std::exp(0.5 * logR2), s};
    }
    // prod_{k=1}^{s-1} (k + alpha) / (k + 1) = Gamma(s + alpha) / (Gamma(1 + alpha) Gamma(s + 1))
    const double a = in.photon.alpha;
    const double logScale = std::lgamma(s + a) - std::lgamma(1.0 + a) - std::lgamma(s + 1.0);
    return {r1 * std::exp(0.5 * logScale), 1.0};
}

}  // namespace

// ---- Plan ----
void planPhotons(const Scene& scene, const SceneFeatures& f, RenderPlan& plan) {
    using namespace shader;
    const IntegratorSettings& in = scene.integrator;
    const PhotonSettings& ph = in.photon;
    const bool nee = ph.directLighting == DirectLighting::NextEvent;

    plan.passes.push_back({"photon_trace", "photon_trace",
                           fmt::format("{} photon paths per pass from the lights (picked by power), stored at diffuse "
                                       "hits{} in one photon buffer (grown, never truncated)",
                                       ph.photonCount, nee ? " after the first bounce" : "")});
    plan.passes.push_back({"hash_grid_build", "hash_grid_build",
                           "count photons per hash bucket, exclusive prefix sum, scatter; cell size = the largest "
                           "gather diameter of the pass"});
    plan.passes.push_back({"gather", "gather",
                           fmt::format("camera paths through specular bounces to the first diffuse vertex, one "
                                       "traversal of the 2x2x2 cells ({} kernel){}",
                                       kernelName(ph.kernel), nee ? ", direct light by next-event estimation" : "")});
    plan.skipped.push_back({"volume tracking", "photon mapping scenes have no participating media (the loader rejects them)"});
    plan.skipped.push_back({"path_trace", fmt::format("the integrator is '{}'",
                                                      progressive(in) ? "progressive_photon_map" : "photon_map")});

    // ---- Estimator ----
    if (!unbiased(in) && !progressive(in)) {
        plan.estimator = fmt::format("biased photon mapping K_r, fixed radius r = {:g}", ph.gatherRadius);
    } else if (!unbiased(in)) {
        plan.estimator = fmt::format("progressive photon mapping (Knaus & Zwicker), r_1 = {:g}, alpha = {:g}",
                                     ph.gatherRadius, ph.alpha);
    } else {
        plan.estimator = fmt::format(
            "unbiased{} photon mapping, single-term K_r{} + (K_r(j+1) - K_r(j)) / p(j), r_1 = {:g}, {} levels, {}, level "
            "drawn per pixel in the shader",
            progressive(in) ? " progressive" : "", progressive(in) ? "(pass)" : "1", ph.gatherRadius,
            in.debias.pmf.type == PmfType::PowerLaw ? "power-law" : "geometric", pmfDescription(in.debias.pmf));
    }

    // ---- Feature switches ----
    auto feature = [&](const char* name, bool on, std::string yes, std::string no) {
        plan.features.push_back({name, on, on ? yes : no});
    };
    feature("spheres", f.spheres, "sphere primitives present", "no sphere primitives");
    feature("disks", f.disks, "disk primitives present", "no disk primitives");
    feature("specular", f.specular, "mirror or dielectric materials present", "no mirror or dielectric materials");
    feature("next event", nee, "direct_lighting = next_event", "direct_lighting = photons: all light from photons");
    feature("debias", unbiased(in), "debias block: K_r1 + correction", "no debias block: biased K_r");
    plan.featuresOf = "photon_trace and gather";

    const uint32_t levels = in.debias.pmf.type == PmfType::PowerLaw ? kPmfPowerLaw : kPmfGeometric;
    plan.photonSpec = {
        {kSpecHasSpheres, f.spheres},
        {kSpecHasDisks, f.disks},
        {kSpecHasSpecular, f.specular},
        {kSpecLightCount, f.lightCount},
        {kSpecTwoSided, in.enableTwoSidedShading},
        {kSpecFilter, filterConstant(scene.camera)},
        {kSpecRayEpsilon, gpu::specFloat(1e-5f * f.sceneExtent)},
        {kSpecPhotonEstimator, unbiased(in) ? kPhotonUnbiased : kPhotonBiased},
        {kSpecPhotonKernel, uint32_t(ph.kernel)},
        {kSpecPhotonLevels, levels},
        {kSpecPhotonPmfR, gpu::specFloat(in.debias.pmf.r)},
        {kSpecPhotonPmfAlpha, gpu::specFloat(in.debias.pmf.alpha)},
        {kSpecPhotonNextEvent, nee},
        {kSpecPhotonMaxBounces, in.maxBounces},
    };
}

// ---- Passes ----
namespace {

class PhotonPasses : public SamplePasses {
public:
    PhotonPasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan, const RenderBuffers& b,
                 uint32_t seed)
        : scene_(scene),
          map_(context, scene.integrator.photon.photonCount),
          trace_(context, "photon_trace", shader::kSceneBindingCount, uint32_t(sizeof(shader::PhotonTracePush)),
                 plan.photonSpec),
          gather_(context, "gather", shader::kSceneBindingCount, uint32_t(sizeof(shader::GatherPush)),
                  plan.photonSpec) {
        trace_.bindBuffers({b.prims, b.nodes, b.materials, b.lights});
        gather_.bindBuffers({b.prims, b.nodes, b.materials, b.lights});
        const Camera& cam = scene.camera;
        const uint32_t paths = scene.integrator.photon.photonCount;
        tracePush_.pathCount = paths;
        tracePush_.seed = seed;
        tracePush_.pathScale = 1.0f / float(paths);
        gatherPush_.cameraPosition = cam.position;
        gatherPush_.cameraRight = cam.right;
        gatherPush_.cameraUp = cam.up;
        gatherPush_.cameraForward = cam.forward;
        gatherPush_.planeDistance = 1.0f / std::tan(0.5f * glm::radians(cam.fovDegrees));
        gatherPush_.width = cam.width;
        gatherPush_.height = cam.height;
        gatherPush_.seed = seed;
        gatherPush_.accumLo = uint32_t(b.accum->address());
        gatherPush_.accumHi = uint32_t(b.accum->address() >> 32);
    }

    bool setCamera(const Camera& cam) override {
        gatherPush_.cameraPosition = cam.position;
        gatherPush_.cameraRight = cam.right;
        gatherPush_.cameraUp = cam.up;
        gatherPush_.cameraForward = cam.forward;
        gatherPush_.planeDistance = 1.0f / std::tan(0.5f * glm::radians(cam.fovDegrees));
        return true;
    }

    uint32_t samplesPerUnit() const override { return 1; }
    uint32_t maxUnitsPerBatch() const override { return 1; }

    void recordUnit(gpu::CommandBatch& batch, uint64_t sampleBase, uint32_t samples) override {
        if (samples != 1) throw std::logic_error("a photon pass adds one sample per pixel");
        const PassRadius r = passRadius(scene_.integrator, sampleBase);
        map_.beginPass(float(2.0 * r.radius));
        const VkDeviceAddress header = map_.headerAddress();

        tracePush_.headerLo = uint32_t(header);
        tracePush_.headerHi = uint32_t(header >> 32);
        tracePush_.pass = uint32_t(sampleBase);
        const uint32_t traceGroups = (tracePush_.pathCount + shader::kPhotonTraceGroupSize - 1) / shader::kPhotonTraceGroupSize;
        // 2D when the paths need more workgroups than one dimension allows.
        const uint32_t gx = std::min<uint32_t>(traceGroups, 32768), gy = (traceGroups + gx - 1) / gx;
        tracePush_.rowThreads = gx * shader::kPhotonTraceGroupSize;
        batch.dispatch(trace_, &tracePush_, sizeof(tracePush_), gx, gy, 1, "photon_trace");

        map_.recordBuild(batch);

        gatherPush_.pass = uint32_t(sampleBase);
        gatherPush_.headerLo = uint32_t(header);
        gatherPush_.headerHi = uint32_t(header >> 32);
        gatherPush_.radius = float(r.radius);
        gatherPush_.baseLevel = float(r.baseLevel);
        const Camera& cam = scene_.camera;
        batch.dispatch(gather_, &gatherPush_, sizeof(gatherPush_), (cam.width + 7) / 8, (cam.height + 7) / 8, 1,
                       "gather");
    }

    bool batchComplete() override {
        const uint64_t stored = map_.storedCount();
        lastStored_ = stored;
        if (stored <= map_.capacity()) {
            map_.shrinkTo(stored + stored / 4);  // the next pass stores about as many
            return true;
        }
        map_.reserve(stored + stored / 4);  // the gather skipped its accumulation: repeat the pass
        return false;
    }

    uint64_t photonPathsLastBatch() const override { return tracePush_.pathCount; }
    uint64_t photonsStoredLastBatch() const override { return lastStored_; }
    uint64_t deviceBytes() const override { return map_.deviceBytes(); }

    void recordWarmUp(gpu::CommandBatch& batch) override {
        map_.recordWarmUp(batch);
        shader::PhotonTracePush t = tracePush_;
        t.pathCount = 0;
        t.headerLo = uint32_t(map_.headerAddress());
        t.headerHi = uint32_t(map_.headerAddress() >> 32);
        batch.dispatch(trace_, &t, sizeof(t), 1, 1, 1, "warm-up");
        shader::GatherPush g = gatherPush_;
        g.width = g.height = 0;
        g.headerLo = t.headerLo;
        g.headerHi = t.headerHi;
        batch.dispatch(gather_, &g, sizeof(g), 1, 1, 1, "warm-up");
    }

private:
    const Scene& scene_;
    PhotonMap map_;
    gpu::ComputePipeline trace_, gather_;
    shader::PhotonTracePush tracePush_{};
    shader::GatherPush gatherPush_{};
    uint64_t lastStored_ = 0;
};

}  // namespace

std::unique_ptr<SamplePasses> makePhotonPasses(gpu::Context& context, const Scene& scene, const RenderPlan& plan,
                                               const RenderBuffers& buffers, uint32_t seed) {
    return std::make_unique<PhotonPasses>(context, scene, plan, buffers, seed);
}

}  // namespace telescope
