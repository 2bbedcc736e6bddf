// The pmf recipe of ESTIMATORS.md section 1: a short pilot measures, per level j, the second
// moment of the correction E[D_j^2] and the cost c_j of a sample at that level on the device; the
// pmf is then the member of the geometric or power-law family that minimises the predicted
// (variance x cost) of the single-term estimator,
//     V(p) = V_base + sum_j E[D_j^2] / p(j),     C(p) = sum_j p(j) c_j,
// (for the sum estimator p(j) in V is replaced by P(N >= j), covariances left out),
// with the measured levels extended by a fitted tail (geometric decay of E[D_j^2], linear cost).
// The ideal unconstrained pmf, p(j) proportional to sqrt(E[D_j^2] / c_j) (Rhee and Glynn 2015),
// is reported beside it. Second moments are weighted per pixel by 1 / (base^2 + 1e-2), the
// weighting of the relative MSE that `telescope converge` measures.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gpu/context.h"
#include "scene/scene.h"

namespace telescope {

struct PilotLevel {
    uint32_t level = 0;          // m = j - k
    double secondMoment = 0.0;   // weighted E[D_j^2]
    double secondsPerPath = 0.0; // GPU time of one sample at this level
};

struct PmfCandidate {
    PmfSettings pmf;
    double variance = 0.0;  // predicted V(p)
    double cost = 0.0;      // predicted C(p), GPU seconds per path
    double product() const { return variance * cost; }
};

struct PmfPilotResult {
    std::vector<PilotLevel> levels;
    double baseVariance = 0.0;     // weighted variance of the base I(k) per sample
    double tailDecay = 0.0;        // fitted E[D_{j+1}^2] / E[D_j^2] beyond the measured levels
    double tailCostSlope = 0.0;    // fitted seconds per path added per level
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

// The prediction of V(p) and C(p) from pilot measurements (exposed for tests).
PmfCandidate predictPmf(const PmfPilotResult& pilot, const PmfSettings& pmf, DebiasEstimator estimator);

// When the scene asks for pmf "auto", runs the pilot and replaces the pmf by the chosen one;
// returns true (and the pilot in *result) when it did.
bool resolveAutoPmf(gpu::Context& context, Scene& scene, uint32_t seed, PmfPilotResult* result = nullptr);

}  // namespace telescope
