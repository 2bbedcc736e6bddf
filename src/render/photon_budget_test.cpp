// scene/photon_budget.h against the renderer's own block levels: many time-limited "renders"
// simulated pass by pass with the level stream of photonBlockLevel (one seed each), their overruns
// (finish-block) and the levels of their completed blocks (deadline) against the renewal sums.
// Control: the theory of a mis-specified pmf fails the same bounds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "render/sample_passes.h"
#include "scene/photon_budget.h"

using namespace telescope;

namespace {

struct Simulated {
    std::vector<double> overruns;          // finish-block, passes
    std::vector<double> completedByLevel;  // deadline: completed blocks per level, all renders
    double completed = 0.0;
};

Simulated simulate(const DebiasSettings& d, uint64_t budget, uint32_t renders) {
    Simulated s;
    s.completedByLevel.assign(d.photon.levelCap, 0.0);
    for (uint32_t seed = 1; seed <= renders; ++seed) {
        uint64_t t = 0;
        for (uint64_t block = 0; t < budget; ++block) {
            const uint32_t level = photonBlockLevel(d, block, seed);
            t += uint64_t(std::pow(double(d.photon.photonGrowth), double(level)) + 0.5);
            if (t <= budget) {
                s.completedByLevel[level] += 1.0;
                s.completed += 1.0;
            }
        }
        s.overruns.push_back(double(t - budget));
    }
    return s;
}

struct Check {
    double worstZ = 0.0;  // largest |empirical - predicted| / its binomial standard error
};

Check compare(const Simulated& s, const PhotonBudget& b) {
    Check c;
    const double n = double(s.overruns.size());
    auto z = [&](double empirical, double predicted, double count) {
        const double se = std::sqrt(std::max(predicted * (1.0 - predicted), 1.0 / count) / count);
        return std::abs(empirical - predicted) / se;
    };
    for (double fraction : {0.0, 0.1, 0.5, 1.0, 3.0}) {
        const double x = std::floor(fraction * b.budgetPasses);
        double above = 0.0;
        for (double o : s.overruns) above += o > x ? 1.0 : 0.0;
        c.worstZ = std::max(c.worstZ, z(above / n, b.overrunAbove(x), n));
    }
    // Level shares of the completed blocks (deadline): rho_k p(k) against the counts.
    for (uint32_t k = 0; k < 4; ++k) {
        const double share = s.completedByLevel[k] / s.completed;
        const double predicted = b.levels[k].deadlineWeight * b.levels[k].probability;
        c.worstZ = std::max(c.worstZ, z(share, predicted, s.completed));
    }
    return c;
}

}  // namespace

TEST(PhotonBudget, OverrunsAndDeadlineLevelsMatchTheRenderersBlocks) {
    DebiasSettings d;
    d.estimator = DebiasEstimator::SingleTerm;
    d.schedule = LevelSchedule::Uniform;
    d.pmf.r = 0.7f;
    for (uint64_t budget : {20u, 200u}) {
        const Simulated s = simulate(d, budget, 4000);
        const PhotonBudget b = photonBudget(photonBlockDesign(d), budget);
        // 5 overrun probabilities and 4 level shares: 5 standard errors is a false-alarm rate
        // below 1e-5 for the nine (the level counts are close to binomial; the blocks of one
        // render are nearly independent draws).
        const Check good = compare(s, b);
        PhotonBlockDesign wrong = photonBlockDesign(d);
        wrong.r = 0.6;
        const Check control = compare(s, photonBudget(wrong, budget));
        std::printf("budget %llu passes: worst z %.2f, control (r 0.6) %.2f\n", (unsigned long long)budget, good.worstZ,
                    control.worstZ);
        EXPECT_LT(good.worstZ, 5.0) << "budget " << budget;
        EXPECT_GT(control.worstZ, 5.0) << "the control (r 0.6) passed at " << budget;
        // Blocks started (finish-block) and completed (deadline) per render.
        const double completedPerRender = s.completed / 4000.0;
        EXPECT_LT(b.expectedBlocksDeadline, b.expectedBlocks);
        EXPECT_NEAR(b.expectedBlocksDeadline, completedPerRender, 0.05 * completedPerRender);
    }
}

TEST(PhotonBudget, LongBudgetsLoseLittleAtTheDeadlineAndShortOnesLoseTheHighLevels) {
    // rho_k: 0 for blocks longer than the budget; close to 1 for short blocks of long budgets.
    const PhotonBlockDesign d{0.7, std::sqrt(0.5), 3, 20};
    const PhotonBudget shortBudget = photonBudget(d, 10);
    EXPECT_EQ(shortBudget.levels[3].deadlineWeight, 0.0) << "a 27-pass block never finishes within 10 passes";
    EXPECT_GT(shortBudget.levels[0].deadlineWeight, 1.0);
    const PhotonBudget longBudget = photonBudget(d, 100000);
    EXPECT_NEAR(longBudget.levels[0].deadlineWeight, 1.0, 0.01);
    EXPECT_LT(longBudget.deadlineBias, shortBudget.deadlineBias);
    EXPECT_GT(longBudget.deadlineBias, longBudget.truncationBias);
    // Beyond the exact range the renewal rate is used: continuous across the boundary.
    const PhotonBudget atLimit = photonBudget(d, kPhotonBudgetExactPasses);
    const PhotonBudget beyond = photonBudget(d, kPhotonBudgetExactPasses + 1000);
    EXPECT_NEAR(beyond.expectedBlocks - atLimit.expectedBlocks, 1000.0 / atLimit.expectedPasses,
                0.05 * 1000.0 / atLimit.expectedPasses);
}
