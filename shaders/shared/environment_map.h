// Tungsten's infinite_sphere with an image (src/core/primitives/InfiniteSphere.cpp and
// textures/BitmapTexture.cpp): the direction <-> (u, v) map, the bilinear texel lookup, and
// importance sampling of a piecewise-constant 2D distribution over the texels, one copy for
// path_trace (binding kBindingEnvironment) and the CPU tests (tests/unit/environment_map_test.cpp).
// The includer defines ENV_DATA(i): float i of the environment buffer, laid out as below and
// built by src/render/environment_map.cpp.
//
// Directions: the local frame is the world frame turned by the inverse of the primitive's
// rotation; in it (phi, theta) = ((u - 1/2) 2 pi, v pi) is the direction
// (cos phi sin theta, -cos theta, sin phi sin theta): v = 1 (theta = pi) looks up +y, the top row
// of the image. Texel (x, y) covers u in [x, x + 1) / w and 1 - v in [y, y + 1) / h.
//
// Sampling density over solid angle (the Jacobian of the (u, v) map: dw = 2 pi^2 sin theta du dv):
//   p(w) = p_uv(u, v) / (2 pi^2 sin theta),  p_uv = w h P(row) P(column | row).
#ifndef TELESCOPE_ENVIRONMENT_MAP_H
#define TELESCOPE_ENVIRONMENT_MAP_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

// ---- Layout of the environment buffer (floats) ----
// [0] width w, [1] height h, [2] flags (kEnv*), [3] tests only: a factor on envSample's pdf (1),
// [4..12] the rotation (local -> world), row-major, [13..15] unused;
// then the texels (3 floats each, row 0 the top row of the image, x fastest),
// then the rows' inclusive cdf (h floats, the last exactly 1),
// then each row's inclusive cdf over its columns (w floats a row, the last of each exactly 1).
CONST uint kEnvHeaderFloats = 16u;
CONST uint kEnvInterpolate = 1u;  // bilinear lookups (Tungsten's `interpolate`, on by default)
CONST uint kEnvClamp = 2u;        // clamp lookups at the edges (Tungsten's `clamp`), else wrap
#ifdef __cplusplus
// Floats of the buffer for a w x h image.
inline uint64_t envBufferFloats(uint64_t w, uint64_t h) { return kEnvHeaderFloats + 4 * w * h + h; }
// The largest buffer: 2^27 bytes, the Vulkan minimum of maxStorageBufferRange (lavapipe's limit).
constexpr uint64_t kEnvMaxBufferBytes = uint64_t(1) << 27;
#endif

#ifdef ENV_DATA

FN uint envWidth() { return uint(ENV_DATA(0u)); }
FN uint envHeight() { return uint(ENV_DATA(1u)); }
FN uint envTexelOffset() { return kEnvHeaderFloats; }
FN uint envRowCdfOffset() { return kEnvHeaderFloats + 3u * envWidth() * envHeight(); }
FN uint envColumnCdfOffset() { return envRowCdfOffset() + envHeight(); }

// ---- Directions ----
FN vec3 envToWorld(vec3 l) {
    return vec3(ENV_DATA(4u) * l.x + ENV_DATA(5u) * l.y + ENV_DATA(6u) * l.z,
                ENV_DATA(7u) * l.x + ENV_DATA(8u) * l.y + ENV_DATA(9u) * l.z,
                ENV_DATA(10u) * l.x + ENV_DATA(11u) * l.y + ENV_DATA(12u) * l.z);
}
FN vec3 envToLocal(vec3 w) {  // the transpose of the rotation
    return vec3(ENV_DATA(4u) * w.x + ENV_DATA(7u) * w.y + ENV_DATA(10u) * w.z,
                ENV_DATA(5u) * w.x + ENV_DATA(8u) * w.y + ENV_DATA(11u) * w.z,
                ENV_DATA(6u) * w.x + ENV_DATA(9u) * w.y + ENV_DATA(12u) * w.z);
}
FN vec2 envLocalToUv(vec3 l) {
    return vec2(atan(l.z, l.x) * (0.5f * kInvPi) + 0.5f, acos(clamp(-l.y, -1.0f, 1.0f)) * kInvPi);
}
FN vec3 envUvToLocal(vec2 uv, OUT(float) sinTheta) {
    float phi = (uv.x - 0.5f) * (2.0f * kPi);
    float theta = uv.y * kPi;
    sinTheta = sin(theta);
    return vec3(cos(phi) * sinTheta, -cos(theta), sin(phi) * sinTheta);
}

// ---- Radiance: Tungsten's BitmapTexture lookup (bilinear between texel centres, wrapped or clamped) ----
FN vec3 envTexel(int x, int y) {
    uint i = envTexelOffset() + 3u * (uint(y) * envWidth() + uint(x));
    return vec3(ENV_DATA(i), ENV_DATA(i + 1u), ENV_DATA(i + 2u));
}
FN int envWrap(int i, int n, bool clampEdges) {
    if (clampEdges) return clamp(i, 0, n - 1);
    return int(float(i) - float(n) * floor(float(i) / float(n)));  // (i mod n), also for i < 0
}
FN vec3 envLookup(vec2 uv) {
    int w = int(envWidth()), h = int(envHeight());
    uint flags = uint(ENV_DATA(2u));
    bool linear = (flags & kEnvInterpolate) != 0u;
    bool clampEdges = (flags & kEnvClamp) != 0u;
    float u = uv.x * float(w), v = (1.0f - uv.y) * float(h);
    if (linear) {
        u -= 0.5f;
        v -= 0.5f;
    }
    float fu = floor(u), fv = floor(v);
    int iu0 = int(fu), iv0 = int(fv);
    u -= fu;
    v -= fv;
    int iu1 = envWrap(iu0 + 1, w, clampEdges), iv1 = envWrap(iv0 + 1, h, clampEdges);
    iu0 = envWrap(iu0, w, clampEdges);
    iv0 = envWrap(iv0, h, clampEdges);
    if (!linear) return envTexel(iu0, iv0);
    return (envTexel(iu0, iv0) * (1.0f - u) + envTexel(iu1, iv0) * u) * (1.0f - v) +
           (envTexel(iu0, iv1) * (1.0f - u) + envTexel(iu1, iv1) * u) * v;
}
FN vec3 envRadiance(vec3 dirWorld) { return envLookup(envLocalToUv(envToLocal(dirWorld))); }

// ---- Sampling ----
// Smallest index i in [0, n) of the inclusive cdf at `offset` with u < cdf[i]; lo receives
// cdf[i - 1] (0 for i = 0). At most log2(n) + 1 steps.
FN uint envSearchCdf(uint offset, uint n, float u, OUT(float) lo) {
    uint a = 0u, b = n - 1u;
    while (a < b) {
        LOOP_BUDGET_TICK(1u);
        uint mid = (a + b) >> 1u;
        if (u < ENV_DATA(offset + mid)) b = mid;
        else a = mid + 1u;
    }
    lo = a > 0u ? ENV_DATA(offset + a - 1u) : 0.0f;
    return a;
}

// Density in (u, v) of the texel cell (row, column): w h P(row) P(column | row).
FN float envCellPdf(uint row, uint column) {
    uint w = envWidth(), h = envHeight();
    uint r = envRowCdfOffset() + row;
    uint c = envColumnCdfOffset() + row * w + column;
    float pRow = ENV_DATA(r) - (row > 0u ? ENV_DATA(r - 1u) : 0.0f);
    float pColumn = ENV_DATA(c) - (column > 0u ? ENV_DATA(c - 1u) : 0.0f);
    return pRow * pColumn * float(w) * float(h);
}

// Solid-angle density of envSample at a world direction (Tungsten's directPdf; 0 at the poles).
FN float envPdf(vec3 dirWorld) {
    vec3 l = envToLocal(dirWorld);
    float sinTheta = sqrt(max(1.0f - l.y * l.y, 0.0f));
    if (!(sinTheta > 0.0f)) return 0.0f;
    vec2 uv = envLocalToUv(l);
    uint w = envWidth(), h = envHeight();
    uint row = min(uint(max((1.0f - uv.y) * float(h), 0.0f)), h - 1u);
    uint column = min(uint(max(uv.x * float(w), 0.0f)), w - 1u);
    return envCellPdf(row, column) / (2.0f * kPi * kPi * sinTheta);
}

// A direction (world), its (u, v) and its solid-angle density from two uniform numbers: a row by
// the rows' cdf, a column by that row's cdf, uniform within the texel (Tungsten's Distribution2D).
FN bool envSample(vec2 xi, OUT(vec3) dirWorld, OUT(vec2) uv, OUT(float) pdf) {
    uint w = envWidth(), h = envHeight();
    float rowLo, columnLo;
    uint row = envSearchCdf(envRowCdfOffset(), h, xi.y, rowLo);
    float rowHi = ENV_DATA(envRowCdfOffset() + row);
    uint column = envSearchCdf(envColumnCdfOffset() + row * w, w, xi.x, columnLo);
    float columnHi = ENV_DATA(envColumnCdfOffset() + row * w + column);
    float fy = clamp((xi.y - rowLo) / max(rowHi - rowLo, 1e-30f), 0.0f, 1.0f);
    float fx = clamp((xi.x - columnLo) / max(columnHi - columnLo, 1e-30f), 0.0f, 1.0f);
    uv = vec2((float(column) + fx) / float(w), 1.0f - (float(row) + fy) / float(h));
    float sinTheta;
    vec3 l = envUvToLocal(uv, sinTheta);
    if (!(sinTheta > 0.0f)) return false;
    pdf = (rowHi - rowLo) * (columnHi - columnLo) * float(w) * float(h) / (2.0f * kPi * kPi * sinTheta) *
          ENV_DATA(3u);
    dirWorld = envToWorld(l);
    return pdf > 0.0f;
}

#endif  // ENV_DATA

SHADER_NAMESPACE_END

#endif
