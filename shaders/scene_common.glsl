// Scene helpers shared by the path tracer and the photon passes (GLSL only; included after the
// scene buffers (textureData[] among them), intersect.h and the specialisation constants
// kRayEpsilon, kLightCount, kHasSpheres, kHasDisks, kHasTextures and kBsdfFamilies). The
// CPU-tested parts live in shared/ (bsdf.h, emitter.h, texture.h).
#ifndef TELESCOPE_SCENE_COMMON_GLSL
#define TELESCOPE_SCENE_COMMON_GLSL
#include "shared/bsdf.h"
#include "shared/emitter.h"
#include "shared/texture.h"

// ---- Shading normals ----
layout(std430, binding = kBindingShadingNormals) readonly buffer ShadingNormalBuffer { vec4 shadingNormals[]; };
layout(binding = kBindingShadingNormalTexels) uniform usamplerBuffer shadingNormalTexels;
vec4 shadingNormalData(uint i) {
    if (kSceneTexels) return uintBitsToFloat(texelFetch(shadingNormalTexels, int(i)));
    return shadingNormals[i];
}

// The normal the BSDF sees at a hit of prim slot `prim` (bary: the weights of p1 and p2): a
// smooth-shaded triangle's vertex normals interpolated and normalised (Tungsten's
// TriangleMesh::normalAt), else the geometric normal ng. As in Tungsten, the side a ray arrives
// from is then read off this normal (the BSDF's frame), while ray offsets, media and one-sided
// emission keep ng.
vec3 shadingNormal(uint prim, vec2 bary, vec3 ng) {
    if (!kSmoothNormals) return ng;
    vec4 a = shadingNormalData(3u * prim);
    if (a.w == 0.0) return ng;
    vec3 n = (1.0 - bary.x - bary.y) * a.xyz + bary.x * shadingNormalData(3u * prim + 1u).xyz +
             bary.y * shadingNormalData(3u * prim + 2u).xyz;
    float l = length(n);
    return l > 0.0 ? n / l : ng;
}

// ---- The material at a hit ----
// Its textured parameters looked up at the hit's uv (only materials with a texture pay for the
// uv; kHasTextures folds all of it out of scenes without textures).
void applyTextures(inout MaterialGpu m, Prim pr, uint slot, vec2 bary, vec3 p) {
    if (m.albedoTexture == kNoTexture && m.roughnessTexture == kNoTexture) return;
    vec2 uv = primUv(slot, primShape(pr), bary, p, pr.p0);
    if (m.albedoTexture != kNoTexture) {
        m.albedo = textureValue(m.albedoTexture, uv);
        // Plastics: the substrate's share of the sampling follows the albedo (layered.h).
        m.substrateWeight = (m.albedo.x + m.albedo.y + m.albedo.z) / 3.0 * exp(-2.0 * (m.k.x + m.k.y + m.k.z) / 3.0);
    }
    if (m.roughnessTexture != kNoTexture) m.roughness = textureValue(m.roughnessTexture, uv).x;
}

// Mixed and transparency materials resolved to one material (index and value, textures applied)
// or a straight pass (true):
// - mixed: component 0 with probability ratio, else component 1, with the mixed albedo as weight.
//   Every estimate at this vertex (next-event estimation, BSDF sampling, the MIS weights between
//   them, a photon stored or gathered there) is then the component's own unbiased estimator, so
//   the expectation is ratio E[0] + (1 - ratio) E[1]: the integral of the mixture ratio f0 +
//   (1 - ratio) f1. (Tungsten samples the mixture as one BSDF; the expectation is the same.)
// - transparency: straight on with probability 1 - alpha (weight 1), else its base (weight 1);
//   Tungsten's handleSurface draws the same way.
bool resolveComposite(inout MaterialGpu m, inout uint index, inout vec3 throughput, Prim pr, uint slot, vec2 bary,
                      vec3 p, inout Rng rng) {
    for (uint level = 0u; level < kMaxMaterialNesting; ++level) {
        if ((kBsdfFamilies & kFamilyMixed) != 0u && m.type == kBsdfMixed) {
            throughput *= m.albedo;
            index = mixedComponent(m, rngNext(rng));
        } else if ((kBsdfFamilies & kFamilyTransparency) != 0u && m.type == kBsdfTransparency) {
            if (rngNext(rng) >= m.alpha) return true;
            index = m.component0;
        } else {
            break;
        }
        m = sceneMaterial(index);
        if (kHasTextures) applyTextures(m, pr, slot, bary, p);  // the component's own textures
    }
    return false;
}

// Offset along the geometric normal, to the side the next ray leaves from.
vec3 offsetRayOrigin(vec3 p, vec3 ng, vec3 dir) {
    float scale = max(max(abs(p.x), abs(p.y)), abs(p.z));
    float eps = max(kRayEpsilon, 4e-6 * scale);
    return p + (dot(dir, ng) >= 0.0 ? ng : -ng) * eps;
}

// Smallest light index whose inclusive cdf exceeds u (lights are picked by power).
uint pickLight(float u) {
    uint lo = 0u, hi = kLightCount - 1u;
    while (lo < hi) {
        LOOP_BUDGET_TICK(1u);
        uint mid = (lo + hi) >> 1u;
        if (u < sceneLight(mid).cdf) hi = mid;
        else lo = mid + 1u;
    }
    return lo;
}

// Emitted radiance towards -dir at a point of prim with geometric normal ng (one-sided).
vec3 primEmission(Prim pr, vec3 dir, vec3 ng) {
    if (pr.light < 0 || dot(dir, ng) >= 0.0) return vec3(0.0);
    return sceneLight(uint(pr.light)).radiance;
}

// ---- Lights ----
// Radiance of the environment light along dir and the solid-angle density with which light
// sampling picks dir (path_trace only: with an image, kEnvironmentMap and shared/environment_map.h).
vec3 environmentRadiance(LightGpu env, vec3 dir) {
#ifdef ENV_DATA
    if (kEnvironmentMap) return envRadiance(dir);
#endif
    return env.radiance;
}
float environmentPdf(LightGpu env, vec3 dir) {
#ifdef ENV_DATA
    if (kEnvironmentMap) return env.pmf * envPdf(dir);
#endif
    return env.pmf / (4.0 * kPi);
}

// Solid-angle density with which next-event estimation picks a point on an emissive prim.
float areaLightPdf(uint lightIndex, float area, float dist, float cosLight) {
    return sceneLight(lightIndex).pmf * dist * dist / max(cosLight * area, 1e-30);
}

// One light picked by power and a direction towards it from p: the shadow-ray length, the
// incident radiance divided by the solid-angle pdf, and that pdf (0 for point lights: no MIS).
struct LightSample {
    vec3 wi;
    float dist;
    vec3 weight;
    float pdf;
};

// u: the light pick (x) and the point on it (y, z).
bool sampleLightWith(vec3 p, vec3 u, out LightSample ls) {
    uint li = pickLight(u.x);
    LightGpu light = sceneLight(li);
    float u1 = u.y, u2 = u.z;
    ls.pdf = 0.0;
    // Each kind's code only where the scene has that kind (lanes with masks run every branch).
    if (kHasPointLights) {
        if (light.type == kLightPoint) {
            vec3 d = light.position - p;
            ls.dist = length(d);
            ls.wi = d / ls.dist;
            ls.weight = light.radiance / (ls.dist * ls.dist * light.pmf);
            return true;
        }
    }
    if (kCapLight != 0xffffffffu) {
        if (light.type == kLightCap) {
            // Uniform in the cone of directions (Tungsten's infinite_sphere_cap)
            ls.wi = sampleUniformCone(light.position, light.cosCap, u1, u2);
            ls.dist = kInfinity;
            ls.pdf = light.pmf / (2.0 * kPi * (1.0 - light.cosCap));
            ls.weight = light.radiance / ls.pdf;
            return true;
        }
    }
    if (kEnvironmentLight != 0xffffffffu) {
        if (light.type == kLightEnvironment) {
            ls.dist = kInfinity;
#ifdef ENV_DATA
            if (kEnvironmentMap) {
                // Importance-sampled image (shared/environment_map.h, Tungsten's InfiniteSphere::sampleDirect)
                vec2 uv;
                float pdf;
                if (!envSample(vec2(u1, u2), ls.wi, uv, pdf)) return false;
                ls.pdf = light.pmf * pdf;
                ls.weight = envLookup(uv) / ls.pdf;
                return true;
            }
#endif
            ls.wi = sampleUniformSphere(u1, u2);
            ls.pdf = light.pmf / (4.0 * kPi);
            ls.weight = light.radiance / ls.pdf;
            return true;
        }
    }
    // Area light: a uniform point on the emissive prim.
    Prim pr = BVH_PRIM(light.prim);
    vec3 q, nq;
    sampleEmitterPoint(pr, kHasSpheres, kHasDisks, u1, u2, q, nq);
    vec3 d = q - p;
    ls.dist = length(d);
    ls.wi = d / max(ls.dist, 1e-30);
    float cosL = -dot(ls.wi, nq);
    if (cosL <= 0.0 || !(ls.dist > 0.0)) return false;
    ls.pdf = areaLightPdf(li, pr.area, ls.dist, cosL);
    ls.weight = light.radiance / ls.pdf;
    ls.dist *= 1.0 - 1e-4;  // stop short of the light itself
    return true;
}

// The three random numbers of a light sample, in the order sampleLight draws them.
vec3 lightSampleNumbers(inout Rng rng) {
    float u0 = rngNext(rng);
    float u1 = rngNext(rng);
    float u2 = rngNext(rng);
    return vec3(u0, u1, u2);
}

bool sampleLight(vec3 p, inout Rng rng, out LightSample ls) { return sampleLightWith(p, lightSampleNumbers(rng), ls); }

// ---- Shadow rays past pass-through surfaces ----
// Thin sheets and transparency let shadow rays through (Tungsten's generalizedShadowRay
// multiplies by every surface's forward transmittance): the kFamilyPassThrough families.
const bool kHasPassThrough = (kBsdfFamilies & kFamilyPassThrough) != 0u;

vec3 primNormalAt(Prim pr, vec3 p) {
    if (kHasSpheres && primShape(pr) == kPrimSphere) return normalize(p - pr.p0);
    return pr.n;
}

// Forward transmittance of material m for a ray at |cos| cosI (shared/bsdf.h; Tungsten's
// eval of the forward lobe): a thin sheet's T, 1 - alpha for transparency, 1 for a forward
// boundary, 0 for the rest; a mixed material picks one component by its ratio (an unbiased
// estimate of the ratio-weighted sum) and weighs it by its albedo.
vec3 passThroughTransmittance(MaterialGpu m, float cosI, inout Rng rng) {
    vec3 w = vec3(1.0);
    for (uint level = 0u; level < kMaxMaterialNesting && m.type == kBsdfMixed; ++level) {
        w *= m.albedo;
        m = sceneMaterial(mixedComponent(m, rngNext(rng)));
    }
    if (m.type == kBsdfTransparency) return w * (1.0 - m.alpha);
    if (m.type == kBsdfForward) return w;
    if (m.type == kBsdfThinSheet) {
        vec3 t;
        thinSheetReflectance(m, cosI, t);
        return w * t;
    }
    return vec3(0.0);
}

// A shadow ray from o along d (up to tMax) that met a surface at hit: the transmittance of
// passing it, with o moved past it, tMax shortened and the surface's geometric normal in ng.
vec3 shadowPass(Hit hit, inout vec3 o, vec3 d, inout float tMax, inout Rng rng, out vec3 ng) {
    Prim pr = BVH_PRIM(hit.prim);
    vec3 p = o + d * hit.t;
    ng = primNormalAt(pr, p);
    // Without pass-through families only forward boundaries get here (shadowTransmittance stops at
    // every other surface), and they pass everything: lanes with masks would otherwise run the
    // material load and the nesting loop of passThroughTransmittance on every shadow ray (12% of
    // the volumetric caustic's time, docs/BENCHMARKS.tungsten-notes.md).
    vec3 tr = vec3(1.0);
    if (kHasPassThrough) tr = passThroughTransmittance(sceneMaterial(pr.material), abs(dot(d, ng)), rng);
    o = offsetRayOrigin(p, ng, d);
    if (tMax < kInfinity) tMax = max(tMax - hit.t, 0.0);
    return tr;
}

// Transmittance of a shadow ray in a scene without media (the photon passes): 1 or 0 by one
// any-hit query, or with pass-through surfaces the product over the surfaces it crosses (counted
// in crossings: each is a bounce, as in the path tracer's shadowTransmittance).
vec3 surfaceShadow(vec3 o, vec3 d, float tMax, inout Rng rng, out uint crossings) {
    crossings = 0u;
    if (!kHasPassThrough) return traceAny(o, d, tMax) ? vec3(0.0) : vec3(1.0);
    vec3 tr = vec3(1.0);
    for (uint guard = 0u; guard < 256u; ++guard) {
        Hit hit;
        if (!traceClosest(o, d, tMax, hit)) return tr;
        vec3 ng;
        tr *= shadowPass(hit, o, d, tMax, rng, ng);
        if (tr == vec3(0.0)) return tr;
        ++crossings;
    }
    return vec3(0.0);
}

#endif
