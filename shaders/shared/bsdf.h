// Scattering at surfaces, shared by the path tracer, the photon tracer and the gather's camera
// chain. One source for GLSL and C++ (tests/unit/bsdf_test.cpp).
#ifndef TELESCOPE_BSDF_H
#define TELESCOPE_BSDF_H

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"

SHADER_NAMESPACE_BEGIN

// Mirror, or smooth dielectric (reflect with probability F, else refract; without refraction the
// reflection is weighted by F). dir is the incoming direction and becomes the scattered one; n is
// the shading normal facing the incoming ray (dot(dir, n) < 0) and `front` says whether the ray
// arrives from outside. Returns the throughput factor. Draws a random number only when the
// material refracts.
FN vec3 scatterSpecular(MaterialGpu m, bool front, vec3 n, INOUT(vec3) dir, INOUT(Rng) rng) {
    if (m.type == kBsdfMirror) {
        dir = reflect(dir, n);
        return m.albedo;
    }
    float eta = front ? m.ior : 1.0f / m.ior;  // n_transmitted / n_incident
    float cosI = -dot(dir, n);
    float cosT;
    float F = fresnelDielectric(cosI, eta, cosT);
    bool refracts = (m.flags & kMaterialRefraction) != 0u;
    if (!refracts || rngNext(rng) < F) {
        dir = reflect(dir, n);
        return refracts ? m.albedo : m.albedo * F;
    }
    dir = normalize(dir / eta + n * (cosI / eta - cosT));
    return m.albedo;
}

SHADER_NAMESPACE_END

#endif
