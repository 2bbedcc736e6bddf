// The level distribution of the telescoping estimators (docs/ESTIMATORS.md section 1).
//
// Levels are counted from the base: m = j - k >= 0.
//   geometric:  p(m) = r (1-r)^m,                      P(M >= m) = (1-r)^m
//   power law:  P(M >= m) = (m+1)^(alpha-1),           p(m) = P(M >= m) - P(M >= m+1)
// The power law is the photon-mapping schedule of section 3 with j = m + 1.
//   fixed (kPmfFixed, the transmittance pmf pilot only): always level m = r, reported with the
//               "probability" alpha (1 or 1/2), so the correction enters weighted by 1 / alpha.
#ifndef TELESCOPE_LEVEL_PMF_H
#define TELESCOPE_LEVEL_PMF_H

#include "shared/enums.h"

SHADER_NAMESPACE_BEGIN

CONST uint kMaxLevel = 0x7fffffffu;  // levels are clamped here (probability < 1e-9 beyond)

struct LevelPmf {
    uint type;
    float r;      // geometric
    float alpha;  // power law, in (0, 1)
};

// log(1 + x) and exp(x) - 1 without cancellation (GLSL has neither): a series below |x| = 1e-2,
// relative error below 1e-6 everywhere (tests/unit/level_pmf_test.cpp).
FN float log1pSafe(float x) {
    if (abs(x) < 1e-2f) return x * (1.0f - x * (0.5f - x * (1.0f / 3.0f - x * (0.25f - x * 0.2f))));
    return log(1.0f + x);
}
FN float expm1Safe(float x) {
    if (abs(x) < 1e-2f) return x * (1.0f + x * (0.5f + x * (1.0f / 6.0f + x * (1.0f / 24.0f + x * (1.0f / 120.0f)))));
    return exp(x) - 1.0f;
}

FN LevelPmf makeLevelPmf(uint type, float r, float alpha) {
    LevelPmf pmf;
    pmf.type = type;
    pmf.r = r;
    pmf.alpha = alpha;
    return pmf;
}

// P(M >= m).
FN float levelTail(LevelPmf pmf, uint m) {
    if (m == 0u) return 1.0f;
    if (pmf.type == kPmfFixed) return m <= uint(pmf.r) ? 1.0f : 0.0f;
    if (pmf.type == kPmfGeometric) return exp(float(m) * log1pSafe(-pmf.r));
    return pow(float(m) + 1.0f, pmf.alpha - 1.0f);
}

// P(M == m), computed without the cancellation of tail(m) - tail(m+1).
FN float levelProbability(LevelPmf pmf, uint m) {
    if (pmf.type == kPmfFixed) return m == uint(pmf.r) ? pmf.alpha : 0.0f;
    if (pmf.type == kPmfGeometric) return pmf.r * levelTail(pmf, m);
    float a = float(m) + 1.0f;
    // (m+1)^(alpha-1) * (1 - ((m+1)/(m+2))^(1-alpha))
    return -pow(a, pmf.alpha - 1.0f) * expm1Safe((1.0f - pmf.alpha) * log1pSafe(-1.0f / (a + 1.0f)));
}

// Inverts the tail: u uniform in [0, 1).
FN uint levelSample(LevelPmf pmf, float u) {
    if (pmf.type == kPmfFixed) return uint(pmf.r);
    float m;
    if (pmf.type == kPmfGeometric) {
        m = floor(log1pSafe(-u) / log1pSafe(-pmf.r));
    } else {
        // n = (1-u)^(1/(alpha-1)) >= 1, m = floor(n) - 1
        m = floor(exp(log1pSafe(-u) / (pmf.alpha - 1.0f))) - 1.0f;
    }
    return m >= float(kMaxLevel) ? kMaxLevel : uint(max(m, 0.0f));
}

// ---- Truncated to the levels below a cap (photon blocks: levels 0 .. cap-1) ----

// P(M < cap) = 1 - P(M >= cap), without cancellation.
FN float levelMassBelow(LevelPmf pmf, uint cap) {
    if (pmf.type == kPmfGeometric) return -expm1Safe(float(cap) * log1pSafe(-pmf.r));
    return -expm1Safe((pmf.alpha - 1.0f) * log(float(cap) + 1.0f));
}

// P(M == m | M < cap).
FN float levelProbabilityBelow(LevelPmf pmf, uint m, uint cap) {
    return levelProbability(pmf, m) / levelMassBelow(pmf, cap);
}

// Draws M given M < cap by inverting P(M >= m | M < cap) = (P(M >= m) - P(M >= cap)) / P(M < cap),
// from 48 random bits (u1, u2 uniform in [0, 1) with 24 bits each): with one float's 24 bits no
// geometric level beyond ~13 / -log2(1 - r) could be drawn.
FN uint levelSampleBelow(LevelPmf pmf, uint cap, float u1, float u2) {
    float v = (1.0f - u1) - u2 * (1.0f / 16777216.0f);  // uniform in (0, 1]
    float tail = levelTail(pmf, cap) + v * levelMassBelow(pmf, cap);  // P(M >= m) at the drawn level
    float m;
    if (pmf.type == kPmfGeometric) m = floor(log(tail) / log1pSafe(-pmf.r));
    else m = floor(exp(log(tail) / (pmf.alpha - 1.0f))) - 1.0f;
    return uint(clamp(m, 0.0f, float(cap - 1u)));
}

SHADER_NAMESPACE_END

#endif
