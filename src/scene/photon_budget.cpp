#include "scene/photon_budget.h"

#include <algorithm>
#include <cmath>

namespace telescope {

double PhotonBudget::blockStartsBefore(double s) const {
    if (s <= 0.0) return 0.0;
    const double last = double(prefix.size() - 1);
    if (s <= last) return prefix[size_t(s)];
    return prefix.back() + (s - last) * rateBeyond;
}

double PhotonBudget::overrunAbove(double x) const {
    const double total = blockStartsBefore(budgetPasses);
    double p = 0.0;
    for (const PhotonBudgetLevel& l : levels)
        if (l.passes > x) p += l.probability * (total - blockStartsBefore(std::max(0.0, budgetPasses + x - l.passes + 1.0)));
    return p;
}

PhotonBudget photonBudget(const PhotonBlockDesign& d, uint64_t budgetPasses) {
    PhotonBudget b;
    b.budgetPasses = double(budgetPasses);
    const double q = 1.0 - d.r, norm = 1.0 - std::pow(q, double(d.levelCap));
    for (uint32_t k = 0; k < d.levelCap; ++k) {
        PhotonBudgetLevel l;
        l.level = k;
        l.passes = std::pow(double(d.growth), double(k));
        l.probability = d.r * std::pow(q, double(k)) / norm;
        b.expectedPasses += l.probability * l.passes;
        b.levels.push_back(l);
    }
    b.rateBeyond = 1.0 / b.expectedPasses;

    // u(t) for t < n, and its prefix sums U(0 .. n)
    const uint64_t n = std::min(budgetPasses, kPhotonBudgetExactPasses) + 1;
    std::vector<double> u(n, 0.0);
    u[0] = 1.0;
    for (uint64_t t = 1; t < n; ++t) {
        double v = 0.0;
        for (const PhotonBudgetLevel& l : b.levels) {
            if (l.passes > double(t)) break;
            v += l.probability * u[t - uint64_t(l.passes)];
        }
        u[t] = v;
    }
    b.prefix.assign(n + 1, 0.0);
    for (uint64_t t = 0; t < n; ++t) b.prefix[t + 1] = b.prefix[t] + u[t];

    // finish-block: blocks started, the overrun's quantiles
    const double B = b.budgetPasses;
    b.expectedBlocks = b.blockStartsBefore(B);
    auto quantile = [&](double p) {
        // smallest integer x with P(O > x) <= 1 - p
        double lo = 0.0, hi = b.levels.back().passes;
        if (b.overrunAbove(lo) <= 1.0 - p) return 0.0;
        while (hi - lo > 1.0) {
            const double mid = std::floor(0.5 * (lo + hi));
            (b.overrunAbove(mid) <= 1.0 - p ? hi : lo) = mid;
        }
        return hi;
    };
    b.overrunMedian = quantile(0.5);
    b.overrun90 = quantile(0.9);
    b.overrun99 = quantile(0.99);
    b.overrun999 = quantile(0.999);

    // deadline: the completed blocks' level weights
    for (PhotonBudgetLevel& l : b.levels) {
        l.deadlineWeight = b.blockStartsBefore(B - l.passes + 1.0);
        b.expectedBlocksDeadline += l.probability * l.deadlineWeight;
    }
    double kept = 0.0;
    for (PhotonBudgetLevel& l : b.levels) {
        l.deadlineWeight = b.expectedBlocksDeadline > 0.0 ? l.deadlineWeight / b.expectedBlocksDeadline : 0.0;
        kept += l.deadlineWeight * std::pow(d.areaRatio, double(l.level));
    }
    b.deadlineBias = 1.0 - (1.0 - d.areaRatio) * kept;
    b.truncationBias = std::pow(d.areaRatio, double(d.levelCap));
    return b;
}

}  // namespace telescope
