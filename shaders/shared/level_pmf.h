// The level distribution of the telescoping estimators (docs/ESTIMATORS.md section 1).
//
// Levels are counted from the base: m = j - k >= 0.
//   geometric:  p(m) = r (1-r)^m,                      P(M >= m) = (1-r)^m
//   power law:  P(M >= m) = (m+1)^(alpha-1),           p(m) = P(M >= m) - P(M >= m+1)
// The power law is the photon-mapping schedule of section 3 with j = m + 1.
#ifndef TELESCOPE_LEVEL_PMF_H
#define TELESCOPE_LEVEL_PMF_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

CONST uint kPmfGeometric = 0u;
CONST uint kPmfPowerLaw = 1u;
CONST uint kMaxLevel = 0x7fffffffu;  // levels are clamped here (probability < 1e-9 beyond)

struct LevelPmf {
    uint type;
    float r;      // geometric
    float alpha;  // power law, in (0, 1)
};

// log(1 + x) and exp(x) - 1 without cancellation for small |x| (GLSL has neither).
FN float log1pSafe(float x) {
    if (abs(x) < 1e-4f) return x * (1.0f - x * (0.5f - x / 3.0f));
    return log(1.0f + x);
}
FN float expm1Safe(float x) {
    if (abs(x) < 1e-4f) return x * (1.0f + x * (0.5f + x / 6.0f));
    return exp(x) - 1.0f;
}

// P(M >= m).
FN float levelTail(LevelPmf pmf, uint m) {
    if (m == 0u) return 1.0f;
    if (pmf.type == kPmfGeometric) return exp(float(m) * log1pSafe(-pmf.r));
    return pow(float(m) + 1.0f, pmf.alpha - 1.0f);
}

// P(M == m), computed without the cancellation of tail(m) - tail(m+1).
FN float levelProbability(LevelPmf pmf, uint m) {
    if (pmf.type == kPmfGeometric) return pmf.r * levelTail(pmf, m);
    float a = float(m) + 1.0f;
    // (m+1)^(alpha-1) * (1 - ((m+1)/(m+2))^(1-alpha))
    return -pow(a, pmf.alpha - 1.0f) * expm1Safe((1.0f - pmf.alpha) * log1pSafe(-1.0f / (a + 1.0f)));
}

// Inverts the tail: u uniform in [0, 1).
FN uint levelSample(LevelPmf pmf, float u) {
    float m;
    if (pmf.type == kPmfGeometric) {
        m = floor(log1pSafe(-u) / log1pSafe(-pmf.r));
    } else {
        // n = (1-u)^(1/(alpha-1)) >= 1, m = floor(n) - 1
        m = floor(exp(log1pSafe(-u) / (pmf.alpha - 1.0f))) - 1.0f;
    }
    return m >= float(kMaxLevel) ? kMaxLevel : uint(max(m, 0.0f));
}

SHADER_NAMESPACE_END

#endif
