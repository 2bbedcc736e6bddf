// Microfacet distributions (Beckmann, Phong, GGX), Smith shadowing, conductor Fresnel and the
// glossy BSDFs built from them, following Tungsten's conventions (bsdfs/Microfacet.hpp,
// Fresnel.hpp, RoughConductorBsdf.cpp): every routine works in the local shading frame (z = the
// normal), wi points towards the viewer, wo towards the light or the sampled direction, and the
// "eval" value is f(wi, wo) |cos wo|, so that sampling weights are eval / pdf.
// CPU-tested in tests/unit/microfacet_test.cpp (chi-square, white furnace, reciprocity).
#ifndef TELESCOPE_MICROFACET_H
#define TELESCOPE_MICROFACET_H

#include "shared/lang.h"
#include "shared/enums.h"
#include "shared/sampling.h"

SHADER_NAMESPACE_BEGIN

// Tungsten's roughness -> alpha: alpha = roughness (Beckmann, GGX), the Phong exponent
// 2 / roughness^2 - 2; roughness is clamped to 1e-3 first.
FN float microfacetAlpha(uint dist, float roughness) {
    float r = max(roughness, 1e-3f);
    return dist == kMicrofacetPhong ? 2.0f / (r * r) - 2.0f : r;
}

// Distribution of normals D(m), normalised so that the integral of D(m) m.z over the
// hemisphere is 1.
FN float microfacetD(uint dist, float alpha, vec3 m) {
    if (m.z <= 0.0f) return 0.0f;
    float cos2 = m.z * m.z;
    float tan2 = max(1.0f - cos2, 0.0f) / cos2;
    if (dist == kMicrofacetBeckmann) {
        float a2 = alpha * alpha;
        return kInvPi * exp(-tan2 / a2) / (a2 * cos2 * cos2);
    }
    if (dist == kMicrofacetPhong) return (alpha + 2.0f) * (0.5f * kInvPi) * pow(m.z, alpha);
    float a2 = alpha * alpha;  // GGX
    float s = a2 + tan2;
    return a2 * kInvPi / (cos2 * cos2 * s * s);
}

// Smith's masking term for direction v and microfacet normal m (Walter et al. 2007: the exact
// GGX form, the rational approximation for Beckmann and Phong).
FN float microfacetG1(uint dist, float alpha, vec3 v, vec3 m) {
    if (dot(v, m) * v.z <= 0.0f) return 0.0f;
    float cos2 = v.z * v.z;
    float tan2 = max(1.0f - cos2, 0.0f) / cos2;
    if (dist == kMicrofacetGGX) return 2.0f / (1.0f + sqrt(1.0f + alpha * alpha * tan2));
    float tanT = sqrt(tan2);
    float a = dist == kMicrofacetBeckmann ? 1.0f / (alpha * tanT) : sqrt(0.5f * alpha + 1.0f) / tanT;
    if (a >= 1.6f) return 1.0f;
    return (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
}

FN float microfacetG(uint dist, float alpha, vec3 wi, vec3 wo, vec3 m) {
    return microfacetG1(dist, alpha, wi, m) * microfacetG1(dist, alpha, wo, m);
}

// Density of sampleMicrofacetNormal over solid angle: D(m) m.z.
FN float microfacetPdf(uint dist, float alpha, vec3 m) { return microfacetD(dist, alpha, m) * m.z; }

// A normal drawn with density D(m) m.z by inversion of its cdf in theta.
FN vec3 sampleMicrofacetNormal(uint dist, float alpha, float u1, float u2) {
    float cosT;
    if (dist == kMicrofacetBeckmann) {
        cosT = 1.0f / sqrt(1.0f - alpha * alpha * log(1.0f - u1));
    } else if (dist == kMicrofacetPhong) {
        cosT = pow(u1, 1.0f / (alpha + 2.0f));
    } else {
        cosT = 1.0f / sqrt(1.0f + alpha * alpha * u1 / (1.0f - u1));
    }
    float sinT = sqrt(max(1.0f - cosT * cosT, 0.0f));
    float phi = 2.0f * kPi * u2;
    return vec3(cos(phi) * sinT, sin(phi) * sinT, cosT);
}

// Unpolarised Fresnel reflectance of a conductor with complex index eta + i k (relative to the
// outside), for the cosine c of the angle of incidence (Born and Wolf's form as in Shirley 1991).
FN float fresnelConductor1(float eta, float k, float c) {
    float c2 = c * c;
    float s2 = max(1.0f - c2, 0.0f);
    float t = eta * eta - k * k - s2;
    float ab = sqrt(max(t * t + 4.0f * eta * eta * k * k, 0.0f));  // a^2 + b^2
    float a = sqrt(max(0.5f * (ab + t), 0.0f));
    float rs = (ab + c2 - 2.0f * a * c) / (ab + c2 + 2.0f * a * c);
    float rp = rs * (ab * c2 + s2 * s2 - 2.0f * a * c * s2) / (ab * c2 + s2 * s2 + 2.0f * a * c * s2);
    return 0.5f * (rs + rp);
}

FN vec3 fresnelConductor(vec3 eta, vec3 k, float c) {
    return vec3(fresnelConductor1(eta.x, k.x, c), fresnelConductor1(eta.y, k.y, c), fresnelConductor1(eta.z, k.z, c));
}

// Reflectance of a smooth dielectric boundary seen from the side whose cosine is c: c >= 0 from
// outside (index 1 into ior), c < 0 from inside (ior into 1, total internal reflection included).
// cosT: the cosine of the refracted direction (0 under total internal reflection).
FN float fresnelDielectricSigned(float c, float ior, OUT(float) cosT) {
    return c >= 0.0f ? fresnelDielectric(c, ior, cosT) : fresnelDielectric(-c, 1.0f / ior, cosT);
}

FN float fresnelDielectricSigned(float c, float ior) {
    float cosT;
    return fresnelDielectricSigned(c, ior, cosT);
}

// ---- Rough conductor: F(wi.m) D G / (4 |wi.z|), sampled by D(m) m.z ----
// eta, k: the complex index per channel; `scale` multiplies the result (the albedo).

FN vec3 roughConductorEval(uint dist, float roughness, vec3 eta, vec3 k, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return vec3(0.0f);
    float alpha = microfacetAlpha(dist, roughness);
    vec3 m = normalize(wi + wo);
    float fr = microfacetG(dist, alpha, wi, wo, m) * microfacetD(dist, alpha, m) * 0.25f / wi.z;
    return fresnelConductor(eta, k, dot(wi, m)) * fr;
}

FN float roughConductorPdf(uint dist, float roughness, vec3 wi, vec3 wo) {
    if (wi.z <= 0.0f || wo.z <= 0.0f) return 0.0f;
    float alpha = microfacetAlpha(dist, roughness);
    vec3 m = normalize(wi + wo);
    return microfacetPdf(dist, alpha, m) * 0.25f / dot(wi, m);
}

// Draws wo; returns false when the sample is lost (below the surface). weight = eval / pdf.
FN bool roughConductorSample(uint dist, float roughness, vec3 eta, vec3 k, vec3 wi, vec2 u, OUT(vec3) wo,
                             OUT(vec3) weight, OUT(float) pdf) {
    wo = vec3(0.0f);
    weight = vec3(0.0f);
    pdf = 0.0f;
    if (wi.z <= 0.0f) return false;
    float alpha = microfacetAlpha(dist, roughness);
    vec3 m = sampleMicrofacetNormal(dist, alpha, u.x, u.y);
    float wiDotM = dot(wi, m);
    wo = 2.0f * wiDotM * m - wi;
    if (wiDotM <= 0.0f || wo.z <= 0.0f) return false;
    float mPdf = microfacetPdf(dist, alpha, m);
    if (!(mPdf > 0.0f)) return false;
    pdf = mPdf * 0.25f / wiDotM;
    float w = wiDotM * microfacetG(dist, alpha, wi, wo, m) * microfacetD(dist, alpha, m) / (wi.z * mPdf);
    weight = fresnelConductor(eta, k, wiDotM) * w;
    return true;
}

// ---- Rough dielectric (Walter et al. 2007 as in Tungsten): reflection and, when `refracts`,
// refraction through a boundary of index ior whose outside is local +z; wi.z < 0 is inside.
// eval is Walter's radiance BSDF times |cos wo|; sampled with Walter's widened roughness
// (1.2 - 0.2 sqrt(|cos wi|)) roughness, the Fresnel term picking reflection or refraction ----

FN float microfacetSampleRoughness(float roughness, float cosI) { return (1.2f - 0.2f * sqrt(abs(cosI))) * roughness; }

FN float signNonZero(float x) { return x < 0.0f ? -1.0f : 1.0f; }

// The microfacet normal joining wi and wo (oriented to +z) and eta = n(wi side) / n(wo side).
FN vec3 roughDielectricHalfVector(float ior, vec3 wi, vec3 wo, bool reflect, OUT(float) eta) {
    eta = wi.z < 0.0f ? ior : 1.0f / ior;
    if (reflect) return signNonZero(wi.z) * normalize(wi + wo);
    return -normalize(wi * eta + wo);
}

FN vec3 roughDielectricEval(uint dist, float roughness, float ior, bool refracts, vec3 wi, vec3 wo) {
    if (wi.z == 0.0f) return vec3(0.0f);
    bool reflect = wi.z * wo.z >= 0.0f;
    if (!reflect && !refracts) return vec3(0.0f);
    float alpha = microfacetAlpha(dist, roughness);
    float eta;
    vec3 m = roughDielectricHalfVector(ior, wi, wo, reflect, eta);
    float wiDotM = dot(wi, m), woDotM = dot(wo, m);
    float F = fresnelDielectricSigned(wiDotM, ior);
    float GD = microfacetG(dist, alpha, wi, wo, m) * microfacetD(dist, alpha, m);
    if (reflect) return vec3(F * GD * 0.25f / abs(wi.z));
    float s = eta * wiDotM + woDotM;
    return vec3(abs(wiDotM * woDotM) * (1.0f - F) * GD / (s * s * abs(wi.z)));
}

FN float roughDielectricPdf(uint dist, float roughness, float ior, bool refracts, vec3 wi, vec3 wo) {
    if (wi.z == 0.0f) return 0.0f;
    bool reflect = wi.z * wo.z >= 0.0f;
    if (!reflect && !refracts) return 0.0f;
    float sampleAlpha = microfacetAlpha(dist, microfacetSampleRoughness(roughness, wi.z));
    float eta;
    vec3 m = roughDielectricHalfVector(ior, wi, wo, reflect, eta);
    float wiDotM = dot(wi, m), woDotM = dot(wo, m);
    // Back-facing microfacets: eval is 0 there (G = 0) and the sampler never returns them.
    if (wiDotM * wi.z <= 0.0f || woDotM * wo.z <= 0.0f) return 0.0f;
    float pm = microfacetPdf(dist, sampleAlpha, m);
    float pdf;
    if (reflect) {
        pdf = pm * 0.25f / abs(wiDotM);
    } else {
        float s = eta * wiDotM + woDotM;
        pdf = pm * abs(woDotM) / (s * s);
    }
    if (refracts) {
        float F = fresnelDielectricSigned(wiDotM, ior);
        pdf *= reflect ? F : 1.0f - F;
    }
    return pdf;
}

FN bool roughDielectricSample(uint dist, float roughness, float ior, bool refracts, vec3 wi, vec3 u, OUT(vec3) wo,
                              OUT(vec3) weight, OUT(float) pdf) {
    wo = vec3(0.0f);
    weight = vec3(0.0f);
    pdf = 0.0f;
    if (wi.z == 0.0f) return false;
    float alpha = microfacetAlpha(dist, roughness);
    float sampleAlpha = microfacetAlpha(dist, microfacetSampleRoughness(roughness, wi.z));
    vec3 m = sampleMicrofacetNormal(dist, sampleAlpha, u.x, u.y);
    float pm = microfacetPdf(dist, sampleAlpha, m);
    if (pm < 1e-10f) return false;
    float wiDotM = dot(wi, m);
    // A microfacet facing away from wi has G = 0: lost (Tungsten carries on with weight 0).
    if (wiDotM * wi.z <= 0.0f) return false;
    float cosT;
    float F = fresnelDielectricSigned(wiDotM, ior, cosT);
    float etaM = wiDotM < 0.0f ? ior : 1.0f / ior;
    bool reflect = !refracts || u.z < F;
    if (reflect) wo = 2.0f * wiDotM * m - wi;
    else wo = (etaM * wiDotM - signNonZero(wiDotM) * cosT) * m - etaM * wi;
    if ((wi.z * wo.z > 0.0f) != reflect) return false;
    float woDotM = dot(wo, m);
    if (woDotM * wo.z <= 0.0f) return false;
    float w = abs(wiDotM) * microfacetG(dist, alpha, wi, wo, m) * microfacetD(dist, alpha, m) / (abs(wi.z) * pm);
    if (reflect) {
        pdf = pm * 0.25f / abs(wiDotM);
    } else {
        float eta = wi.z < 0.0f ? ior : 1.0f / ior;
        float s = eta * wiDotM + woDotM;
        pdf = pm * abs(woDotM) / (s * s);
    }
    if (refracts) pdf *= reflect ? F : 1.0f - F;
    else w *= F;
    weight = vec3(w);
    return pdf > 0.0f;
}

SHADER_NAMESPACE_END

#endif
