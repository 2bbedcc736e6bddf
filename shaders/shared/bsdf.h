// Scattering at surfaces, shared by the path tracer, the photon tracer and the gather's camera
// chain. One source for GLSL and C++ (tests/unit/bsdf_test.cpp).
#ifndef TELESCOPE_BSDF_H
#define TELESCOPE_BSDF_H

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"
#include "shared/microfacet.h"
#include "shared/layered.h"

// The material families a pass is compiled for: GLSL passes define it as their kSpecBsdfFamilies
// specialisation constant before including this file, so the branches of the families a scene
// lacks fold away on the host (src/gpu/pipeline.cpp); C++ compiles every family.
#ifndef BSDF_FAMILIES
#define BSDF_FAMILIES kFamilyAll
#endif

SHADER_NAMESPACE_BEGIN

// Materials that scatter into one direction (a Dirac delta): scatterSpecular.
FN bool isSpecularBsdf(uint type) {
    return type == kBsdfMirror || type == kBsdfDielectric || type == kBsdfConductor;
}

// Materials other than Lambert with a non-delta lobe, handled in the local shading frame
// (glossy*; plastic also has a Dirac lobe, sampled there).
FN bool isGlossyBsdf(uint type) { return type >= kBsdfRoughConductor && type <= kBsdfRoughDielectric; }

FN uint bsdfFamily(uint type) {
    if (type == kBsdfRoughConductor) return kFamilyRoughConductor;
    if (type == kBsdfPlastic) return kFamilyPlastic;
    if (type == kBsdfRoughPlastic) return kFamilyRoughPlastic;
    if (type == kBsdfOrenNayar) return kFamilyOrenNayar;
    if (type == kBsdfRoughDielectric) return kFamilyRoughDielectric;
    return 0u;
}

FN PlasticParams plasticParams(MaterialGpu m) {
    PlasticParams p;
    p.albedo = m.albedo;
    p.ior = m.ior;
    p.diffuseFresnel = m.diffuseFresnel;
    p.tau = m.k;
    p.substrateWeight = m.substrateWeight;
    return p;
}

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
    if (m.type == kBsdfConductor) {
        float c = -dot(dir, n);
        dir = reflect(dir, n);
        return m.albedo * fresnelConductor(m.eta, m.k, c);
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

// ---- Glossy materials in the local frame (z = the shading normal facing the viewer, wi towards
// the viewer; for rough_dielectric z is the outward normal and wi.z < 0 inside): eval is
// f(wi, wo) |cos wo| and a sample's weight is eval / pdf, as in Tungsten ----

FN vec3 glossyEval(MaterialGpu m, vec3 wi, vec3 wo) {
    if ((BSDF_FAMILIES & kFamilyRoughConductor) != 0u && m.type == kBsdfRoughConductor)
        return m.albedo * roughConductorEval(m.distribution, m.roughness, m.eta, m.k, wi, wo);
    if ((BSDF_FAMILIES & kFamilyPlastic) != 0u && m.type == kBsdfPlastic) return plasticEval(plasticParams(m), wi, wo);
    if ((BSDF_FAMILIES & kFamilyRoughPlastic) != 0u && m.type == kBsdfRoughPlastic)
        return roughPlasticEval(plasticParams(m), m.distribution, m.roughness, wi, wo);
    if ((BSDF_FAMILIES & kFamilyOrenNayar) != 0u && m.type == kBsdfOrenNayar)
        return orenNayarEval(m.albedo, m.roughness, wi, wo);
    if ((BSDF_FAMILIES & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric)
        return m.albedo * roughDielectricEval(m.distribution, m.roughness, m.ior, (m.flags & kMaterialRefraction) != 0u, wi, wo);
    return vec3(0.0f);
}

FN float glossyPdf(MaterialGpu m, vec3 wi, vec3 wo) {
    if ((BSDF_FAMILIES & kFamilyRoughConductor) != 0u && m.type == kBsdfRoughConductor)
        return roughConductorPdf(m.distribution, m.roughness, wi, wo);
    if ((BSDF_FAMILIES & kFamilyPlastic) != 0u && m.type == kBsdfPlastic) return plasticPdf(plasticParams(m), wi, wo);
    if ((BSDF_FAMILIES & kFamilyRoughPlastic) != 0u && m.type == kBsdfRoughPlastic)
        return roughPlasticPdf(plasticParams(m), m.distribution, m.roughness, wi, wo);
    if ((BSDF_FAMILIES & kFamilyOrenNayar) != 0u && m.type == kBsdfOrenNayar) return orenNayarPdf(m.roughness, wi, wo);
    if ((BSDF_FAMILIES & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric)
        return roughDielectricPdf(m.distribution, m.roughness, m.ior, (m.flags & kMaterialRefraction) != 0u, wi, wo);
    return 0.0f;
}

// Draws wo from the material's sampling routine: false when the sample is lost. `specular` says
// the sample came from a Dirac lobe (its pdf is then not a solid-angle density).
FN bool glossySample(MaterialGpu m, vec3 wi, INOUT(Rng) rng, OUT(vec3) wo, OUT(vec3) weight, OUT(float) pdf,
                     OUT(bool) specular) {
    specular = false;
    float u1 = rngNext(rng), u2 = rngNext(rng);
    if ((BSDF_FAMILIES & kFamilyRoughConductor) != 0u && m.type == kBsdfRoughConductor) {
        bool ok = roughConductorSample(m.distribution, m.roughness, m.eta, m.k, wi, vec2(u1, u2), wo, weight, pdf);
        weight *= m.albedo;
        return ok;
    }
    if ((BSDF_FAMILIES & kFamilyPlastic) != 0u && m.type == kBsdfPlastic)
        return plasticSample(plasticParams(m), wi, vec3(u1, u2, rngNext(rng)), wo, weight, pdf, specular);
    if ((BSDF_FAMILIES & kFamilyRoughPlastic) != 0u && m.type == kBsdfRoughPlastic)
        return roughPlasticSample(plasticParams(m), m.distribution, m.roughness, wi, vec3(u1, u2, rngNext(rng)), wo,
                                  weight, pdf);
    if ((BSDF_FAMILIES & kFamilyOrenNayar) != 0u && m.type == kBsdfOrenNayar)
        return orenNayarSample(m.albedo, m.roughness, wi, vec3(u1, u2, rngNext(rng)), wo, weight, pdf);
    if ((BSDF_FAMILIES & kFamilyRoughDielectric) != 0u && m.type == kBsdfRoughDielectric) {
        bool ok = roughDielectricSample(m.distribution, m.roughness, m.ior, (m.flags & kMaterialRefraction) != 0u, wi,
                                        vec3(u1, u2, rngNext(rng)), wo, weight, pdf);
        weight *= m.albedo;
        return ok;
    }
    wo = vec3(0.0f);
    weight = vec3(0.0f);
    pdf = 0.0f;
    return false;
}

SHADER_NAMESPACE_END

#endif
