#include "study/reference.h"

#include <fmt/format.h>

namespace telescope {

UnbiasedSetup unbiasedSetup(const Scene& scene) {
    UnbiasedSetup s;
    const IntegratorSettings& in = scene.integrator;
    if (in.debias.estimator != DebiasEstimator::None) {
        s.why = "the integrator's debias block already makes it unbiased";
        return s;
    }
    if (usesPhotons(in)) {
        // Unbiased photon mapping (ESTIMATORS.md section 3): single-term over radius levels with
        // the power-law pmf of the integrator's alpha; the path part stays as it is.
        s.overrides.push_back({"integrator.debias", R"({"estimator":"single_term"})"});
        s.why = fmt::format("added unbiased photon mapping (single-term over radius levels, power-law pmf with alpha = "
                            "{:g}) at base radius {:g}",
                            in.photon.alpha, in.photon.gatherRadius);
        return s;
    }
    s.overrides.push_back({"integrator.debias", R"({"estimator":"sum","pmf":{"type":"geometric","r":0.65}})"});
    s.why = fmt::format("added the sum estimator over path depth beyond max_bounces = {} (geometric pmf, r = 0.65)",
                        in.maxBounces);
    return s;
}

}  // namespace telescope
