// gather: one thread per pixel, one sample per pass. The camera path follows mirror and
// dielectric bounces to the first diffuse vertex, where the photon map gives
//   biased:   Z = K_r                                              (fixed radius or PPM pass radius)
//   unbiased: Z = K_{r_b} + (K_{r_{j+1}} - K_{r_j}) / p(j | j >= b) (level j drawn per pixel here)
// times the Lambert BSDF, plus emission seen along the specular chain and, with
// direct_lighting = next_event, one light sample (no MIS: photons carry no direct light then).
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"
#include "shared/photon_density.h"
#include "photon_scene.glsl"
#include "photon_gather.glsl"
#include "accumulate.glsl"

layout(local_size_x = kGatherGroupSize, local_size_y = kGatherGroupSize) in;

layout(constant_id = kSpecFilter) const uint kFilter = kFilterTent;
layout(constant_id = kSpecPhotonEstimator) const uint kEstimator = kPhotonBiased;
layout(constant_id = kSpecPhotonKernel) const uint kKernel = kKernelCone;
layout(constant_id = kSpecPhotonLevels) const uint kLevels = kPmfPowerLaw;
layout(constant_id = kSpecPhotonPmfR) const float kPmfR = 0.65;
layout(constant_id = kSpecPhotonPmfAlpha) const float kPmfAlpha = 0.6666667;

layout(push_constant) uniform Push { GatherPush pc; };

// Next-event estimation at a Lambertian point: one light picked by power, one shadow ray.
vec3 directLight(vec3 p, vec3 ng, vec3 n, vec3 albedo, inout Rng rng) {
    uint li = pickLight(rngNext(rng));
    LightGpu light = lights[li];
    float u1 = rngNext(rng), u2 = rngNext(rng);
    vec3 wi;
    float dist;
    vec3 value;
    if (light.type == kLightPoint) {
        vec3 d = light.position - p;
        dist = length(d);
        wi = d / dist;
        value = light.radiance * max(dot(n, wi), 0.0) / (dist * dist * light.pmf);
    } else {
        Prim pr = prims[light.prim];
        vec3 q, nq;
        sampleLightPoint(pr, u1, u2, q, nq);
        vec3 d = q - p;
        dist = length(d);
        wi = d / max(dist, 1e-30);
        float cosS = dot(n, wi);
        float cosL = -dot(wi, nq);
        if (cosS <= 0.0 || cosL <= 0.0 || !(dist > 0.0)) return vec3(0.0);
        value = light.radiance * cosS * cosL * pr.area / (dist * dist * light.pmf);
        dist *= 1.0 - 1e-4;  // stop short of the light itself
    }
    if (!any(greaterThan(value, vec3(0.0)))) return vec3(0.0);
    vec3 o = offsetRayOrigin(p, ng, wi);
    if (traceAny(o, wi, max(dist - length(o - p), 0.0))) return vec3(0.0);
    return albedo * kInvPi * value;
}

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= pc.width || pixel.y >= pc.height) return;
    PhotonMapRef map = PhotonMapRef(uvec2(pc.headerLo, pc.headerHi));
    if (map.h.storedCount > map.h.capacity) return;  // photons were dropped: the host repeats the pass
    uint pixelIndex = pixel.y * pc.width + pixel.x;

    // ---- Camera ray and the level of this pixel sample ----
    Rng rng = rngCreate(pixelIndex, pc.pass, pc.seed);
    vec2 jitter = vec2(rngNext(rng), rngNext(rng));
    if (kFilter == kFilterTent) jitter = vec2(sampleTent(jitter.x), sampleTent(jitter.y)) + 0.5;
    else if (kFilter == kFilterDirac) jitter = vec2(0.5);
    float w = float(pc.width);
    vec3 local = vec3(-1.0 + 2.0 * (float(pixel.x) + jitter.x) / w,
                      float(pc.height) / w - 2.0 * (float(pixel.y) + jitter.y) / w, pc.planeDistance);
    vec3 dir = normalize(pc.cameraRight * local.x + pc.cameraUp * local.y + pc.cameraForward * local.z);
    vec3 origin = pc.cameraPosition;

    LevelPmf pmf = LevelPmf(kLevels, kPmfR, kPmfAlpha);
    float j = 0.0;  // 0: no correction (biased, or a level beyond the truncation)
    float u1 = rngNext(rng), u2 = rngNext(rng);
    if (kEstimator == kPhotonUnbiased) j = levelSampleFrom(pmf, pc.baseLevel, u1, u2);

    // ---- Specular chain to the first diffuse vertex ----
    vec3 throughput = vec3(1.0);
    vec3 base = vec3(0.0), correction = vec3(0.0);
    for (uint v = 1u; v <= kPhotonMaxBounces + 1u; ++v) {
        Hit hit;
        if (!traceClosest(origin, dir, kInfinity, hit)) break;
        Prim pr = prims[hit.prim];
        vec3 p = origin + dir * hit.t;
        vec3 ng = pr.n;
        if (kHasSpheres && pr.type == kPrimSphere) {
            ng = normalize(p - pr.p0);
            p = pr.p0 + ng * pr.p1.x;
        }
        base += throughput * primEmission(pr, dir, ng);
        if (v > kPhotonMaxBounces) break;
        MaterialGpu m = materials[pr.material];
        bool front = dot(dir, ng) < 0.0;
        vec3 n = front ? ng : -ng;  // faces the camera path

        if (m.type == kBsdfLambert) {
            if (!front && !kTwoSided) break;
            vec3 f = throughput * m.albedo * kInvPi;
            if (kNextEvent && kLightCount > 0u) base += throughput * directLight(p, ng, n, m.albedo, rng);
            float rb2 = pc.radius * pc.radius;
            bool correct = j > 0.0;
            float logRadius2 = correct ? levelLogRadius2(pmf, j, pc.baseLevel) : 0.0;
            float logStep2 = correct ? levelLogStep2(pmf, j) : 0.0;
            GatherSums sums = gatherPhotons(map, p, n, rb2, correct, logRadius2, logStep2, kKernel);
            base += f * sums.base;
            if (correct) correction = f * sums.difference / levelProbabilityFrom(pmf, j, pc.baseLevel);
            break;
        }
        if (!kHasSpecular || (m.type != kBsdfMirror && m.type != kBsdfDielectric)) break;  // null
        throughput *= scatterSpecular(m, front, n, dir, rng);
        origin = offsetRayOrigin(p, ng, dir);
    }

    // ---- Accumulate: estimate, square, base, correction and its signed parts ----
    vec3 z = base + correction;
    float dropped = 0.0;
    if (any(isnan(z)) || any(isinf(z))) {
        dropped = 1.0;
        z = base = correction = vec3(0.0);
    }
    AccumRef accum = AccumRef(uvec2(pc.accumLo, pc.accumHi));
    uint pixelCount = pc.width * pc.height;
    accumulateAdd(accum, kChannelEstimate, pixelIndex, pixelCount, vec4(z, dropped));
    accumulateAdd(accum, kChannelEstimateSq, pixelIndex, pixelCount, vec4(z * z, 0.0));
    accumulateAdd(accum, kChannelBase, pixelIndex, pixelCount, vec4(base, 0.0));
    accumulateAdd(accum, kChannelCorrection, pixelIndex, pixelCount, vec4(correction, 0.0));
    accumulateAdd(accum, kChannelCorrectionPositive, pixelIndex, pixelCount, vec4(max(correction, vec3(0.0)), 0.0));
    accumulateAdd(accum, kChannelCorrectionNegative, pixelIndex, pixelCount, vec4(min(correction, vec3(0.0)), 0.0));
}
