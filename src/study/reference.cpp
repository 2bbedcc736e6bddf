#include "study/reference.h"

#include <fmt/format.h>

namespace telescope {

UnbiasedSetup unbiasedSetup(const Scene& scene) {
    UnbiasedSetup s;
    const IntegratorSettings& in = scene.integrator;
    // Biased ray-marched transmittance becomes debiased marching at the same base level.
    if (!scene.media.empty() && in.transmittance.type == TransmittanceEstimatorType::RayMarch) {
        s.overrides.push_back({"integrator.transmittance_estimator",
                               fmt::format(R"({{"type":"debiased_ray_march","level":{}}})", in.transmittance.level)});
        s.why = fmt::format("transmittance by debiased ray marching (base level {}) instead of biased ray marching; ",
                            in.transmittance.level);
    }
    if (usesPhotons(in)) {
        // Not unbiased photon mapping: its per-pixel error has a 1/z tail and does not shrink with
        // passes (docs/PHOTON-MAPPING.md). The path tracer with the sum estimator over path depth
        // renders the same light transport; the photon keys are ignored (and listed).
        s.overrides.push_back({"integrator.type", R"("path_tracer")"});
        s.overrides.push_back({"integrator.debias", R"({"estimator":"sum","pmf":{"type":"geometric","r":0.65}})"});
        s.why += fmt::format("photon scene: rendered by the path tracer with the sum estimator over path depth beyond "
                             "max_bounces = {} (unbiased photon mapping does not converge in practice, "
                             "docs/PHOTON-MAPPING.md)",
                             in.maxBounces);
        return s;
    }
    if (in.debias.estimator != DebiasEstimator::None) {
        s.why += "the integrator's debias block already makes it unbiased";
        return s;
    }
    s.overrides.push_back({"integrator.debias", R"({"estimator":"sum","pmf":{"type":"geometric","r":0.65}})"});
    s.why += fmt::format("added the sum estimator over path depth beyond max_bounces = {} (geometric pmf, r = 0.65)",
                        in.maxBounces);
    return s;
}

}  // namespace telescope
