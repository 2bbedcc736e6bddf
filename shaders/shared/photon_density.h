// Photon density estimation (docs/PHOTON-MAPPING.md): kernels, the radius levels of the
// telescope, their pmf, and the hash grid's cell arithmetic. Compiled as GLSL and as C++; the
// CPU tests (tests/unit/photon_density_test.cpp) check every formula here.
//
//   K_r(x)  = sum_i f Phi_i W_r(|x - x_i|),        W_r(d) = shape(d / r) / (pi r^2), d < r
//   cone: shape(t) = 3 (1 - t)   uniform: 1   Epanechnikov: 2 (1 - t^2)   (each integrates to 1)
//
// Unbiased photon mapping draws a level per block of photon passes (see "Block levels" below).
// Kernel differences K_{r'} - K_r are evaluated per photon in closed form (expm1/log1p), so
// neighbouring radii that are equal in float keep their exact difference.
#ifndef TELESCOPE_PHOTON_DENSITY_H
#define TELESCOPE_PHOTON_DENSITY_H

#include "shared/level_pmf.h"
#ifdef __cplusplus
#include <glm/gtc/packing.hpp>
#endif

SHADER_NAMESPACE_BEGIN

CONST float kLn2 = 0.69314718056f;

// ---- Kernels ----
FN float kernelShape(uint kernel, float t) {
    if (kernel == kKernelUniform) return 1.0f;
    if (kernel == kKernelEpanechnikov) return 2.0f * (1.0f - t * t);
    return 3.0f * (1.0f - t);
}

// The k-nearest gather's weight: W_r(d) with the photon at d = r (the k-th nearest, which sets r)
// still inside the kernel (Tungsten's uniform 1 / (pi r^2) counts it; the cone and Epanechnikov
// shapes are 0 there anyway).
FN float nearestKernelWeight(uint kernel, float d2, float r2) {
    if (!(r2 > 0.0f)) return 0.0f;
    return kernelShape(kernel, sqrt(min(d2 / r2, 1.0f))) / (kPi * r2);
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
    float e2 = expm1Safe(-logQ2);
    if (kernel == kKernelUniform) return e2 / (kPi * r2);
    if (kernel == kKernelEpanechnikov) return 2.0f * (e2 - t2 * expm1Safe(-2.0f * logQ2)) / (kPi * r2);
    return 3.0f * (e2 - t * expm1Safe(-1.5f * logQ2)) / (kPi * r2);
}

// ---- Block levels (docs/PHOTON-MAPPING.md) ----
// A sample of unbiased photon mapping is a block of level k = 0 .. K-1: m^k photon passes whose
// kernels have the base radius r_b and r_k^2 = r_b^2 s^k, r_{k+1}^2 = r_k^2 s. The level has the
// truncated geometric pmf p(k) = r (1-r)^k / (1 - (1-r)^K) (continue with q = 1 - r):
//   Z = mean over the block of K_{r_b}  +  mean over the block of (K_{r_{k+1}} - K_{r_k}) / p(k),
// unbiased for the kernel estimate at r_K (the cap K is the only truncation).
struct PhotonLevels {
    float r;             // stopping probability of the geometric pmf
    float logAreaRatio;  // ln s
    uint growth;         // m: photon passes grow m-fold per level
    uint cap;            // K: levels 0 .. K-1
};

// The geometric pmf of the levels (truncated to k < K by the functions below).
FN LevelPmf photonLevelPmf(PhotonLevels l) { return makeLevelPmf(kPmfGeometric, l.r, 0.0f); }

// p(k).
FN float photonLevelProbability(PhotonLevels l, uint k) { return levelProbabilityBelow(photonLevelPmf(l), k, l.cap); }

// A level from 48 random bits (shared/level_pmf.h levelSampleBelow).
FN uint photonLevelSample(PhotonLevels l, float u1, float u2) { return levelSampleBelow(photonLevelPmf(l), l.cap, u1, u2); }

// m^k passes (the settings keep m^(K-1) below 2^31).
FN uint photonBlockPasses(PhotonLevels l, uint k) {
    uint n = 1u;
    for (uint i = 0u; i < k; ++i) n *= l.growth;
    return n;
}

// ln(r_k^2 / r_b^2).
FN float photonLevelLogRadius2(PhotonLevels l, uint k) { return float(k) * l.logAreaRatio; }

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

// Bucket of a cell in a table of 2^k >= 512 entries: unsigned arithmetic only (wraps, never
// overflows). Cells go in blocks of 8x8x8: a block's 512 cells take consecutive buckets in Morton
// order and the block's place is hashed. Nearby cells then take nearby buckets, so a gather's
// reads of the cells around x stay within a few cache lines (a hash of each cell scattered them
// over the whole table: docs/BENCHMARKS.md), and two cells less than 8 apart on every axis differ
// in some coordinate mod 8, so never share a bucket (a gather reads each bucket once).
FN uint gridMorton3(uint v) {  // v < 8: bits 0, 1, 2 to 0, 3, 6
    return (v & 1u) | ((v & 2u) << 2u) | ((v & 4u) << 4u);
}
FN uint gridHash(ivec3 c, uint tableSize) {
    uvec3 u = uvec3(c);
    uvec3 b = u >> 3u;
    uint h = (b.x * 73856093u) ^ (b.y * 19349663u) ^ (b.z * 83492791u);
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    uint local = gridMorton3(u.x & 7u) | (gridMorton3(u.y & 7u) << 1u) | (gridMorton3(u.z & 7u) << 2u);
    return ((h << 9u) | local) & (tableSize - 1u);
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
