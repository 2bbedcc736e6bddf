// What a time budget does to unbiased photon mapping's blocks (uniform schedule,
// docs/PHOTON-MAPPING.md "Time limits"). A level-k block costs C = m^k photon passes with
// probability p(k) (truncated to k < K); a render with a budget of B passes starts blocks while
// fewer than B passes have run. Blocks start at the renewal times of the block costs: u(t), the
// probability that a block starts at pass t, satisfies u(0) = 1, u(t) = sum_k p(k) u(t - m^k),
// and U(s) = sum_{t < s} u(t) counts the expected block starts before s. Then, exactly:
//   finish-block (the block running at B is finished):
//     overrun O = (end of the last block) - B,  P(O > x) = sum_{k: m^k > x} p(k) (U(B) - U(B + x - m^k + 1))
//     expected blocks U(B); by Wald's identity (the block count is a stopping time) the expected
//     count of level-k blocks is p(k) U(B): every level keeps its weight.
//   deadline (stop at B, the running block left out):
//     expected level-k blocks p(k) U(B - m^k + 1): level k keeps rho_k = U(B - m^k + 1) / E[N]
//     of its weight (E[N] = sum_k p(k) U(B - m^k + 1)), and levels with m^k > B never finish.
// For a smooth photon density the level-k correction is (s - 1) s^k times the base bias, so the
// image of the completed blocks keeps 1 - (1 - s) sum_k rho_k s^k of the base bias (both to first
// order: expected counts, not the expectation of their ratio).
#pragma once

#include <cstdint>
#include <vector>

#include "scene/scene.h"

namespace telescope {

struct PhotonBlockDesign {
    double r = 0.7;          // p(k) ~ r (1 - r)^k
    double areaRatio = 0.5;  // s
    uint32_t growth = 3;     // m
    uint32_t levelCap = 10;  // K
};

struct PhotonBudgetLevel {
    uint32_t level = 0;
    double passes = 0.0;          // m^k
    double probability = 0.0;     // p(k), truncated
    double deadlineWeight = 0.0;  // rho_k (finish-block: 1)
};

struct PhotonBudget {
    double budgetPasses = 0.0;
    double expectedPasses = 0.0;        // per block
    double expectedBlocks = 0.0;        // finish-block: U(B)
    double expectedBlocksDeadline = 0.0;
    double overrunMedian = 0.0, overrun90 = 0.0, overrun99 = 0.0, overrun999 = 0.0;  // quantiles, passes
    std::vector<PhotonBudgetLevel> levels;
    double deadlineBias = 0.0;   // of the base bias, smooth density (1 - (1 - s) sum rho_k s^k)
    double truncationBias = 0.0; // of the base bias: s^K (finish-block's, the render's own)
    // P(O > x), finish-block, x in passes.
    double overrunAbove(double x) const;
    // U(s): expected block starts before pass s.
    double blockStartsBefore(double s) const;

    // The renewal sums U(0 .. n) for n = min(B, the exact limit) + 1, and 1 / E[C] beyond.
    std::vector<double> prefix;
    double rateBeyond = 0.0;
};

// The block design of a scene's debias settings.
inline PhotonBlockDesign photonBlockDesign(const DebiasSettings& d) {
    return {double(d.pmf.r), double(d.photon.areaRatio), d.photon.photonGrowth, d.photon.levelCap};
}

// Exact for budgets up to kPhotonBudgetExactPasses passes; beyond, u(t) is taken as 1 / E[C]
// past that point (the renewal theorem), which the caller's text says.
constexpr uint64_t kPhotonBudgetExactPasses = uint64_t(1) << 22;
PhotonBudget photonBudget(const PhotonBlockDesign& design, uint64_t budgetPasses);

}  // namespace telescope
