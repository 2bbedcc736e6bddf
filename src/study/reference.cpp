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
    s.overrides.push_back({"integrator.debias", R"({"estimator":"sum","pmf":{"type":"geometric","r":0.65}})"});
    s.why = fmt::format("added the sum estimator over path depth beyond max_bounces = {} (geometric pmf, r = 0.65)",
                        in.maxBounces);
    return s;
}

}  // namespace telescope
