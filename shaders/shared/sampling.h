// Direction and area sampling, frames and MIS weights.
#ifndef TELESCOPE_SAMPLING_H
#define TELESCOPE_SAMPLING_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

// Orthonormal basis around a unit normal (Duff et al. 2017, branchless).
FN void buildFrame(vec3 n, OUT(vec3) t, OUT(vec3) b) {
    float s = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (s + n.z);
    float c = n.x * n.y * a;
    t = vec3(1.0f + s * n.x * n.x * a, s * c, -s * n.x);
    b = vec3(c, s + n.y * n.y * a, -n.y);
}

// Cosine-weighted hemisphere around n; pdf = cos / pi.
FN vec3 sampleCosineHemisphere(vec3 n, float u1, float u2) {
    float r = sqrt(u1);
    float phi = 2.0f * kPi * u2;
    vec3 t, b;
    buildFrame(n, t, b);
    float z = sqrt(max(0.0f, 1.0f - u1));
    return normalize(t * (r * cos(phi)) + b * (r * sin(phi)) + n * z);
}

// ---- Stratified emission along a Z-order curve (photon_trace.comp) ----
// Path `path` of `count` takes T = floor((path 2^32 + random) / count), random a uniform 32-bit
// word: over the count paths the numerator covers [0, count 2^32) once, so T is exactly uniform on
// [0, 2^32) while path i keeps to the stretch [i, i + 1) 2^32 / count. (64-bit, once per path;
// GLSL shaders that use it define TELESCOPE_INT64 after enabling the int64 extension.)
#if defined(__cplusplus) || defined(TELESCOPE_INT64)
FN uint curvePosition(uint path, uint count, uint random) {
    return uint(((uint64_t(path) << 32u) | uint64_t(random)) / uint64_t(count));
}
#endif

// The Z-order curve's cell of T: bits 0, 2, 4, ... (axis 0) or 1, 3, 5, ... (axis 1) packed into 16
// bits for the unit square, bits a, a + 4, a + 8, ... packed into 8 bits for axis a of the 4-cube.
FN uint curveCoordinate2(uint t, uint axis) {
    uint x = (t >> axis) & 0x55555555u;
    x = (x ^ (x >> 1u)) & 0x33333333u;
    x = (x ^ (x >> 2u)) & 0x0f0f0f0fu;
    x = (x ^ (x >> 4u)) & 0x00ff00ffu;
    return (x ^ (x >> 8u)) & 0x0000ffffu;
}
FN uint curveCoordinate4(uint t, uint axis) {
    uint x = (t >> axis) & 0x11111111u;
    x = (x ^ (x >> 3u)) & 0x03030303u;
    x = (x ^ (x >> 6u)) & 0x000f000fu;
    return (x ^ (x >> 12u)) & 0x000000ffu;
}

// Uniform direction on the sphere; pdf = 1 / (4 pi).
FN vec3 sampleUniformSphere(float u1, float u2) {
    float z = 1.0f - 2.0f * u1;
    float r = sqrt(max(0.0f, 1.0f - z * z));
    float phi = 2.0f * kPi * u2;
    return vec3(r * cos(phi), r * sin(phi), z);
}

// Uniform direction in the cone of half angle acos(cosMax) around the unit axis;
// pdf = 1 / (2 pi (1 - cosMax)).
FN vec3 sampleUniformCone(vec3 axis, float cosMax, float u1, float u2) {
    float z = 1.0f - u1 * (1.0f - cosMax);
    float r = sqrt(max(0.0f, 1.0f - z * z));
    float phi = 2.0f * kPi * u2;
    vec3 t, b;
    buildFrame(axis, t, b);
    return normalize(t * (r * cos(phi)) + b * (r * sin(phi)) + axis * z);
}

// Uniform point on a triangle (barycentrics).
FN vec3 sampleTriangle(vec3 p0, vec3 p1, vec3 p2, float u1, float u2) {
    float su = sqrt(u1);
    float b0 = 1.0f - su;
    float b1 = u2 * su;
    return p0 * b0 + p1 * b1 + p2 * (1.0f - b0 - b1);
}

// Uniform point on the parallelogram p0 + [0,1] (p1 - p0) + [0,1] (p2 - p0).
FN vec3 sampleParallelogram(vec3 p0, vec3 p1, vec3 p2, float u1, float u2) {
    return p0 + u1 * (p1 - p0) + u2 * (p2 - p0);
}

// Uniform point on a disk of radius r around c with normal n.
FN vec3 sampleDisk(vec3 c, vec3 n, float radius, float u1, float u2) {
    vec3 t, b;
    buildFrame(n, t, b);
    float r = radius * sqrt(u1);
    float phi = 2.0f * kPi * u2;
    return c + t * (r * cos(phi)) + b * (r * sin(phi));
}

// Tent filter over [-1, 1] by inversion.
FN float sampleTent(float u) {
    return u < 0.5f ? sqrt(2.0f * u) - 1.0f : 1.0f - sqrt(2.0f - 2.0f * u);
}

FN float powerHeuristic(float a, float b) {
    float a2 = a * a;
    float b2 = b * b;
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}

FN float maxComponent(vec3 v) { return max(v.x, max(v.y, v.z)); }
FN float luminance(vec3 c) { return dot(c, vec3(0.2126f, 0.7152f, 0.0722f)); }

// Fresnel reflectance of a smooth dielectric; eta = n_transmitted / n_incident.
FN float fresnelDielectric(float cosI, float eta, OUT(float) cosT) {
    float sin2T = (1.0f - cosI * cosI) / (eta * eta);
    if (sin2T >= 1.0f) {
        cosT = 0.0f;
        return 1.0f;
    }
    cosT = sqrt(max(0.0f, 1.0f - sin2T));
    float rs = (cosI - eta * cosT) / (cosI + eta * cosT);
    float rp = (eta * cosI - cosT) / (eta * cosI + cosT);
    return 0.5f * (rs * rs + rp * rp);
}

SHADER_NAMESPACE_END

#endif
