#include "study/reference.h"

#include <fmt/format.h>

namespace telescope {

namespace {

// The sum estimator over path depth with a geometric pmf, r = 0.65 (a fresh debias block).
DebiasSettings sumOverPathDepth() {
    DebiasSettings d;
    d.estimator = DebiasEstimator::Sum;
    d.pmf.type = PmfType::Geometric;
    d.pmf.r = 0.65f;
    d.pmf.origin = "set by `reference` (the sum estimator over path depth makes the reference unbiased)";
    return d;
}

}  // namespace

UnbiasedSetup unbiasedSetup(const Scene& scene) {
    UnbiasedSetup s;
    s.integrator = scene.integrator;
    IntegratorSettings& in = s.integrator;
    // Biased ray-marched transmittance becomes debiased marching at the same base level.
    if (!scene.media.empty() && in.transmittance.type == TransmittanceEstimatorType::RayMarch) {
        in.transmittance.type = TransmittanceEstimatorType::DebiasedRayMarch;
        in.transmittance.pmf = defaultTransmittancePmf();
        s.why = fmt::format("transmittance by debiased ray marching (base level {}) instead of biased ray marching; ",
                            in.transmittance.level);
    }
    if (usesPhotons(in)) {
        // Not unbiased photon mapping: its per-pixel error has a 1/z tail and does not shrink with
        // passes (docs/PHOTON-MAPPING.md). The path tracer with the sum estimator over path depth
        // renders the same light transport; the photon settings are left unused.
        in.type = IntegratorType::PathTracer;
        in.debias = sumOverPathDepth();
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
    in.debias = sumOverPathDepth();
    s.why += fmt::format("added the sum estimator over path depth beyond k = max_bounces - 1 = {} (geometric pmf, r = 0.65)",
                        pathDepthK(in));
    return s;
}

}  // namespace telescope
