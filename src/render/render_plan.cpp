#include "render/render_plan.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "render/sample_passes.h"
#include "scene/scene_loader.h"
#include "shared/gpu_types.h"

namespace telescope {

std::string pmfDescription(const PmfSettings& pmf) {
    // The same text every output uses for the pmf (plan, EXR metadata, --stats-json).
    if (pmf.type == PmfType::Auto) return "auto pmf (pilot)";
    if (pmf.type == PmfType::Geometric) return fmt::format("geometric pmf, r = {:g}", pmf.r);
    return fmt::format("power-law pmf, alpha = {:g}", pmf.alpha);
}

uint32_t filterConstant(const Camera& camera) { return uint32_t(camera.filter); }

const PassInfo& passInfo(PassKind kind) {
    for (const PassInfo& p : kPassTable)
        if (p.kind == kind) return p;
    throw std::logic_error("a pass kind missing from kPassTable");
}

PlannedPass plannedPass(PassKind kind, std::string why) {
    const PassInfo& info = passInfo(kind);
    return PlannedPass{kind, info.name, info.shader, std::move(why), false};
}

const PlannedPass& plannedEntry(const RenderPlan& plan, PassKind kind) {
    for (const PlannedPass& p : plan.passes)
        if (!p.pilot && p.kind == kind) return p;
    throw std::logic_error(fmt::format("the plan has no {} pass", passName(kind)));
}

namespace {

const shader::SpecConstantInfo& specRow(uint32_t id) {
    const shader::SpecConstantInfo* row = shader::specConstantInfo(id);
    if (!row) throw std::logic_error(fmt::format("specialisation constant {} is not in shared/spec_constants.h", id));
    return *row;
}

std::string specValueText(const shader::SpecConstantInfo& row, uint32_t value) {
    const std::string type = row.type;
    if (type == "bool") return value ? "true" : "false";
    if (type == "float") return fmt::format("{:g}", gpu::floatOfSpec(value));
    if (value == 0xffffffffu) return "0xffffffff";
    return fmt::format("{}", value);
}

}  // namespace

std::string describeSpecialisation(const std::vector<gpu::SpecConstant>& spec) {
    std::vector<gpu::SpecConstant> sorted = spec;
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
    std::string s;
    for (const gpu::SpecConstant& c : sorted) {
        const shader::SpecConstantInfo& row = specRow(c.id);
        s += fmt::format("  {:<2} {:<19} {:<10} {}\n", c.id, row.name, specValueText(row, c.value), row.why);
    }
    return s;
}

uint32_t specValue(const std::vector<gpu::SpecConstant>& spec, uint32_t id) {
    for (const gpu::SpecConstant& c : spec)
        if (c.id == id) return c.value;
    throw std::logic_error(fmt::format("the pipeline does not set {}", specRow(id).name));
}

FeatureSwitch specSwitch(const std::vector<gpu::SpecConstant>& spec, const char* name, uint32_t id,
                         const std::string& offWhy, uint32_t offValue, const std::string& onWhy) {
    const shader::SpecConstantInfo& row = specRow(id);
    const uint32_t value = specValue(spec, id);
    const bool on = value != offValue;
    const std::string why = !on ? offWhy : onWhy.empty() ? std::string(row.why) : onWhy;
    return {name, on, fmt::format("{} ({} = {})", why, row.name, specValueText(row, value))};
}

std::vector<FeatureSwitch> sceneFeatureSwitches(const std::vector<gpu::SpecConstant>& spec, const SceneFeatures& f) {
    using namespace shader;
    return {
        specSwitch(spec, "spheres", kSpecHasSpheres, "no sphere primitives"),
        specSwitch(spec, "disks", kSpecHasDisks, "no disk primitives"),
        specSwitch(spec, "specular", kSpecHasSpecular, "no mirror, dielectric or conductor materials"),
        specSwitch(spec, "textures", kSpecHasTextures, "no textured materials"),
        specSwitch(spec, "smooth normals", kSpecSmoothNormals, "every triangle flat-shaded"),
        specSwitch(spec, "interfaces", kSpecTieRanks, "no refracting dielectric or medium boundary", 0,
                   "refracting dielectrics or medium boundaries present: a surface coinciding with one is hit first"),
        specSwitch(spec, "uniform scene", kSpecSceneInUniforms,
                   f.fitsUniforms ? "BVH walks read the scene from uniform texel buffers, which lavapipe gathers faster (the "
                                    "uniform scene serves brute-force rays)"
                                  : "more than 1024 BVH nodes or 1024 primitives: read from uniform texel buffers (from "
                                    "storage buffers on devices whose texel limit the scene exceeds)"),
        specSwitch(spec, "uniform tables", kSpecTablesInUniforms,
                   fmt::format("more than {} materials, {} lights or {} media: read from storage buffers",
                               kMaxUniformMaterials, kMaxUniformLights, kMaxUniformMedia)),
        specSwitch(spec, "brute-force rays", kSpecBruteForcePrims,
                   fmt::format("BVH traversal over {} primitives (brute force takes at most {} in the path tracer, {} "
                               "in the photon passes, in uniform buffers)",
                               f.primCount, kMaxBruteForcePathPrims, kMaxBruteForcePrims),
                   0, "every ray tests the scene's primitives in turn, no BVH walk"),
    };
}

RenderPlan makeRenderPlan(const Scene& scene, const SceneFeatures& f, const PlanOptions& options) {
    const uint32_t pilotLevel = options.pilotLevel;
    const PilotKind pilotKind = options.pilotKind;
    RenderPlan plan;
    if (pilotLevel != kNoPilotLevel && usesPhotons(scene.integrator))
        throw std::logic_error("the pmf pilot runs the path tracer only");
    if (pilotLevel != kNoPilotLevel && pilotKind == PilotKind::Transmittance &&
        scene.integrator.transmittance.type != TransmittanceEstimatorType::DebiasedRayMarch)
        throw std::logic_error("the transmittance pmf pilot runs debiased ray marching only");
    plan.pilotLevel = pilotLevel;
    plan.pilotKind = pilotKind;
    if (usesPhotons(scene.integrator)) planPhotons(scene, f, plan);
    else planPathTrace(scene, f, plan);
    return plan;
}

std::string describePlan(const Scene& scene, const RenderPlan& plan) {
    std::string s = fmt::format("scene: {}\nintegrator: {}\n", scene.path, plan.estimator);
    if (plan.pilotLevel == kNoPilotLevel && !usesPhotons(scene.integrator) &&
        scene.integrator.debias.estimator != DebiasEstimator::None) {
        const PmfSettings& p = scene.integrator.debias.pmf;
        s += fmt::format("path-depth pmf: {}; {}\n", pmfDescription(p),
                         p.type == PmfType::Auto ? "chosen by a pilot before the render (see below)" : p.origin);
        if (scene.integrator.debias.testPmfWeight != 1.0f)
            s += fmt::format("TEST ONLY: every 1 / p(j) scaled by {:g} (test_pmf_weight): a biased estimator\n",
                             scene.integrator.debias.testPmfWeight);
    }
    if (usesPhotons(scene.integrator) && scene.integrator.debias.estimator != DebiasEstimator::None)
        s += fmt::format("photon level pmf: {}; {}\n", pmfDescription(scene.integrator.debias.pmf),
                         scene.integrator.debias.pmf.origin);
    if (!scene.media.empty() && scene.integrator.transmittance.type == TransmittanceEstimatorType::DebiasedRayMarch)
        s += fmt::format("transmittance pmf: {}; {}\n", pmfDescription(scene.integrator.transmittance.pmf),
                         scene.integrator.transmittance.pmf.type == PmfType::Auto
                             ? "chosen by a pilot before the render (see below)"
                             : scene.integrator.transmittance.pmf.origin);
    s += "passes, per batch of samples:\n";
    for (const auto& p : plan.passes) {
        s += fmt::format("  {:<16} {}\n", p.name, p.why);
        s += fmt::format("  {:<16} runs {}.comp; binds {}\n", "", p.shader, passInfo(p.kind).bindings);
    }
    s += "not scheduled:\n";
    for (const auto& p : plan.skipped) s += fmt::format("  {:<16} {}\n", p.name, p.why);
    s += fmt::format("compiled into the {} pipeline{}:\n", plan.featuresOf,
                     plan.featuresOf.find(' ') == std::string::npos ? "" : "s");
    for (const auto& f : plan.features) s += fmt::format("  {:<19} {:<4} {}\n", f.name, f.on ? "on" : "off", f.why);
    // The values themselves, named by the table of shader features (shared/spec_constants.h).
    if (!plan.pathTraceSpec.empty())
        s += fmt::format("specialisation of {} (the scene's values; a device may change the loop budget and the "
                         "scene's bindings):\n{}",
                         plannedEntry(plan, PassKind::PathTrace).shader, describeSpecialisation(plan.pathTraceSpec));
    if (!plan.photonSpec.empty())
        s += fmt::format("specialisation of photon_trace and gather (as above):\n{}", describeSpecialisation(plan.photonSpec));
    if (!scene.ignoredKeys.empty()) {
        s += "ignored scene keys:\n";
        for (const auto& k : scene.ignoredKeys) {
            const std::string why = ignoredKeyReason(k);
            s += fmt::format("  {:<36} {}\n", k, why.empty() ? "unknown to Telescope" : why);
        }
    }
    return s;
}

}  // namespace telescope
