// The pmf recipe of docs/ESTIMATORS.md section 1: a short pilot measures, per level j, the second
// moment of the correction E[D_j^2] and the cost c_j of a sample at that level on the device; the
// pmf is then the member of the geometric or power-law family that minimises the predicted
// (variance x cost) of the single-term estimator,
//     V(p) = V_base + sum_j E[D_j^2] / p(j),     C(p) = sum_j p(j) c_j,
// (for the sum estimator p(j) in V is replaced by P(N >= j), covariances left out).
// The ideal unconstrained pmf, p(j) proportional to sqrt(E[D_j^2] / c_j) (Rhee and Glynn 2015),
// is reported beside it. Second moments are weighted per pixel by 1 / (base^2 + 1e-2), the
// weighting of the relative MSE that `telescope converge` measures.
//
// The model behind the prediction is deliberately pessimistic about the tail, because the two
// mistakes cost very differently: a pmf whose tail is too heavy wastes a constant factor, one whose
// tail is too light has infinite variance (E[D^2]/p(j) stops decaying). A few pilot samples
// underestimate the deep levels' second moments (their corrections are rare and large), so
//   - E[D_j^2] is fitted by a line in log space over the measured levels, each level weighted by
//     its measured relative standard error, and the tail beyond them decays at the fit's upper
//     confidence bound (two standard errors);
//   - a measured level below the fitted line is replaced by the line (never lowered);
//   - the cost of a level is a + b (rays per path), fitted on the measured levels; rays per path
//     beyond them grow by increments that shrink at the measured survival ratio (constant for a
//     closed, lossless scene), up to the tracer's depth cap.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gpu/context.h"
#include "render/render_plan.h"
#include "render/resolved_scene.h"
#include "scene/scene.h"

namespace telescope {

struct PilotLevel {
    uint32_t level = 0;          // m = j - k
    double secondMoment = 0.0;   // weighted E[D_j^2]
    double secondsPerPath = 0.0; // GPU time of one sample at this level
    double relativeError = 0.0;  // standard error of secondMoment / secondMoment (pixel spread)
    double raysPerPath = 0.0;    // rays traced by one sample at this level
};

// The fitted model the prediction extrapolates with (fitPilotModel).
struct PilotModel {
    double rayCap = 4096.0;  // rays (or points) per path at most: the tracer's depth cap
    std::vector<double> secondMoment;  // per measured level: max(measured, fitted line)
    double decay = 0.0;       // fitted E[D_{m+1}^2] / E[D_m^2]
    double decayUpper = 0.0;  // its upper bound (two standard errors), used beyond the levels
    double costIntercept = 0.0, costPerRay = 0.0;  // seconds per path = a + b rays
    std::vector<double> rays;  // rays per path per measured level (non-decreasing)
    double raySurvival = 0.0;  // ratio of successive ray increments beyond the measured levels
    uint32_t levelCap = 0;     // levels beyond this add nothing (the tracer's depth cap)
    double secondMomentAt(uint32_t m) const;
    double logSecondMomentAt(uint32_t m) const;  // -inf where E[D^2] is 0
    double costAt(uint32_t m) const;
};

struct PmfCandidate {
    PmfSettings pmf;
    double variance = 0.0;  // predicted V(p)
    double cost = 0.0;      // predicted C(p), GPU seconds per path
    double product() const { return variance * cost; }
};

struct PmfPilotResult {
    PilotKind kind = PilotKind::PathDepth;  // whose pmf: path depth or debiased ray marching
    std::vector<PilotLevel> levels;         // for transmittance, raysPerPath = points per estimate
    double baseVariance = 0.0;     // weighted variance of the base I(k) per sample
    uint32_t levelCap = 4096;      // deepest level that can contribute (set by the pilot)
    double maxRaySurvival = 1.0;   // path depth: ray increments shrink; marching: points double
    double rayCap = 4096.0;        // the cost coordinate's cap (path depth: the tracer's depth cap)
    PilotModel model;              // fitPilotModel
    std::vector<double> idealPmf;  // sqrt(E[D_j^2]/c_j), normalised over the measured levels
    PmfCandidate chosen, geometricDefault, powerLawDefault;
    double pilotGpuSeconds = 0.0;
    double pilotWallSeconds = 0.0;  // render time only: pipeline compilation is left out, as for
                                    // every method's renderer in `telescope converge`

    std::string summary() const;  // a few lines for logs and reports
};

// Runs the pilot for the scene's debiased integrator (its pmf settings give pilot_spp and
// pilot_levels) and returns the measurements and the chosen pmf.
PmfPilotResult runPmfPilot(gpu::Context& context, const Scene& scene, uint32_t seed);

// The same recipe for debiased ray marching's level pmf (integrator.transmittance_estimator):
// per level m = j - k, pilot_spp samples per pixel are rendered twice with every transmittance
// estimate at the fixed level j, the correction weighted once by 1 and once by 2, with the same
// random numbers and no Russian roulette. Per sample, the difference of the two is the path's
// unweighted correction D_j (to first order in the corrections when a path holds several
// estimates) and twice the first minus the second its base. Paths are traced to the base depth
// k only (a path-depth telescope is off in the pilot). The cost coordinate is the number of
// points per estimate, 2^(j+1); levels beyond kTrMaxCombLog2 are truncated as in the shader.
PmfPilotResult runTransmittancePmfPilot(gpu::Context& context, const Scene& scene, uint32_t seed);

// Fits pilot.model from pilot.levels (exposed for tests).
void fitPilotModel(PmfPilotResult& pilot);

// The prediction of V(p) and C(p) from the fitted model (exposed for tests).
PmfCandidate predictPmf(const PmfPilotResult& pilot, const PmfSettings& pmf, DebiasEstimator estimator);

// Fits the model and fills the ideal pmf, the two defaults' predictions and the chosen pmf: the
// geometric r or power-law alpha (0.02 to 0.98) with the smallest predicted variance x cost.
void choosePmf(PmfPilotResult& pilot, DebiasEstimator estimator);

// Resolves every pmf "auto" of the scene (debiased ray marching's pmf, then the path-depth pmf,
// whose pilot so renders with the transmittance pmf the render will use): runs each one's pilot
// (seeded from `seed`) and puts the chosen pmf in the scene. `pilots` are those that ran, in that
// order (none when the scene has no "auto"). A transmittance "auto" in a scene without media has
// nothing to measure and becomes the default pmf (it cannot change the image).
struct Resolution {
    ResolvedScene scene;
    std::vector<PmfPilotResult> pilots;
};
Resolution resolveScene(gpu::Context& context, Scene scene, uint32_t seed);

}  // namespace telescope
