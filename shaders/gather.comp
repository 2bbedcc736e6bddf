// gather: one thread per pixel and photon pass. The camera path follows mirror and dielectric
// bounces to the first diffuse vertex, where the photon map gives, times the Lambert BSDF,
//   biased:   the pass's sample  K_r                     (fixed radius or the PPM pass radius)
//   unbiased: the pass's part of a block of m^k passes at level k (docs/PHOTON-MAPPING.md):
//             Z = mean over the block of [K_{r_b} + (K_{r_{k+1}} - K_{r_k}) / p(k)]
// plus emission seen along the specular chain and, with direct_lighting = next_event, one light
// sample (no MIS: photons carry no direct light then). A block's sums live in the per-pixel block
// buffer until its last pass adds the sample to the film. The level is the host's (uniform
// schedule) or drawn here when a pixel starts a block (per_pixel schedule).
// A pass whose fullest bucket holds more than kGatherSlicePhotons photons runs in slices (one
// dispatch each, see photon_gather.glsl); the last slice completes the pass.
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
layout(constant_id = kSpecPhotonSchedule) const uint kSchedule = kPhotonScheduleUniform;

layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4ArrayRef { vec4 v[]; };

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

// The per-pixel block buffer (kGatherBlockVec4s vec4 per pixel): compensated sums of the block's
// base and correction (hi, lo pairs; w of the first: level + 1 for per_pixel, 0 = no block; w of
// the second: passes done), then the kernel sums of the slices before the last.
const uint kBlockBaseHi = 0u, kBlockBaseLo = 1u, kBlockCorrHi = 2u, kBlockCorrLo = 3u;
const uint kSliceBase = 4u, kSliceDifference = 5u;

void addCompensated(Vec4ArrayRef b, uint i, vec3 value) {
    vec3 hi = b.v[i].xyz;
    precise vec3 s = hi + value;
    precise vec3 bp = s - hi;
    precise vec3 err = (hi - (s - bp)) + (value - bp);
    b.v[i].xyz = s;
    b.v[i + 1u].xyz += err;
}

uint passSeed(uint seed, uint passInBlock) { return passInBlock == 0u ? seed : seed ^ pcgHash(passInBlock); }

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= pc.width || pixel.y >= pc.height) return;
    PhotonMapRef map = PhotonMapRef(uvec2(pc.headerLo, pc.headerHi));
    if (map.h.storedCount > map.h.capacity) return;  // photons were dropped: the host repeats the pass
    if (map.h.maxBucket > pc.sliceCount * kGatherSlicePhotons) return;  // too few slices: repeated too
    uint pixelIndex = pixel.y * pc.width + pixel.x;
    Vec4ArrayRef block = Vec4ArrayRef(uvec2(pc.blockLo, pc.blockHi));
    uint bi = pixelIndex * kGatherBlockVec4s;
    bool lastSlice = pc.slice + 1u == pc.sliceCount;

    // ---- Camera ray and the level of this pass ----
    Rng rng = rngCreate(pixelIndex, pc.pass, passSeed(pc.seed, pc.passInBlock));
    vec2 jitter = vec2(rngNext(rng), rngNext(rng));
    if (kFilter == kFilterTent) jitter = vec2(sampleTent(jitter.x), sampleTent(jitter.y)) + 0.5;
    else if (kFilter == kFilterDirac) jitter = vec2(0.5);
    float w = float(pc.width);
    vec3 local = vec3(-1.0 + 2.0 * (float(pixel.x) + jitter.x) / w,
                      float(pc.height) / w - 2.0 * (float(pixel.y) + jitter.y) / w, pc.planeDistance);
    vec3 dir = normalize(pc.cameraRight * local.x + pc.cameraUp * local.y + pc.cameraForward * local.z);
    vec3 origin = pc.cameraPosition;

    const bool unbiased = kEstimator == kPhotonUnbiased;
    PhotonLevels levels = PhotonLevels(pc.pmfR, pc.logAreaRatio, pc.photonGrowth, pc.levelCap);
    float uLevel1 = rngNext(rng), uLevel2 = rngNext(rng);
    uint level = pc.level;
    uint done = pc.passInBlock;
    if (unbiased && kSchedule == kPhotonSchedulePerPixel) {
        float state = block.v[bi + kBlockBaseHi].w;
        done = state == 0.0 ? 0u : uint(block.v[bi + kBlockBaseLo].w);
        level = state == 0.0 ? photonLevelSample(levels, uLevel1, uLevel2) : uint(state) - 1u;
    }

    // ---- Specular chain to the first diffuse vertex ----
    vec3 throughput = vec3(1.0);
    vec3 light = vec3(0.0);  // emission along the chain and the light sample
    vec3 kernelBase = vec3(0.0), kernelDifference = vec3(0.0);  // times the BSDF, this slice
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
        light += throughput * primEmission(pr, dir, ng);
        if (v > kPhotonMaxBounces) break;
        MaterialGpu m = materials[pr.material];
        bool front = dot(dir, ng) < 0.0;
        vec3 n = front ? ng : -ng;  // faces the camera path

        if (m.type == kBsdfLambert) {
            if (!front && !kTwoSided) break;
            vec3 f = throughput * m.albedo * kInvPi;
            if (lastSlice && kNextEvent && kLightCount > 0u) light += throughput * directLight(p, ng, n, m.albedo, rng);
            float rb2 = pc.radius * pc.radius;
            float logRadius2 = unbiased ? photonLevelLogRadius2(levels, level) : 0.0;
            GatherSums sums = gatherPhotons(map, p, n, rb2, unbiased, logRadius2, pc.logAreaRatio, kKernel,
                                            pc.slice * kGatherSlicePhotons);
            kernelBase = f * sums.base;
            kernelDifference = f * sums.difference;
            break;
        }
        if (!kHasSpecular || (m.type != kBsdfMirror && m.type != kBsdfDielectric)) break;  // null
        throughput *= scatterSpecular(m, front, n, dir, rng);
        origin = offsetRayOrigin(p, ng, dir);
    }

    // ---- Slices: the kernel sums of the earlier slices wait in the block buffer ----
    if (pc.sliceCount > 1u) {
        if (pc.slice > 0u) {
            kernelBase += block.v[bi + kSliceBase].xyz;
            kernelDifference += block.v[bi + kSliceDifference].xyz;
        }
        if (!lastSlice) {
            block.v[bi + kSliceBase] = vec4(kernelBase, 0.0);
            block.v[bi + kSliceDifference] = vec4(kernelDifference, 0.0);
            return;
        }
    }

    // ---- The pass's sample, or its part of the block ----
    vec3 base = light + kernelBase, correction = vec3(0.0);
    float count = 0.0;  // per_pixel: samples added to this pixel (film channel kChannelEstimateSq.w)
    if (unbiased) {
        vec3 passCorrection = kernelDifference / photonLevelProbability(levels, level);
        if (done == 0u) {
            block.v[bi + kBlockBaseHi] = vec4(0.0);
            block.v[bi + kBlockBaseLo] = vec4(0.0);
            block.v[bi + kBlockCorrHi] = vec4(0.0);
            block.v[bi + kBlockCorrLo] = vec4(0.0);
        }
        addCompensated(block, bi + kBlockBaseHi, base);
        addCompensated(block, bi + kBlockCorrHi, passCorrection);
        uint passes = photonBlockPasses(levels, level);
        if (done + 1u < passes) {
            block.v[bi + kBlockBaseHi].w = float(level + 1u);
            block.v[bi + kBlockBaseLo].w = float(done + 1u);
            return;
        }
        // The block is complete: its sample is the mean of its passes.
        float inv = 1.0 / float(passes);
        base = (block.v[bi + kBlockBaseHi].xyz + block.v[bi + kBlockBaseLo].xyz) * inv;
        correction = (block.v[bi + kBlockCorrHi].xyz + block.v[bi + kBlockCorrLo].xyz) * inv;
        block.v[bi + kBlockBaseHi].w = 0.0;
        if (kSchedule == kPhotonSchedulePerPixel) count = 1.0;
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
    accumulateAdd(accum, kChannelEstimateSq, pixelIndex, pixelCount, vec4(z * z, count));
    accumulateAdd(accum, kChannelBase, pixelIndex, pixelCount, vec4(base, 0.0));
    accumulateAdd(accum, kChannelCorrection, pixelIndex, pixelCount, vec4(correction, 0.0));
    accumulateAdd(accum, kChannelCorrectionPositive, pixelIndex, pixelCount, vec4(max(correction, vec3(0.0)), 0.0));
    accumulateAdd(accum, kChannelCorrectionNegative, pixelIndex, pixelCount, vec4(min(correction, vec3(0.0)), 0.0));
}
