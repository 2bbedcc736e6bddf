// The variance and cost prediction behind pmf "auto", against closed forms for a correction whose
// second moment decays geometrically: E[D_m^2] = rho^m, cost c per path at every level.
#include "study/pmf_pilot.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace telescope;

namespace {

PmfPilotResult syntheticPilot(double rho, double cost, uint32_t levels, double baseVariance) {
    PmfPilotResult pilot;
    for (uint32_t m = 0; m < levels; ++m) pilot.levels.push_back({m, std::pow(rho, double(m)), cost});
    pilot.tailDecay = rho;
    pilot.tailCostSlope = 0.0;
    pilot.baseVariance = baseVariance;
    return pilot;
}

PmfSettings geometric(float r) {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = r;
    return p;
}

}  // namespace

TEST(PmfPilot, SingleTermPredictionMatchesTheClosedForm) {
    // sum_m rho^m / (r (1-r)^m) = 1 / (r (1 - rho / (1-r))) for rho < 1 - r.
    const double rho = 0.3, base = 0.25;
    const PmfPilotResult pilot = syntheticPilot(rho, 2e-6, 8, base);
    for (float r : {0.2f, 0.4f, 0.6f}) {
        const PmfCandidate c = predictPmf(pilot, geometric(r), DebiasEstimator::SingleTerm);
        const double expected = base + 1.0 / (double(r) * (1.0 - rho / (1.0 - double(r))));
        EXPECT_NEAR(c.variance / expected, 1.0, 1e-5) << "r = " << r;
        EXPECT_NEAR(c.cost / 2e-6, 1.0, 1e-5) << "r = " << r;
    }
}

TEST(PmfPilot, SumPredictionMatchesTheClosedForm) {
    // sum_m rho^m / (1-r)^m = 1 / (1 - rho / (1-r)).
    const double rho = 0.3;
    const PmfPilotResult pilot = syntheticPilot(rho, 1.0, 8, 0.0);
    const PmfCandidate c = predictPmf(pilot, geometric(0.5f), DebiasEstimator::Sum);
    EXPECT_NEAR(c.variance, 1.0 / (1.0 - rho / 0.5), 1e-5);
}

TEST(PmfPilot, InfiniteVarianceIsPredictedWhenThePmfDecaysFasterThanTheMoments) {
    // (1 - r) <= rho: the terms rho^m / (1-r)^m do not decay.
    const PmfPilotResult pilot = syntheticPilot(0.55, 1.0, 8, 0.0);
    EXPECT_FALSE(std::isfinite(predictPmf(pilot, geometric(0.65f), DebiasEstimator::SingleTerm).product()));
    EXPECT_TRUE(std::isfinite(predictPmf(pilot, geometric(0.3f), DebiasEstimator::SingleTerm).product()));
}

TEST(PmfPilot, RisingCostShiftsTheOptimumToLighterTails) {
    // With cost growing per level, the best geometric r is larger than with constant cost.
    auto bestR = [](double slope) {
        PmfPilotResult pilot = syntheticPilot(0.3, 1.0, 8, 0.0);
        for (auto& l : pilot.levels) l.secondsPerPath = 1.0 + slope * l.level;
        pilot.tailCostSlope = slope;
        float best = 0.0f;
        double bestProduct = INFINITY;
        for (int i = 2; i <= 98; ++i) {
            const double p = predictPmf(pilot, geometric(float(i) / 100.0f), DebiasEstimator::SingleTerm).product();
            if (p < bestProduct) bestProduct = p, best = float(i) / 100.0f;
        }
        return best;
    };
    EXPECT_LT(bestR(0.0), bestR(2.0));
}
