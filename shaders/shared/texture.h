// Textures on material parameters (Tungsten's constant, checker and bitmap textures) and the uv
// coordinates of a hit, following Tungsten's parameterisation of each primitive. One source for
// GLSL and C++ (tests/unit/texture_test.cpp).
//
// The texture buffer (binding kBindingTextures) is an array of vec4:
//   [0]                          x: first vec4 of the prim uv records (float bits of a uint)
//   [1 + 3 t, 3 + 3 t]           TextureGpu t (shared/gpu_types.h), three vec4
//   [uvBase + 2 s, +1]           the uv record of prim slot s (two vec4, see primUv)
//   [TextureGpu::offset ...]     a bitmap's texels, RGBA, row-major from the image's top row
// GLSL reads it as textureData[]; C++ passes the array as the first argument (TEX_PARAM).
#ifndef TELESCOPE_TEXTURE_H
#define TELESCOPE_TEXTURE_H

#include "shared/gpu_types.h"

#ifdef __cplusplus
#define TEX_PARAM const glm::vec4 *texData,
#define TEX_PASS texData,
#define TEX_VEC4(i) texData[i]
#else
#define TEX_PARAM
#define TEX_PASS
#define TEX_VEC4(i) textureData[i]
#endif

SHADER_NAMESPACE_BEGIN

CONST float kInvTwoPi = 0.15915494309189533577f;

FN TextureGpu textureRecord(TEX_PARAM uint t) {
    vec4 a = TEX_VEC4(1u + 3u * t);
    vec4 b = TEX_VEC4(2u + 3u * t);
    vec4 c = TEX_VEC4(3u + 3u * t);
    TextureGpu r;
    r.on = vec3(a.x, a.y, a.z);
    r.type = floatBitsToUint(a.w);
    r.off = vec3(b.x, b.y, b.z);
    r.flags = floatBitsToUint(b.w);
    r.res = uvec2(floatBitsToUint(c.x), floatBitsToUint(c.y));
    r.offset = floatBitsToUint(c.z);
    r.pad = 0u;
    return r;
}

// Tungsten's CheckerTexture: cell (int(u res_u), int(v res_v)) is "on" when the parities differ.
FN vec3 checkerValue(vec3 on, vec3 off, uvec2 res, vec2 uv) {
    int iu = int(uv.x * float(res.x));
    int iv = int(uv.y * float(res.y));
    return ((iu ^ iv) & 1) != 0 ? on : off;
}

// Integer texel coordinate i wrapped into [0, n) (only non-negative operands reach %).
FN int wrapTexel(int i, int n) { return i >= 0 ? i % n : n - 1 - ((-i - 1) % n); }

FN int texelIndex(int i, int n, bool clampEdge) { return clampEdge ? clamp(i, 0, n - 1) : wrapTexel(i, n); }

// Tungsten's BitmapTexture lookup: x = u w, y = (1 - v) h (row 0 is the image's top row); nearest
// takes the texel containing (x, y), bilinear the four around (x - 1/2, y - 1/2); wrap or clamp at
// the edges. The scale multiplies both (Tungsten's nearest path leaves it out; its default is 1).
FN vec3 bitmapValue(TEX_PARAM TextureGpu r, vec2 uv) {
    int w = int(r.res.x), h = int(r.res.y);
    float x = uv.x * float(w);
    float y = (1.0f - uv.y) * float(h);
    bool linear = (r.flags & kTextureInterpolate) != 0u;
    bool clampEdge = (r.flags & kTextureClamp) != 0u;
    if (linear) {
        x -= 0.5f;
        y -= 0.5f;
    }
    int ix0 = x < 0.0f ? -int(-x) - 1 : int(x);
    int iy0 = y < 0.0f ? -int(-y) - 1 : int(y);
    float fx = x - float(ix0);
    float fy = y - float(iy0);
    int x0 = texelIndex(ix0, w, clampEdge);
    int y0 = texelIndex(iy0, h, clampEdge);
    vec3 t00 = vec3(TEX_VEC4(r.offset + uint(y0 * w + x0)));
    if (!linear) return r.on * t00;
    int x1 = texelIndex(ix0 + 1, w, clampEdge);
    int y1 = texelIndex(iy0 + 1, h, clampEdge);
    vec3 t10 = vec3(TEX_VEC4(r.offset + uint(y0 * w + x1)));
    vec3 t01 = vec3(TEX_VEC4(r.offset + uint(y1 * w + x0)));
    vec3 t11 = vec3(TEX_VEC4(r.offset + uint(y1 * w + x1)));
    return r.on * ((t00 * (1.0f - fx) + t10 * fx) * (1.0f - fy) + (t01 * (1.0f - fx) + t11 * fx) * fy);
}

FN vec3 textureValue(TEX_PARAM uint t, vec2 uv) {
    TextureGpu r = textureRecord(TEX_PASS t);
    if (r.type == kTextureChecker) return checkerValue(r.on, r.off, r.res, uv);
    if (r.type == kTextureBitmap) return bitmapValue(TEX_PASS r, uv);
    return r.on;
}

// ---- uv coordinates of a hit (Tungsten's parameterisations) ----
// The uv record of a prim slot, two vec4 a, b:
//   triangle, quad: a = (uv(p0), uv(p1)), b.xy = uv(p2); uv is affine in the barycentrics (exact
//                   for Tungsten's quads and cube faces, whose uvs are their edge coordinates)
//   sphere:         a.xyz, b.xyz = the first two rows of the world-to-local rotation (the third is
//                   their cross product); uv = (atan2(y, x) / 2 pi + 1/2, acos(z) / pi) of the
//                   local normal
//   disk:           a.xyz = Tungsten's bitangent, b.xyz = tangent, a.w = 1 / radius;
//                   uv = (atan2(d.t, d.b) / 2 pi + 1/2, |d| / radius), d = p - centre

FN vec2 planarUv(vec4 a, vec4 b, vec2 bary) {
    vec2 uv0 = vec2(a.x, a.y);
    return uv0 + bary.x * (vec2(a.z, a.w) - uv0) + bary.y * (vec2(b.x, b.y) - uv0);
}

// Azimuth in [0, 1) from atan2(y, x) / 2 pi + 1/2; 0 at the pole (x = y = 0), as Tungsten.
FN float azimuthU(float y, float x) { return (x == 0.0f && y == 0.0f) ? 0.0f : atan(y, x) * kInvTwoPi + 0.5f; }

FN vec2 sphereUv(vec4 a, vec4 b, vec3 n) {
    vec3 r0 = vec3(a.x, a.y, a.z);
    vec3 r1 = vec3(b.x, b.y, b.z);
    vec3 local = vec3(dot(r0, n), dot(r1, n), dot(cross(r0, r1), n));
    return vec2(azimuthU(local.y, local.x), acos(clamp(local.z, -1.0f, 1.0f)) * kInvPi);
}

FN vec2 diskUv(vec4 a, vec4 b, vec3 d) {
    float x = dot(vec3(a.x, a.y, a.z), d);
    float y = dot(vec3(b.x, b.y, b.z), d);
    return vec2(azimuthU(y, x), length(d) * a.w);
}

// The uv of the hit at p (bary from the intersection) on prim slot `slot` of type `type`, centre
// the sphere's or disk's centre.
FN vec2 primUv(TEX_PARAM uint slot, uint type, vec2 bary, vec3 p, vec3 centre) {
    uint base = floatBitsToUint(TEX_VEC4(0u).x) + 2u * slot;
    vec4 a = TEX_VEC4(base);
    vec4 b = TEX_VEC4(base + 1u);
    if (type == kPrimSphere) return sphereUv(a, b, normalize(p - centre));
    if (type == kPrimDisk) return diskUv(a, b, p - centre);
    return planarUv(a, b, bary);
}

// sRGB-encoded value in [0, 1] to linear (the exact piecewise curve).
FN float srgbToLinear(float c) {
    return c <= 0.04045f ? c * (1.0f / 12.92f) : pow((c + 0.055f) * (1.0f / 1.055f), 2.4f);
}

SHADER_NAMESPACE_END

#endif
