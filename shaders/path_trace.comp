// path_trace: one thread per pixel traces `sampleCount` paths and accumulates the estimate,
// its square, the base I(k) and the correction (docs/ESTIMATORS.md section 2).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"
#include "shared/path_depth.h"
#include "shared/pixel_filter.h"
#include "accumulate.glsl"

layout(local_size_x = kPathTraceGroupSize, local_size_y = kPathTraceGroupSize) in;

layout(constant_id = kSpecMaxBounces) const uint kMaxBounces = 64u;
layout(constant_id = kSpecMinBounces) const uint kMinBounces = 0u;
layout(constant_id = kSpecDebiasMode) const uint kDebiasMode = 0u;
layout(constant_id = kSpecPmfType) const uint kPmfType = 0u;
layout(constant_id = kSpecPmfR) const float kPmfR = 0.65;
layout(constant_id = kSpecPmfAlpha) const float kPmfAlpha = 0.6666667;
layout(constant_id = kSpecHasSpheres) const bool kHasSpheres = true;
layout(constant_id = kSpecHasDisks) const bool kHasDisks = true;
layout(constant_id = kSpecHasSpecular) const bool kHasSpecular = true;
layout(constant_id = kSpecLightCount) const uint kLightCount = 0u;
layout(constant_id = kSpecLightSampling) const bool kLightSampling = true;
layout(constant_id = kSpecTwoSided) const bool kTwoSided = true;
layout(constant_id = kSpecFilter) const uint kFilter = kFilterTent;
layout(constant_id = kSpecEnvironmentLight) const uint kEnvironmentLight = 0xffffffffu;
layout(constant_id = kSpecMaxTraceDepth) const uint kMaxTraceDepth = 4096u;
layout(constant_id = kSpecRayEpsilon) const float kRayEpsilon = 1e-5;
layout(constant_id = kSpecPilot) const bool kPilot = false;
layout(constant_id = kSpecLevelSchedule) const uint kLevelSchedule = kLevelSchedulePerPixel;
layout(constant_id = kSpecTestPmfWeight) const float kTestPmfWeight = 1.0;

layout(std430, binding = kBindingPrims) readonly buffer PrimBuffer { Prim prims[]; };
layout(std430, binding = kBindingBvh) readonly buffer BvhBuffer { BvhNode nodes[]; };
layout(std430, binding = kBindingMaterials) readonly buffer MaterialBuffer { MaterialGpu materials[]; };
layout(std430, binding = kBindingLights) readonly buffer LightBuffer { LightGpu lights[]; };

layout(constant_id = kSpecSceneInUniforms) const bool kSceneInUniforms = false;
layout(std140, binding = kBindingBvhUniform) uniform BvhUniform { BvhNode uniformNodes[kMaxUniformNodes]; };
layout(std140, binding = kBindingPrimsUniform) uniform PrimUniform { Prim uniformPrims[kMaxUniformPrims]; };

layout(push_constant) uniform Push { PathTracePush pc; };

// (Functions, not ?: : the uniform and storage structs are distinct SPIR-V types.)
BvhNode sceneNode(uint i) {
    if (kSceneInUniforms) return uniformNodes[i];
    return nodes[i];
}
Prim scenePrim(uint i) {
    if (kSceneInUniforms) return uniformPrims[i];
    return prims[i];
}
#define BVH_NODE(i) sceneNode(i)
#define BVH_PRIM(i) scenePrim(i)
#include "shared/intersect.h"
#include "medium.glsl"
#include "path_tracer.glsl"

// The reconstruction-filter weight of the sample being traced (1 except for the wide filters of
// shared/pixel_filter.h); it multiplies the sample's base and correction when the path ends.
float gFilterWeight = 1.0;

// Camera ray of sample s (Tungsten's pinhole: pixel (0,0) top-left, fov horizontal) and the
// level drawn for it.
PathState startSample(uvec2 pixel, uint pixelIndex, uint s, LevelPmf pmf, out Rng rng) {
    rng = rngCreate(pixelIndex, pc.sampleBase + s, pc.seed);
    vec2 jitter = vec2(rngNext(rng), rngNext(rng));
    if (kFilter == kFilterTent) jitter = vec2(sampleTent(jitter.x), sampleTent(jitter.y)) + 0.5;
    else if (kFilter == kFilterDirac) jitter = vec2(0.5);
    else if (isWideFilter(kFilter)) {
        float wx, wy;
        jitter = vec2(sampleWideFilter(kFilter, jitter.x, wx), sampleWideFilter(kFilter, jitter.y, wy)) + 0.5;
        gFilterWeight = wx * wy;
    }
    float w = float(pc.width);
    vec3 local = vec3(-1.0 + 2.0 * (float(pixel.x) + jitter.x) / w,
                      float(pc.height) / w - 2.0 * (float(pixel.y) + jitter.y) / w, pc.planeDistance);
    vec3 dir = normalize(pc.cameraRight * local.x + pc.cameraUp * local.y + pc.cameraForward * local.z);
    uint level = 0u;
    if (kPilot) {
        level = pc.pilotLevel;
    } else if (kDebiasMode != kDebiasNone) {
        if (kLevelSchedule == kLevelScheduleUniform) {
            Rng levelRng = rngCreate(0xffffffffu, pc.sampleBase + s, pc.seed);  // the same for every pixel
            level = levelSample(pmf, rngNext(levelRng));
        } else {
            level = levelSample(pmf, rngNext(rng));  // level_queue.glsl drawLevel() repeats this draw
        }
    }
    // Camera rays start kRayEpsilon out, like every other ray (traceClosest uses tMin = 0), so a
    // camera placed on a surface sees what is in front of it rather than that surface's back.
    return beginPath(pc.cameraPosition + dir * kRayEpsilon, dir, level);
}

#include "level_queue.glsl"

// ---- Queued schedule: lanes take (pixel, sample) items from the level-sorted queue ----
// Lane i takes slots i, i + lanes, i + 2 lanes, ...: the lanes of a SIMD group hold neighbouring
// slots, so paths of the same level. (Static, so no atomics: the image is repeatable.)
bool fetchItem(LevelQueueRef q, uint total, inout uint slot, out uint item) {
    if (slot >= total) return false;
    item = q.u[queueItemsOffset() + slot];
    uvec3 lanes = gl_NumWorkGroups * gl_WorkGroupSize;
    slot += lanes.x * lanes.y;
    return true;
}

PathState startItem(uint item, LevelPmf pmf, out Rng rng) {
    uint pixelCount = pc.width * pc.height;
    uint pixelIndex = item % pixelCount;
    uvec2 pixel = uvec2(pixelIndex % pc.width, pixelIndex / pc.width);
    return startSample(pixel, pixelIndex, item / pixelCount, pmf, rng);
}

void queuedMain(LevelPmf pmf) {
    uint total = pc.width * pc.height * pc.sampleCount;
    LevelQueueRef q = levelQueue();
    LevelResultsRef results = levelResults();
    uvec3 lanes = gl_NumWorkGroups * gl_WorkGroupSize;
    uint slot = gl_GlobalInvocationID.y * lanes.x + gl_GlobalInvocationID.x, item;
    if (!fetchItem(q, total, slot, item)) return;
    Rng rng;
    PathState path = startItem(item, pmf, rng);
    while (true) {
        if (pathStep(path, pmf, rng)) continue;
        if (isWideFilter(kFilter)) path.result = PathResult(path.result.base * gFilterWeight, path.result.correction * gFilterWeight);
        vec3 z = path.result.base + path.result.correction;
        float bad = (any(isnan(z)) || any(isinf(z))) ? 1.0 : 0.0;
        results.v[2u * item] = vec4(path.result.base, bad);
        results.v[2u * item + 1u] = vec4(path.result.correction, 0.0);
        if (!fetchItem(q, total, slot, item)) break;
        path = startItem(item, pmf, rng);
    }
}

void main() {
    if (kLevelSchedule == kLevelScheduleQueued) {
        if (pc.sampleCount != 0u) queuedMain(LevelPmf(kPmfType, kPmfR, kPmfAlpha));
        return;
    }
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= pc.width || pixel.y >= pc.height) return;
    uint pixelIndex = pixel.y * pc.width + pixel.x;
    uint pixelCount = pc.width * pc.height;
    LevelPmf pmf = LevelPmf(kPmfType, kPmfR, kPmfAlpha);

    vec3 sumZ = vec3(0.0), sumZ2 = vec3(0.0), sumBase = vec3(0.0), sumCorrection = vec3(0.0);
    vec3 sumCorrectionPos = vec3(0.0), sumCorrectionNeg = vec3(0.0);
    float dropped = 0.0;
    if (pc.sampleCount == 0u) return;

    uint s = 0u;
    Rng rng;
    PathState path = startSample(pixel, pixelIndex, s, pmf, rng);
    float rays = 0.0;  // pmf pilot: rays traced by this sample, the pilot's cost model
    while (true) {
        if (kPilot) rays += 1.0;
        if (pathStep(path, pmf, rng)) continue;
        // ---- Path finished: accumulate, then start the next sample in the same lane ----
        if (isWideFilter(kFilter)) path.result = PathResult(path.result.base * gFilterWeight, path.result.correction * gFilterWeight);
        vec3 z = kPilot ? path.result.correction : path.result.base + path.result.correction;
        if (any(isnan(z)) || any(isinf(z)) || any(isnan(path.result.base)) || any(isinf(path.result.base))) {
            dropped += 1.0;
        } else if (kPilot) {
            // pmf pilot, channels: estimate D_j, estimate^2, base = (rays traced, 0, 0),
            // correction+ = I(k), correction- = I(k)^2 (accumulate.glsl has no other use for them here).
            sumZ += z;
            sumZ2 += z * z;
            sumBase += vec3(rays, 0.0, 0.0);
            sumCorrectionPos += path.result.base;
            sumCorrectionNeg += path.result.base * path.result.base;
        } else {
            sumZ += z;
            sumZ2 += z * z;
            sumBase += path.result.base;
            sumCorrection += path.result.correction;
            sumCorrectionPos += max(path.result.correction, vec3(0.0));
            sumCorrectionNeg += min(path.result.correction, vec3(0.0));
        }
        rays = 0.0;
        if (++s == pc.sampleCount) break;
        path = startSample(pixel, pixelIndex, s, pmf, rng);
    }

    AccumRef accum = AccumRef(uvec2(pc.accumAddressLo, pc.accumAddressHi));
    accumulateAdd(accum, kChannelEstimate, pixelIndex, pixelCount, vec4(sumZ, dropped));
    accumulateAdd(accum, kChannelEstimateSq, pixelIndex, pixelCount, vec4(sumZ2, 0.0));
    accumulateAdd(accum, kChannelBase, pixelIndex, pixelCount, vec4(sumBase, 0.0));
    accumulateAdd(accum, kChannelCorrection, pixelIndex, pixelCount, vec4(sumCorrection, 0.0));
    accumulateAdd(accum, kChannelCorrectionPositive, pixelIndex, pixelCount, vec4(sumCorrectionPos, 0.0));
    accumulateAdd(accum, kChannelCorrectionNegative, pixelIndex, pixelCount, vec4(sumCorrectionNeg, 0.0));
}
