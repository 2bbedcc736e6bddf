// Plastic, rough plastic and Oren-Nayar, following Tungsten's models (bsdfs/PlasticBsdf.cpp,
// RoughPlasticBsdf.cpp, OrenNayarBsdf.cpp) in the conventions of shared/microfacet.h: local frame,
// wi towards the viewer, eval = f(wi, wo) |cos wo|, sample weight = eval / pdf.
//
// Plastic: a smooth dielectric coat (index ior) over a Lambertian substrate of albedo a, the
// light between them bouncing any number of times: the diffuse lobe is
//   (1 - F(wi)) (1 - F(wo)) / ior^2 a / (1 - a Fdr) |cos wo| / pi  exp(-tau (1/wi.z + 1/wo.z))
// with Fdr the coat's cosine-weighted internal reflectance (diffuseFresnel) and tau = thickness
// sigma_a. The coat's reflection is a Dirac lobe of weight F(wi) (plastic) or a microfacet lobe
// (rough plastic); the coat's lobe is picked with probability F / (F + w (1 - F)), w the
// substrate's weight mean(albedo) exp(-2 mean(tau)) (Tungsten's current rule; it changes the
// noise only).
// CPU-tested in tests/unit/microfacet_test.cpp.
#ifndef TELESCOPE_LAYERED_H
#define TELESCOPE_LAYERED_H

#include "shared/lang.h"
#include "shared/microfacet.h"
#include "shared/sampling.h"

SHADER_NAMESPACE_BEGIN

// Parameters of a plastic: ior, the diffuse Fresnel term, tau = thickness sigma_a per channel and
// the substrate's weight in the lobe choice.
struct PlasticParams {
    vec3 albedo;
    float ior;
    float diffuseFresnel;
    vec3 tau;
    float substrateWeight;
};

FN float plasticSpecularProbability(PlasticParams p, float cosI) {
    float fi = fresnelDielectricSigned(cosI, p.ior);
    return fi / (fi + p.substrateWeight * (1.0f - fi));
}

FN vec3 plasticSubstrateEval(PlasticParams p, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return vec3(0.0f);
    float fi = fresnelDielectricSigned(wi.z, p.ior);
    float fo = fresnelDielectricSigned(wo.z, p.ior);
    vec3 f = ((1.0f - fi) * (1.0f - fo) / (p.ior * p.ior) * wo.z * kInvPi) * (p.albedo / (vec3(1.0f) - p.albedo * p.diffuseFresnel));
    if (max(p.tau.x, max(p.tau.y, p.tau.z)) > 0.0f) f *= exp(-p.tau * (1.0f / wo.z + 1.0f / wi.z));
    return f;
}

// ---- Smooth plastic: the substrate lobe here; the coat's mirror lobe is a Dirac delta ----
FN vec3 plasticEval(PlasticParams p, vec3 wi, vec3 wo) { return plasticSubstrateEval(p, wi, wo); }

FN float plasticPdf(PlasticParams p, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    return wo.z * kInvPi * (1.0f - plasticSpecularProbability(p, wi.z));
}

// u.z picks the lobe. specular: the mirror lobe was sampled (pdf is then its probability).
FN bool plasticSample(PlasticParams p, vec3 wi, vec3 u, OUT(vec3) wo, OUT(vec3) weight, OUT(float) pdf,
                      OUT(bool) specular) {
    wo = vec3(0.0f);
    weight = vec3(0.0f);
    pdf = 0.0f;
    specular = false;
    if (wi.z <= 0.0f) return false;
    float ps = plasticSpecularProbability(p, wi.z);
    if (u.z < ps) {
        wo = vec3(-wi.x, -wi.y, wi.z);
        pdf = ps;
        weight = vec3(fresnelDielectricSigned(wi.z, p.ior) / ps);
        specular = true;
        return true;
    }
    wo = sampleCosineHemisphere(vec3(0.0f, 0.0f, 1.0f), u.x, u.y);
    if (wo.z <= 0.0f) return false;
    pdf = wo.z * kInvPi * (1.0f - ps);
    weight = plasticSubstrateEval(p, wi, wo) / pdf;
    return true;
}

// ---- The coat's microfacet reflection (Tungsten's rough dielectric, reflection only) ----
// Sampled with Walter et al.'s widened roughness (1.2 - 0.2 sqrt(|cos wi|)) roughness.

FN vec3 coatEval(uint dist, float roughness, float ior, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return vec3(0.0f);
    float alpha = microfacetAlpha(dist, roughness);
    vec3 m = normalize(wi + wo);
    float F = fresnelDielectricSigned(dot(wi, m), ior);
    return vec3(F * microfacetG(dist, alpha, wi, wo, m) * microfacetD(dist, alpha, m) * 0.25f / wi.z);
}

FN float coatPdf(uint dist, float roughness, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float sampleAlpha = microfacetAlpha(dist, microfacetSampleRoughness(roughness, wi.z));
    vec3 m = normalize(wi + wo);
    return microfacetPdf(dist, sampleAlpha, m) * 0.25f / abs(dot(wi, m));
}

// ---- Rough plastic: coat lobe + substrate lobe, both non-delta ----
FN vec3 roughPlasticEval(PlasticParams p, uint dist, float roughness, vec3 wi, vec3 wo) {
    return coatEval(dist, roughness, p.ior, wi, wo) + plasticSubstrateEval(p, wi, wo);
}

FN float roughPlasticPdf(PlasticParams p, uint dist, float roughness, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float ps = plasticSpecularProbability(p, wi.z);
    return coatPdf(dist, roughness, wi, wo) * ps + wo.z * kInvPi * (1.0f - ps);
}

// One-sample MIS over the two lobes: the weight is eval / pdf of the mixture.
FN bool roughPlasticSample(PlasticParams p, uint dist, float roughness, vec3 wi, vec3 u, OUT(vec3) wo,
                           OUT(vec3) weight, OUT(float) pdf) {
    wo = vec3(0.0f);
    weight = vec3(0.0f);
    pdf = 0.0f;
    if (wi.z <= 0.0f) return false;
    float ps = plasticSpecularProbability(p, wi.z);
    if (u.z < ps) {
        float sampleAlpha = microfacetAlpha(dist, microfacetSampleRoughness(roughness, wi.z));
        vec3 m = sampleMicrofacetNormal(dist, sampleAlpha, u.x, u.y);
        if (microfacetPdf(dist, sampleAlpha, m) < 1e-10f) return false;
        wo = 2.0f * dot(wi, m) * m - wi;
    } else {
        wo = sampleCosineHemisphere(vec3(0.0f, 0.0f, 1.0f), u.x, u.y);
    }
    if (wo.z <= 0.0f) return false;
    pdf = roughPlasticPdf(p, dist, roughness, wi, wo);
    if (!(pdf > 0.0f)) return false;
    weight = roughPlasticEval(p, dist, roughness, wi, wo) / pdf;
    return true;
}

// ---- Oren-Nayar (the full qualitative model with the interreflection term, Oren and Nayar 1994;
// sigma = roughness / sqrt(2)); sampled by a mixture of uniform (probability clamp(roughness,
// 0.01, 1)) and cosine hemisphere sampling ----
FN vec3 orenNayarEval(vec3 albedo, float roughness, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return vec3(0.0f);
    float thetaR = acos(min(wo.z, 1.0f));
    float thetaI = acos(min(wi.z, 1.0f));
    float a = max(thetaR, thetaI);
    float b = min(thetaR, thetaI);
    float denom = (wi.x * wi.x + wi.y * wi.y) * (wo.x * wo.x + wo.y * wo.y);
    float cosDPhi = denom == 0.0f ? 1.0f : (wi.x * wo.x + wi.y * wo.y) / sqrt(denom);
    float s2 = 0.5f * roughness * roughness;
    float c1 = 1.0f - 0.5f * s2 / (s2 + 0.33f);
    float c2 = 0.45f * s2 / (s2 + 0.09f);
    float bb = 2.0f * kInvPi * b;
    c2 *= cosDPhi >= 0.0f ? sin(a) : sin(a) - bb * bb * bb;
    float ab = 4.0f * kInvPi * kInvPi * a * b;
    float c3 = 0.125f * (s2 / (s2 + 0.09f)) * ab * ab;
    float fr1 = c1 + cosDPhi * c2 * tan(b) + (1.0f - abs(cosDPhi)) * c3 * tan(0.5f * (a + b));
    float fr2 = 0.17f * s2 / (s2 + 0.13f) * (1.0f - cosDPhi * bb * bb);
    return (albedo * fr1 + albedo * albedo * fr2) * (wo.z * kInvPi);
}

FN float orenNayarPdf(float roughness, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float ratio = clamp(roughness, 0.01f, 1.0f);
    return ratio * (0.5f * kInvPi) + (1.0f - ratio) * wo.z * kInvPi;
}

FN bool orenNayarSample(vec3 albedo, float roughness, vec3 wi, vec3 u, OUT(vec3) wo, OUT(vec3) weight,
                        OUT(float) pdf) {
    wo = vec3(0.0f);
    weight = vec3(0.0f);
    pdf = 0.0f;
    if (wi.z <= 0.0f) return false;
    float ratio = clamp(roughness, 0.01f, 1.0f);
    if (u.z < ratio) {
        vec3 d = sampleUniformSphere(u.x, u.y);
        wo = vec3(d.x, d.y, abs(d.z));
    } else {
        wo = sampleCosineHemisphere(vec3(0.0f, 0.0f, 1.0f), u.x, u.y);
    }
    if (wo.z <= 0.0f) return false;
    pdf = orenNayarPdf(roughness, wi, wo);
    weight = orenNayarEval(albedo, roughness, wi, wo) / pdf;
    return true;
}

SHADER_NAMESPACE_END

#endif
