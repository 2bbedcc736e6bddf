// Photon density estimation (ESTIMATORS.md section 3): kernels, the radius levels of the
// telescope, their pmf, and the hash grid's cell arithmetic. Compiled as GLSL and as C++; the
// CPU tests (tests/unit/photon_density_test.cpp) check every formula here.
//
//   K_r(x)  = sum_i f Phi_i W_r(|x - x_i|),        W_r(d) = shape(d / r) / (pi r^2), d < r
//   cone: shape(t) = 3 (1 - t)   uniform: 1   Epanechnikov: 2 (1 - t^2)   (each integrates to 1)
//
// Levels j >= b (b = 1, or the pass index + 1 for the unbiased progressive variant):
//   power law: r_j^2 = r_1^2 j^(alpha-1),  p(j | j >= b) = (j^(alpha-1) - (j+1)^(alpha-1)) / b^(alpha-1)
//   geometric: r_j^2 = r_1^2 2^-(j-1),     p(j | j >= b) = r (1-r)^(j-b)
//   Z = K_{r_b} + (K_{r_{j+1}} - K_{r_j}) / p(j | j >= b)
// Radii are carried as logarithms relative to r_b, and K_{r_{j+1}} - K_{r_j} is evaluated per
// photon in closed form, so levels far beyond 2^24 (r_{j+1} and r_j equal in float) keep their
// exact difference.
//
// Truncation (the only one): levels with r_j < 2^-16 r_b are never corrected
// (kLogRadius2Floor). The estimator is then unbiased for I(2^-16 r_b); the neglected tail is the
// bias of a kernel estimate with that radius, ~2^-32 of the base bias for smooth radiance. With
// the power law alpha = 2/3 it is drawn with probability ~2^-32, with the geometric pmf r = 0.65
// with probability 0.35^32 ~ 3e-15.
#ifndef TELESCOPE_PHOTON_DENSITY_H
#define TELESCOPE_PHOTON_DENSITY_H

#include "shared/level_pmf.h"
#ifdef __cplusplus
#include <glm/gtc/packing.hpp>
#endif

SHADER_NAMESPACE_BEGIN

CONST uint kKernelCone = 0u;
CONST uint kKernelUniform = 1u;
CONST uint kKernelEpanechnikov = 2u;

CONST float kLogRadius2Floor = -22.18070978f;  // ln(2^-32): r_j^2 / r_b^2 below this is not corrected
CONST float kLn2 = 0.69314718056f;

// ---- Accurate log(1 + x) and exp(x) - 1 (series below 1e-2, relative error < 1e-6 above) ----
FN float log1pPrecise(float x) {
    if (abs(x) < 1e-2f) return x * (1.0f - x * (0.5f - x * (1.0f / 3.0f - x * (0.25f - x * 0.2f))));
    return log(1.0f + x);
}
FN float expm1Precise(float x) {
    if (abs(x) < 1e-2f) return x * (1.0f + x * (0.5f + x * (1.0f / 6.0f + x * (1.0f / 24.0f + x * (1.0f / 120.0f)))));
    return exp(x) - 1.0f;
}

// ---- Kernels ----
FN float kernelShape(uint kernel, float t) {
    if (kernel == kKernelUniform) return 1.0f;
    if (kernel == kKernelEpanechnikov) return 2.0f * (1.0f - t * t);
    return 3.0f * (1.0f - t);
}

// W_r(d) from d^2 and r^2.
FN float kernelWeight(uint kernel, float d2, float r2) {
    if (!(d2 < r2)) return 0.0f;
    return kernelShape(kernel, sqrt(d2 / r2)) / (kPi * r2);
}

// W_{r'}(d) - W_r(d) for r' < r, logQ2 = ln(r'^2 / r^2) < 0, without cancellation:
// inside r', shape(d/r')/r'^2 - shape(d/r)/r^2 = (1/r^2) [c0 (q^-2 - 1) - c1 t^k (q^-(2+k) - 1)],
// with t = d/r and the q^-n - 1 = expm1(-n/2 logQ2) exact for q near 1; in the shell
// r' <= d < r only -W_r(d) remains.
FN float kernelDifference(uint kernel, float d2, float r2, float logQ2) {
    if (!(d2 < r2)) return 0.0f;
    float t2 = d2 / r2;
    float t = sqrt(t2);
    if (!(t2 < exp(logQ2))) return -kernelShape(kernel, t) / (kPi * r2);
    float e2 = expm1Precise(-logQ2);
    if (kernel == kKernelUniform) return e2 / (kPi * r2);
    if (kernel == kKernelEpanechnikov) return 2.0f * (e2 - t2 * expm1Precise(-2.0f * logQ2)) / (kPi * r2);
    return 3.0f * (e2 - t * expm1Precise(-1.5f * logQ2)) / (kPi * r2);
}

// ---- Levels (the pmf type is the radius schedule: kPmfPowerLaw or kPmfGeometric) ----

// ln(r_j^2 / r_b^2).
FN float levelLogRadius2(LevelPmf pmf, float j, float b) {
    if (pmf.type == kPmfGeometric) return -(j - b) * kLn2;
    return (pmf.alpha - 1.0f) * log(j / b);
}

// ln(r_{j+1}^2 / r_j^2).
FN float levelLogStep2(LevelPmf pmf, float j) {
    if (pmf.type == kPmfGeometric) return -kLn2;
    return (pmf.alpha - 1.0f) * log1pPrecise(1.0f / j);
}

// p(j | j >= b).
FN float levelProbabilityFrom(LevelPmf pmf, float j, float b) {
    if (pmf.type == kPmfGeometric) return pmf.r * exp((j - b) * log1pPrecise(-pmf.r));
    return -exp((pmf.alpha - 1.0f) * log(j / b)) * expm1Precise((pmf.alpha - 1.0f) * log1pPrecise(1.0f / j));
}

// Draws j >= b by inverting the tail P(J >= j | J >= b) from 48 random bits (u1, u2 uniform in
// [0, 1) with 24 bits each), so that the deep tail is resolved. Returns 0 when the level lies
// beyond the truncation (r_j < 2^-16 r_b): no correction.
FN float levelSampleFrom(LevelPmf pmf, float b, float u1, float u2) {
    float v = (1.0f - u1) - u2 * (1.0f / 16777216.0f);  // uniform in (0, 1]
    float lv = log(v);
    float j;
    if (pmf.type == kPmfGeometric) {
        j = b + floor(lv / log1pPrecise(-pmf.r));
    } else {
        // P(J >= n | J >= b) = (n / b)^(alpha-1): n = b v^(1/(alpha-1)), j = floor(n)
        float logN = log(b) + lv / (pmf.alpha - 1.0f);
        if (logN > 80.0f) return 0.0f;
        j = max(floor(exp(logN)), b);
    }
    if (levelLogRadius2(pmf, j, b) < kLogRadius2Floor) return 0.0f;
    return j;
}

// ---- Hash grid ----
CONST float kGridCellLimit = 1073741824.0f;  // 2^30: cell coordinates are clamped here

// Cell of p: floor() so negative coordinates round down; clamped so the int conversion is defined
// (points beyond 2^30 cells share the border cells, which only costs work).
FN ivec3 gridCell(vec3 p, float cellSize) {
    return ivec3(clamp(floor(p / cellSize), vec3(-kGridCellLimit), vec3(kGridCellLimit)));
}

// Lower corner of the 2x2x2 cells that contain every point within cellSize / 2 of p.
FN ivec3 gridNeighbourhood(vec3 p, float cellSize) {
    vec3 s = p / cellSize;
    vec3 f = floor(s);
    vec3 low = f - vec3(1.0f) + step(vec3(0.5f), s - f);
    return ivec3(clamp(low, vec3(-kGridCellLimit), vec3(kGridCellLimit)));
}

// Bucket of a cell in a table of 2^k entries: unsigned arithmetic only (wraps, never overflows).
FN uint gridHash(ivec3 c, uint tableSize) {
    uvec3 u = uvec3(c);
    uint h = (u.x * 73856093u) ^ (u.y * 19349663u) ^ (u.z * 83492791u);
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    return h & (tableSize - 1u);
}

// ---- Photon directions: octahedral map to 2 x snorm16 ----
FN uint encodeDirection(vec3 d) {
    vec2 p = vec2(d.x, d.y) / (abs(d.x) + abs(d.y) + abs(d.z));
    if (d.z < 0.0f) {
        vec2 s = vec2(p.x >= 0.0f ? 1.0f : -1.0f, p.y >= 0.0f ? 1.0f : -1.0f);
        p = (vec2(1.0f) - abs(vec2(p.y, p.x))) * s;
    }
    return packSnorm2x16(p);
}

FN vec3 decodeDirection(uint packed) {
    vec2 p = unpackSnorm2x16(packed);
    vec3 d = vec3(p.x, p.y, 1.0f - abs(p.x) - abs(p.y));
    if (d.z < 0.0f) {
        vec2 s = vec2(d.x >= 0.0f ? 1.0f : -1.0f, d.y >= 0.0f ? 1.0f : -1.0f);
        vec2 xy = (vec2(1.0f) - abs(vec2(d.y, d.x))) * s;
        d.x = xy.x;
        d.y = xy.y;
    }
    return normalize(d);
}

SHADER_NAMESPACE_END

#endif
