// Scene access shared by photon_trace.comp and gather.comp (GLSL only): the scene buffers, the
// scene switches (same specialisation ids as path_trace), ray offsets, emission, light picking,
// specular scattering, and the photon map reached by device address.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(constant_id = kSpecHasSpheres) const bool kHasSpheres = true;
layout(constant_id = kSpecHasDisks) const bool kHasDisks = true;
layout(constant_id = kSpecHasSpecular) const bool kHasSpecular = true;
layout(constant_id = kSpecLightCount) const uint kLightCount = 0u;
layout(constant_id = kSpecTwoSided) const bool kTwoSided = true;
layout(constant_id = kSpecRayEpsilon) const float kRayEpsilon = 1e-5;
layout(constant_id = kSpecPhotonMaxBounces) const uint kPhotonMaxBounces = 64u;
layout(constant_id = kSpecPhotonNextEvent) const bool kNextEvent = true;

layout(std430, binding = kBindingPrims) readonly buffer PrimBuffer { Prim prims[]; };
layout(std430, binding = kBindingBvh) readonly buffer BvhBuffer { BvhNode nodes[]; };
layout(std430, binding = kBindingMaterials) readonly buffer MaterialBuffer { MaterialGpu materials[]; };
layout(std430, binding = kBindingLights) readonly buffer LightBuffer { LightGpu lights[]; };

#define BVH_NODE(i) nodes[i]
#define BVH_PRIM(i) prims[i]
#include "shared/intersect.h"

layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonMapRef { PhotonMapHeader h; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonArrayRef { Photon p[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintArrayRef { uint v[]; };

#include "scene_common.glsl"

// A uniform point on an emissive prim and its emitting normal.
void sampleLightPoint(Prim pr, float u1, float u2, out vec3 q, out vec3 nq) {
    if (kHasSpheres && pr.type == kPrimSphere) {
        nq = sampleUniformSphere(u1, u2);
        q = pr.p0 + nq * pr.p1.x;
    } else if (kHasDisks && pr.type == kPrimDisk) {
        q = sampleDisk(pr.p0, pr.n, pr.p1.x, u1, u2);
        nq = pr.n;
    } else {
        q = sampleTriangle(pr.p0, pr.p1, pr.p2, u1, u2);
        nq = pr.n;
    }
}

// Mirror or smooth dielectric (reflect with probability F, else refract), as path_trace does;
// returns the throughput factor. n faces the incoming ray.
vec3 scatterSpecular(MaterialGpu m, bool front, vec3 n, inout vec3 dir, inout Rng rng) {
    if (m.type == kBsdfMirror) {
        dir = reflect(dir, n);
        return m.albedo;
    }
    float eta = front ? m.ior : 1.0 / m.ior;  // n_transmitted / n_incident
    float cosI = -dot(dir, n);
    float cosT;
    float F = fresnelDielectric(cosI, eta, cosT);
    bool refract = (m.flags & kMaterialRefraction) != 0u;
    if (!refract || rngNext(rng) < F) {
        dir = reflect(dir, n);
        return refract ? m.albedo : m.albedo * F;
    }
    dir = normalize(dir / eta + n * (cosI / eta - cosT));
    return m.albedo;
}
