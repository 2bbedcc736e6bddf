// path_trace: one thread per pixel traces `sampleCount` paths and accumulates the estimate,
// its square, the base I(k) and the correction (docs/ESTIMATORS.md section 2). The body of
// path_trace.comp and path_trace_glossy.comp (GLSL only; included after #version).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"
#include "shared/path_depth.h"
#include "shared/camera.h"
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
layout(constant_id = kSpecCapLight) const uint kCapLight = 0xffffffffu;
layout(constant_id = kSpecMaxTraceDepth) const uint kMaxTraceDepth = 4096u;
layout(constant_id = kSpecRayEpsilon) const float kRayEpsilon = 1e-5;
layout(constant_id = kSpecPilot) const bool kPilot = false;
layout(constant_id = kSpecLevelSchedule) const uint kLevelSchedule = kLevelSchedulePerPixel;
layout(constant_id = kSpecTestPmfWeight) const float kTestPmfWeight = 1.0;
layout(constant_id = kSpecBsdfFamilies) const uint kBsdfFamilies = kFamilyAll;
#define BSDF_FAMILIES kBsdfFamilies  // shared/bsdf.h: the glossy families this scene uses
layout(constant_id = kSpecHasTextures) const bool kHasTextures = false;

layout(std430, binding = kBindingPrims) readonly buffer PrimBuffer { Prim prims[]; };
layout(std430, binding = kBindingBvh) readonly buffer BvhBuffer { BvhNode nodes[]; };
layout(std430, binding = kBindingMaterials) readonly buffer MaterialBuffer { MaterialGpu materials[]; };
layout(std430, binding = kBindingLights) readonly buffer LightBuffer { LightGpu lights[]; };
// The same tables as uniform buffers, read when they fit (kSpecTablesInUniforms; the media's in
// medium.glsl): lavapipe gathers a divergent uniform load with vector instructions.
layout(constant_id = kSpecTablesInUniforms) const bool kTablesInUniforms = false;
layout(std140, binding = kBindingMaterialsUniform) uniform MaterialUniform { MaterialGpu uniformMaterials[kMaxUniformMaterials]; };
layout(std140, binding = kBindingLightsUniform) uniform LightUniform { LightGpu uniformLights[kMaxUniformLights]; };
MaterialGpu sceneMaterial(uint i) {
    if (kTablesInUniforms) return uniformMaterials[i];
    return materials[i];
}
LightGpu sceneLight(uint i) {
    if (kTablesInUniforms) return uniformLights[i];
    return lights[i];
}
layout(std430, binding = kBindingTextures) readonly buffer TextureBuffer { vec4 textureData[]; };
// The environment image and its sampling tables (shared/environment_map.h), read only when the
// environment light has one.
layout(constant_id = kSpecEnvironmentMap) const bool kEnvironmentMap = false;
layout(std430, binding = kBindingEnvironment) readonly buffer EnvironmentBuffer { float envData[]; };
#define ENV_DATA(i) envData[i]
#include "shared/environment_map.h"

layout(push_constant) uniform Push { PathTracePush pc; };

#include "scene_geometry.glsl"
#include "medium.glsl"
#include "path_tracer.glsl"

// The reconstruction-filter weight of the sample being traced (1 except for the wide filters of
// shared/pixel_filter.h); it multiplies the sample's base and correction when the path ends.
float gFilterWeight = 1.0;

// Camera ray of sample s (shared/camera.h) and the level drawn for it.
PathState startSample(uvec2 pixel, uint pixelIndex, uint s, LevelPmf pmf, out Rng rng) {
    rng = rngCreate(pixelIndex, pc.sampleBase + s, pc.seed);
    float u1 = rngNext(rng), u2 = rngNext(rng);
    vec2 film = cameraFilmPoint(kFilter, pixel, vec2(u1, u2), gFilterWeight);
    vec3 dir = cameraRayDirection(film, pc.width, pc.height, pc.planeDistance, pc.cameraRight, pc.cameraUp,
                                  pc.cameraForward);
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
        float bad = isFiniteVec(path.result.base + path.result.correction) ? 0.0 : 1.0;
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
    if (pc.sampleCount == 0u) return;
    SampleSums sums = sampleSumsZero();
    // pmf pilot: its own sums (kPilot*), D_j and I(k) of the same paths, and the rays traced.
    vec3 pilotD = vec3(0.0), pilotD2 = vec3(0.0), pilotBase = vec3(0.0), pilotBase2 = vec3(0.0);
    float pilotRays = 0.0, pilotDropped = 0.0;

    uint s = 0u;
    Rng rng;
    PathState path = startSample(pixel, pixelIndex, s, pmf, rng);
    float rays = 0.0;
    while (true) {
        if (kPilot) rays += 1.0;
        if (pathStep(path, pmf, rng)) continue;
        // ---- Path finished: accumulate, then start the next sample in the same lane ----
        if (isWideFilter(kFilter)) path.result = PathResult(path.result.base * gFilterWeight, path.result.correction * gFilterWeight);
        if (!kPilot) {
            sampleSumsAdd(sums, path.result.base, path.result.correction);
        } else if (!isFiniteVec(path.result.correction) || !isFiniteVec(path.result.base)) {
            pilotDropped += 1.0;
        } else {
            vec3 d = path.result.correction, b = path.result.base;
            pilotD += d;
            pilotD2 += d * d;
            pilotBase += b;
            pilotBase2 += b * b;
            pilotRays += rays;
        }
        rays = 0.0;
        if (++s == pc.sampleCount) break;
        path = startSample(pixel, pixelIndex, s, pmf, rng);
    }
    if (kPilot) {
        AccumRef pilot = AccumRef(uvec2(pc.pilotAddressLo, pc.pilotAddressHi));
        accumulateAdd(pilot, kPilotCorrection, pixelIndex, pixelCount, vec4(pilotD, pilotDropped));
        accumulateAdd(pilot, kPilotCorrectionSq, pixelIndex, pixelCount, vec4(pilotD2, 0.0));
        accumulateAdd(pilot, kPilotBase, pixelIndex, pixelCount, vec4(pilotBase, 0.0));
        accumulateAdd(pilot, kPilotBaseSq, pixelIndex, pixelCount, vec4(pilotBase2, 0.0));
        accumulateAdd(pilot, kPilotRays, pixelIndex, pixelCount, vec4(pilotRays, 0.0, 0.0, 0.0));
        return;
    }
    accumulateSums(AccumRef(uvec2(pc.accumAddressLo, pc.accumAddressHi)), pixelIndex, pixelCount, sums);
}
