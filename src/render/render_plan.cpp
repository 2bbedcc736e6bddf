#include "render/render_plan.h"

#include <algorithm>

#include <fmt/format.h>

#include "render/sample_passes.h"
#include "shared/gpu_types.h"

namespace telescope {

std::string pmfDescription(const PmfSettings& pmf) {
    if (pmf.type == PmfType::Auto) return "auto pmf (pilot)";
    if (pmf.type == PmfType::Geometric) return fmt::format("geometric pmf, r = {:g}", pmf.r);
    return fmt::format("power-law pmf, alpha = {:g}", pmf.alpha);
}

uint32_t filterConstant(const Camera& camera) {
    return camera.filter == "dirac" ? shader::kFilterDirac : camera.filter == "box" ? shader::kFilterBox : shader::kFilterTent;
}

RenderPlan makeRenderPlan(const Scene& scene, const SceneFeatures& f) {
    RenderPlan plan;
    if (usesPhotons(scene.integrator)) planPhotons(scene, f, plan);
    else planPathTrace(scene, f, plan);
    return plan;
}

std::string describePlan(const Scene& scene, const RenderPlan& plan) {
    std::string s = fmt::format("scene: {}\nintegrator: {}\n", scene.path, plan.estimator);
    s += "passes, per batch of samples:\n";
    for (const auto& p : plan.passes) s += fmt::format("  {:<16} {}\n", p.name, p.why);
    s += "not scheduled:\n";
    for (const auto& p : plan.skipped) s += fmt::format("  {:<16} {}\n", p.name, p.why);
    s += fmt::format("compiled into the {} pipeline{}:\n", plan.featuresOf,
                     plan.featuresOf.find(' ') == std::string::npos ? "" : "s");
    for (const auto& f : plan.features) s += fmt::format("  {:<16} {:<4} {}\n", f.name, f.on ? "on" : "off", f.why);
    if (!scene.ignoredKeys.empty()) {
        s += "ignored scene keys:\n";
        for (const auto& k : scene.ignoredKeys) s += "  " + k + "\n";
    }
    return s;
}

}  // namespace telescope
