// The path-depth telescope (docs/ESTIMATORS.md section 2).
//
// I(d) sums the contributions c_b of paths with b <= d bounces. With the level M = j - k drawn
// from a LevelPmf, one path traced to depth k + M + 1 gives
//   single term:  Z = sum_{b<=k} c_b + c_{j+1} / p(j - k)
//   sum (RR):     Z = sum_{b<=k} c_b + sum_{j=k}^{k+M} c_{j+1} / P(M >= j - k)
// depthWeight() is the factor applied to c_b; the path need not go deeper than depthLimit().
#ifndef TELESCOPE_PATH_DEPTH_H
#define TELESCOPE_PATH_DEPTH_H

#include "shared/level_pmf.h"

SHADER_NAMESPACE_BEGIN

// Deepest bounce whose contribution has a non-zero weight.
FN uint depthLimit(uint mode, uint k, uint level) {
    if (mode == kDebiasNone) return k;
    return k + 1u + min(level, 0x7ffff000u - k);
}

FN float depthWeight(uint mode, LevelPmf pmf, uint k, uint level, uint bounce) {
    if (bounce <= k) return 1.0f;
    if (mode == kDebiasNone) return 0.0f;
    uint m = bounce - 1u - k;  // c_b is the correction D_j with j = b - 1
    if (mode == kDebiasSingleTerm) return m == level ? 1.0f / levelProbability(pmf, m) : 0.0f;
    return m <= level ? 1.0f / levelTail(pmf, m) : 0.0f;
}

SHADER_NAMESPACE_END

#endif
