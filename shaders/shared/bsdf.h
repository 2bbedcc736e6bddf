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
    if (type == kBsdfThinSheet) return kFamilyThinSheet;
    if (type == kBsdfMixed) return kFamilyMixed;
    if (type == kBsdfTransparency) return kFamilyTransparency;
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

// Radiance scaling of a camera path (transported radiance, not flux) that refracted through a smooth
// dielectric: L_i / n_i^2 = L_t / n_t^2 (Veach's thesis, section 5.2), so radiance arriving from the
// transmitted side is (n_i / n_t)^2 times what it was there. A path tracer joins camera and light in
// the same medium, where the factors of a closed path cancel; photon mapping gathers on the far side
// of the interface, and photons carry flux (unscaled): the camera side must carry the factor.
// front: the camera ray arrives from outside (eta = n_t / n_i = ior).
FN float refractionRadianceScale(MaterialGpu m, bool front) {
    float eta = front ? m.ior : 1.0f / m.ior;
    return 1.0f / (eta * eta);
}

// The same for a rough dielectric, where photon mapping gathers at the interface itself: its BTDF
// for light travelling from a to b is n_b^2 S(a, b) with S symmetric (Walter et al. 2007; Veach's
// generalised reciprocity f(a->b) / n_b^2 = f(b->a) / n_a^2). glossyEval(wi, wo) carries n_wo^2:
// f(wi->wo) |cos wo|, the weight a photon arriving from wi and leaving towards wo needs
// (photon_trace.comp samples it so, unchanged). A gather seen from wi, of a photon that arrived from
// wo, needs f(wo->wi), i.e. glossyEval times this ratio: 1 for reflection, (n_wi / n_wo)^2 for
// refraction (local frame, z outward, wi.z < 0 inside).
FN float roughRefractionRadianceScale(float ior, vec3 wi, vec3 wo) {
    if (wi.z * wo.z >= 0.0f) return 1.0f;
    float eta = wi.z < 0.0f ? ior : 1.0f / ior;
    return eta * eta;
}

// ---- Thin sheet (Tungsten's ThinSheetBsdf and Fresnel::thinFilmReflectance*): a dielectric slab
// of index ior in vacuum, thin enough that the reflected and transmitted rays leave where they
// entered. Reflection is specular, transmission goes straight on (a forward lobe). ----

// Reflectance of the slab from incoherent multiple reflections: with r the single-interface
// reflectance of one polarisation, the slab reflects r + (1 - r)^2 r (1 + r^2 + r^4 + ...) =
// 2 r / (1 + r); the result averages s and p. cosT is the cosine inside the slab (0 when the
// light cannot enter, for ior < 1 past the critical angle; the slab then reflects all).
FN float thinSheetSlabReflectance(float ior, float cosI, OUT(float) cosT) {
    float sin2T = (1.0f - cosI * cosI) / (ior * ior);
    if (sin2T > 1.0f) {
        cosT = 0.0f;
        return 1.0f;
    }
    cosT = sqrt(max(0.0f, 1.0f - sin2T));
    float rs = (cosI - ior * cosT) / (cosI + ior * cosT);
    float rp = (ior * cosI - cosT) / (ior * cosI + cosT);
    rs *= rs;
    rp *= rp;
    return 0.5f * (2.0f * rs / (1.0f + rs) + 2.0f * rp / (1.0f + rp));
}

// Reflectance of a film `nm` nanometres thick with thin-film interference at 650, 510 and 475 nm
// (the R, G and B wavelengths Tungsten uses): the coherent sum of the multiply reflected waves,
// per polarisation 1 - t^2 / (1 + r^2 - 2 r cos phi) with t = 1 - r the single-interface
// transmittance and phi = 4 pi ior nm cos(theta_t) / lambda the phase of one round trip. Averaged
// over phi it is the incoherent slab above.
FN vec3 thinFilmInterferenceReflectance(float ior, float cosI, float nm, OUT(float) cosT) {
    float sin2T = (1.0f - cosI * cosI) / (ior * ior);
    if (sin2T > 1.0f) {
        cosT = 0.0f;
        return vec3(1.0f);
    }
    cosT = sqrt(max(0.0f, 1.0f - sin2T));
    float rs = (cosI - ior * cosT) / (cosI + ior * cosT);
    float rp = (ior * cosI - cosT) / (ior * cosI + cosT);
    rs *= rs;
    rp *= rp;
    vec3 phi = (4.0f * kPi * ior * nm * cosT) / vec3(650.0f, 510.0f, 475.0f);
    vec3 cosPhi = vec3(cos(phi.x), cos(phi.y), cos(phi.z));
    vec3 ts = (1.0f - rs) * (1.0f - rs) / ((1.0f + rs * rs) - 2.0f * rs * cosPhi);
    vec3 tp = (1.0f - rp) * (1.0f - rp) / ((1.0f + rp * rp) - 2.0f * rp * cosPhi);
    return vec3(1.0f) - 0.5f * (ts + tp);
}

// Reflectance R and forward transmittance T of a thin sheet (MaterialGpu: ior, roughness = the
// thickness, k = tau = thickness sigma_a, kMaterialInterference) for |cos| cosI of the incoming
// ray. As in Tungsten, T = (1 - R) exp(-2 tau / cos theta_t) and R ignores the absorption; the
// film of an interfering sheet is 500 nm per unit of thickness.
FN vec3 thinSheetReflectance(MaterialGpu m, float cosI, OUT(vec3) T) {
    float cosT;
    vec3 R;
    if ((m.flags & kMaterialInterference) != 0u) R = thinFilmInterferenceReflectance(m.ior, cosI, m.roughness * 500.0f, cosT);
    else R = vec3(thinSheetSlabReflectance(m.ior, cosI, cosT));
    T = vec3(1.0f) - R;
    if (m.k != vec3(0.0f) && cosT > 0.0f) T *= exp(-2.0f * m.k / cosT);
    return R;
}

// Tungsten's scattering at a thin sheet: straight on with probability p = mean(T), weight T / p;
// else specular reflection with weight R / (1 - p). Returns true for reflection.
FN bool thinSheetScatter(MaterialGpu m, float cosI, float u, OUT(vec3) weight) {
    vec3 T;
    vec3 R = thinSheetReflectance(m, cosI, T);
    float p = (T.x + T.y + T.z) / 3.0f;
    bool plain = m.k == vec3(0.0f) && (m.flags & kMaterialInterference) == 0u;  // T = 1 - R, grey
    if (u < p) {
        weight = plain ? vec3(1.0f) : T / p;
        return false;
    }
    weight = plain ? vec3(1.0f) : R / (1.0f - p);
    return true;
}

// ---- Mixed: the component an event at a mixed material uses, component 0 with probability
// ratio (Tungsten's nextBoolean(ratio) picks bsdf0); u uniform in [0, 1). ----
FN uint mixedComponent(MaterialGpu m, float u) { return u < m.ratio ? m.component0 : m.component1; }

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

// The Dirac lobe among a glossy material's lobes (plastic's smooth coat; none for the others):
// the probability p with which glossySample takes it from wi, and the lobe's reflectance. A camera
// chain of photon mapping (shaders/gather.comp) follows that lobe with probability p, weight
// reflectance / p, and gathers the other lobes with weight 1 / (1 - p).
FN float glossyDiracProbability(MaterialGpu m, vec3 wi) {
    if ((BSDF_FAMILIES & kFamilyPlastic) != 0u && m.type == kBsdfPlastic && wi.z > 0.0f)
        return plasticSpecularProbability(plasticParams(m), wi.z);
    return 0.0f;
}

FN float glossyDiracReflectance(MaterialGpu m, vec3 wi) {
    if ((BSDF_FAMILIES & kFamilyPlastic) != 0u && m.type == kBsdfPlastic && wi.z > 0.0f)
        return fresnelDielectricSigned(wi.z, m.ior);
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
