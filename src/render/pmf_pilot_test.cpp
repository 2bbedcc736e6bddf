// pmf "auto": the variance and cost prediction against closed forms, the fit of the pilot's
// measurements, and the recipe's robustness to the pilot's own noise (simulated pilots whose
// deep levels see few, large corrections).
#include "render/pmf_pilot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace telescope;

namespace {

// A model given directly: E[D_m^2] = rho^m, cost c per path at every level.
PmfPilotResult exactModel(double rho, double cost, uint32_t levels, double baseVariance) {
    PmfPilotResult pilot;
    pilot.baseVariance = baseVariance;
    for (uint32_t m = 0; m < levels; ++m) {
        pilot.levels.push_back({m, std::pow(rho, double(m)), cost, 0.0, 1.0});
        pilot.model.secondMoment.push_back(std::pow(rho, double(m)));
        pilot.model.rays.push_back(1.0);
    }
    pilot.model.decay = pilot.model.decayUpper = rho;
    pilot.model.costIntercept = cost;
    pilot.model.levelCap = pilot.levelCap;
    return pilot;
}

PmfSettings geometric(float r) {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = r;
    return p;
}

PmfSettings powerLaw(float alpha) {
    PmfSettings p;
    p.type = PmfType::PowerLaw;
    p.alpha = alpha;
    return p;
}

}  // namespace

TEST(PmfPilot, SingleTermPredictionMatchesTheClosedForm) {
    // sum_m rho^m / (r (1-r)^m) = 1 / (r (1 - rho / (1-r))) for rho < 1 - r.
    const double rho = 0.3, base = 0.25;
    const PmfPilotResult pilot = exactModel(rho, 2e-6, 8, base);
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
    const PmfPilotResult pilot = exactModel(rho, 1.0, 8, 0.0);
    const PmfCandidate c = predictPmf(pilot, geometric(0.5f), DebiasEstimator::Sum);
    EXPECT_NEAR(c.variance, 1.0 / (1.0 - rho / 0.5), 1e-5);
}

TEST(PmfPilot, InfiniteVarianceIsPredictedWhenThePmfDecaysFasterThanTheMoments) {
    // (1 - r) < rho: the terms rho^m / (1-r)^m grow, up to the depth cap.
    const PmfPilotResult pilot = exactModel(0.55, 1.0, 8, 0.0);
    EXPECT_FALSE(std::isfinite(predictPmf(pilot, geometric(0.65f), DebiasEstimator::SingleTerm).product()));
    EXPECT_TRUE(std::isfinite(predictPmf(pilot, geometric(0.3f), DebiasEstimator::SingleTerm).product()));
    EXPECT_TRUE(std::isfinite(predictPmf(pilot, powerLaw(2.0f / 3.0f), DebiasEstimator::SingleTerm).product()));
}

TEST(PmfPilot, CostGrowingWithRaysShiftsTheOptimumToLighterTails) {
    // A closed, lossless scene: every level traces one more ray.
    auto best = [](double costPerRay) {
        PmfPilotResult pilot = exactModel(0.3, 1.0, 8, 0.0);
        for (uint32_t m = 0; m < 8; ++m) pilot.model.rays[m] = 1.0 + m;
        pilot.model.raySurvival = 1.0;
        pilot.model.costPerRay = costPerRay;
        float bestR = 0.0f;
        double bestProduct = INFINITY;
        for (int i = 2; i <= 98; ++i) {
            const double p = predictPmf(pilot, geometric(float(i) / 100.0f), DebiasEstimator::SingleTerm).product();
            if (p < bestProduct) bestProduct = p, bestR = float(i) / 100.0f;
        }
        return bestR;
    };
    EXPECT_LT(best(0.0), best(2.0));
}

TEST(PmfPilot, ClosedSceneCostGrowsLinearlyAndSaturatesWhenPathsDie) {
    PmfPilotResult pilot = exactModel(0.3, 1.0, 8, 0.0);
    pilot.model.costIntercept = 1.0;
    pilot.model.costPerRay = 0.5;
    for (uint32_t m = 0; m < 8; ++m) pilot.model.rays[m] = 2.0 + m;
    pilot.model.raySurvival = 1.0;
    EXPECT_NEAR(pilot.model.costAt(20), 1.0 + 0.5 * 22.0, 1e-9);
    EXPECT_NEAR(pilot.model.costAt(100000), 1.0 + 0.5 * 4096.0, 1e-9);  // the tracer's depth cap
    // Increments 1/2, 1/4, ...: rays approach 2 + 1 = 3.
    for (uint32_t m = 0; m < 8; ++m) pilot.model.rays[m] = 3.0 - std::ldexp(1.0, -int(m));
    pilot.model.raySurvival = 0.5;
    EXPECT_NEAR(pilot.model.costAt(9), 1.0 + 0.5 * (3.0 - std::ldexp(1.0, -9)), 1e-9);
    EXPECT_NEAR(pilot.model.costAt(4000), 1.0 + 0.5 * 3.0, 1e-9);
}

TEST(PmfPilot, FitRecoversExactMeasurements) {
    PmfPilotResult pilot;
    for (uint32_t m = 0; m < 8; ++m) {
        const double rays = 3.0 - std::pow(0.6, double(m));
        pilot.levels.push_back({m, 0.2 * std::pow(0.4, double(m)), 1e-6 + 2e-7 * rays, 0.01, rays});
    }
    fitPilotModel(pilot);
    EXPECT_NEAR(pilot.model.decay, 0.4, 1e-6);
    EXPECT_GE(pilot.model.decayUpper, 0.4);
    EXPECT_LE(pilot.model.decayUpper, 0.42);  // two standard errors of a well-measured line
    EXPECT_NEAR(pilot.model.costPerRay, 2e-7, 1e-12);
    EXPECT_NEAR(pilot.model.costIntercept, 1e-6, 1e-12);
    EXPECT_NEAR(pilot.model.raySurvival, 0.6, 1e-6);
    for (uint32_t m = 0; m < 8; ++m) EXPECT_NEAR(pilot.model.secondMomentAt(m) / pilot.levels[m].secondMoment, 1.0, 1e-6);
}

TEST(PmfPilot, LevelsBelowTheFittedLineAreRaisedNeverLowered) {
    PmfPilotResult pilot;
    for (uint32_t m = 0; m < 8; ++m) pilot.levels.push_back({m, std::pow(0.5, double(m)), 1e-6, 0.05, 3.0});
    pilot.levels[6].secondMoment = 0.0;                           // a rare correction never seen
    pilot.levels[3].secondMoment *= 4.0;                          // a lucky large one
    pilot.levels[3].relativeError = pilot.levels[6].relativeError = 0.9;
    fitPilotModel(pilot);
    EXPECT_GT(pilot.model.secondMomentAt(6), 0.5 * std::pow(0.5, 6.0));
    EXPECT_EQ(pilot.model.secondMomentAt(3), pilot.levels[3].secondMoment);
    EXPECT_GE(pilot.model.decayUpper, pilot.model.decay);
}

// The first version of the recipe, kept as the control of the test below: measured levels taken
// at face value, E[D^2] beyond them decaying at the ratio of an unweighted fit over the second
// half of the levels, the cost per path growing geometrically at its fitted rate.
PmfSettings firstRecipe(const PmfPilotResult& pilot) {
    const size_t n = pilot.levels.size(), half = n / 2;
    auto slope = [&](auto value) {
        double sx = 0, sy = 0, sxx = 0, sxy = 0, k = 0;
        for (size_t m = half; m < n; ++m) {
            const double v = value(pilot.levels[m]);
            if (!(v > 0.0)) continue;
            const double y = std::log(v);
            sx += double(m), sy += y, sxx += double(m * m), sxy += double(m) * y, k += 1;
        }
        return (k * sxy - sx * sy) / (k * sxx - sx * sx);
    };
    const double decay = std::min(0.999, std::exp(slope([](const PilotLevel& l) { return l.secondMoment; })));
    const double growth = std::max(0.0, std::expm1(slope([](const PilotLevel& l) { return l.secondsPerPath; })));
    auto product = [&](const PmfSettings& pmf) {
        double variance = pilot.baseVariance, cost = 0.0;
        for (uint32_t m = 0; m < 20000; ++m) {
            double p = pmf.type == PmfType::Geometric
                           ? pmf.r * std::pow(1.0 - pmf.r, double(m))
                           : std::pow(m + 1.0, pmf.alpha - 1.0) - std::pow(m + 2.0, pmf.alpha - 1.0);
            const size_t last = n - 1;
            const double m2 = m < n ? std::max(pilot.levels[m].secondMoment, 1e-30)
                                    : pilot.levels[last].secondMoment * std::pow(decay, double(m - last));
            const double c = m < n ? pilot.levels[m].secondsPerPath
                                   : pilot.levels[last].secondsPerPath * std::pow(1.0 + growth, double(m - last));
            const double dv = p > 0.0 ? m2 / p : (m2 > 0.0 ? INFINITY : 0.0);
            variance += dv;
            cost += p * c;
        }
        return variance * cost;
    };
    PmfSettings best = geometric(0.65f);
    double bestProduct = product(best);
    for (int i = 2; i <= 98; ++i)
        for (const PmfSettings& c : {geometric(float(i) / 100.0f), powerLaw(float(i) / 100.0f)})
            if (const double p = product(c); p < bestProduct) bestProduct = p, best = c;
    return best;
}

// Simulated pilots of a scene whose correction at level m is non-zero with probability
// q_m = q0 * 0.55^m and then has E[D_m^2] = 0.5^m: rare, large corrections at the deep levels,
// as in a Cornell box with a small light. The geometric default (r = 0.65) has infinite variance
// here. Across seeds, the pmf the recipe picks from a 4096-pixel, 4-sample pilot must be within
// 10% of the better default in true (variance x cost), and never of infinite variance.
// GPU timings jitter by several percent and rays per path saturate, as measured.
TEST(PmfPilot, ChosenPmfIsRobustToPilotNoise) {
    const double trueDecay = 0.5, hitDecay = 0.55, q0 = 0.05;
    // Given a hit, D^2 is hit x a Pareto variable of mean 1 and tail index 1.3 (infinite
    // variance): most pilots see less than the mean at the deep levels.
    const double kTail = 1.3, kParetoMean = (kTail - 1.0) / kTail;
    const uint32_t levels = 8, pixels = 4096, spp = 4;
    const PmfPilotResult truth = exactModel(trueDecay, 1e-6, levels, 0.2);
    const PmfCandidate truthPower = predictPmf(truth, powerLaw(2.0f / 3.0f), DebiasEstimator::SingleTerm);
    const PmfCandidate truthGeometric = predictPmf(truth, geometric(0.65f), DebiasEstimator::SingleTerm);
    ASSERT_FALSE(std::isfinite(truthGeometric.product()));
    int worse = 0, naiveWorse = 0;
    for (uint32_t seed = 1; seed <= 20; ++seed) {
        std::mt19937_64 rng(seed);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        std::normal_distribution<double> jitter;
        PmfPilotResult pilot;
        pilot.baseVariance = 0.2;
        for (uint32_t m = 0; m < levels; ++m) {
            const double q = q0 * std::pow(hitDecay, double(m));
            const double hit = std::pow(trueDecay, double(m)) / q;  // D^2 when non-zero
            double sum = 0.0, sumSq = 0.0;
            for (uint32_t p = 0; p < pixels; ++p) {
                double value = 0.0;
                for (uint32_t s = 0; s < spp; ++s)
                    if (u(rng) < q) value += hit * kParetoMean * std::pow(1.0 - u(rng), -1.0 / kTail) / spp;
                sum += value, sumSq += value * value;
            }
            // GPU timings jitter by several percent; rays per path saturate (paths escape).
            PilotLevel l{m, sum / pixels, 1e-6 * (1.0 + 0.08 * jitter(rng)), 0.0, 3.0 - std::ldexp(1.0, -int(m))};
            const double spread = std::sqrt(std::max(0.0, sumSq / pixels - l.secondMoment * l.secondMoment));
            l.relativeError = l.secondMoment > 0.0 ? spread / std::sqrt(double(pixels)) / l.secondMoment : 0.0;
            pilot.levels.push_back(l);
        }
        choosePmf(pilot, DebiasEstimator::SingleTerm);
        const PmfSettings naiveChoice = firstRecipe(pilot);
        const double trueProduct = predictPmf(truth, pilot.chosen.pmf, DebiasEstimator::SingleTerm).product();
        const double naiveProduct = predictPmf(truth, naiveChoice, DebiasEstimator::SingleTerm).product();
        EXPECT_TRUE(std::isfinite(trueProduct)) << "seed " << seed << ": chosen r " << pilot.chosen.pmf.r << ", alpha "
                                                << pilot.chosen.pmf.alpha << " (type " << int(pilot.chosen.pmf.type) << ")";
        if (!(trueProduct <= 1.1 * truthPower.product())) ++worse;
        if (!(naiveProduct <= 1.1 * truthPower.product())) ++naiveWorse;
    }
    EXPECT_EQ(worse, 0);
    // The test has the power to fail a recipe that trusts the pilot: the first recipe picks the
    // infinite-variance r = 0.65 for 2 of the 20 seeds.
    EXPECT_GE(naiveWorse, 1);
}
