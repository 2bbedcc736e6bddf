// path_trace: one thread per pixel traces `sampleCount` paths and accumulates the estimate,
// its square, the base I(k) and the correction (docs/ESTIMATORS.md section 2). The body of
// path_trace.comp and path_trace_glossy.comp (GLSL only; included after #version).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_EXT_control_flow_attributes : require  // [[unroll]]: scene_geometry.glsl

// The loop budget's counting (shared/lang.h; kLoopBudget, gLoopTicks and gLoopHardLimit are
// declared below): every loop counts, only the long walks of media stop at the hard limit.
#define LOOP_BUDGET_TICK(n) gLoopTicks += (n)
#define LOOP_BUDGET_SPENT(n) (kLoopBudget != 0u && (gLoopTicks += (n)) > gLoopHardLimit)

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/sampling.h"
#include "shared/path_depth.h"
#include "shared/camera.h"
#include "accumulate.glsl"

layout(local_size_x = kPathTraceGroupSize, local_size_y = kPathTraceGroupSize) in;

// ---- Loop budget (shared/gpu_types.h "Lavapipe's loop cap") ----
uint gLoopTicks = 0u;  // loop iterations this lane has counted in this dispatch
// A lane starts no step past gLoopBudget (it carries its path instead); a walk that passes
// gLoopHardLimit stops, and the lane's dispatch is undone and retried (main).
uint gLoopBudget = kLoopBudget;
uint gLoopHardLimit = kHeavyLoopBudget;

#define BSDF_FAMILIES kBsdfFamilies  // shared/bsdf.h: the glossy families this scene uses

layout(std430, binding = kBindingPrims) readonly buffer PrimBuffer { Prim prims[]; };
layout(std430, binding = kBindingBvh) readonly buffer BvhBuffer { BvhNode nodes[]; };
layout(std430, binding = kBindingMaterials) readonly buffer MaterialBuffer { MaterialGpu materials[]; };
layout(std430, binding = kBindingLights) readonly buffer LightBuffer { LightGpu lights[]; };
// The same tables as uniform buffers, read when they fit (kSpecTablesInUniforms; the media's in
// medium.glsl): lavapipe gathers a divergent uniform load with vector instructions.
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
layout(std430, binding = kBindingEnvironment) readonly buffer EnvironmentBuffer { float envData[]; };
#define ENV_DATA(i) envData[i]
#include "shared/environment_map.h"

layout(push_constant) uniform Push { PathTracePush pc; };

#include "scene_geometry.glsl"
#include "scene_common.glsl"
#include "medium.glsl"
#include "path_tracer.glsl"

// The reconstruction-filter weight of the sample being traced (1 except for the wide filters of
// shared/pixel_filter.h); it multiplies the sample's base and correction when the path ends.
float gFilterWeight = 1.0;

// Camera ray of the sample of global index g (shared/camera.h) and the level drawn for it.
PathState startSample(uvec2 pixel, uint pixelIndex, uint g, LevelPmf pmf, out Rng rng) {
    rng = rngCreate(pixelIndex, g, pc.seed);
    float u1 = rngNext(rng), u2 = rngNext(rng);
    vec2 film = cameraFilmPoint(kFilter, pixel, vec2(u1, u2), gFilterWeight);
    vec3 dir = cameraRayDirection(film, pc.width, pc.height, pc.planeDistance, pc.cameraRight, pc.cameraUp,
                                  pc.cameraForward);
    uint level = 0u;
    if (kPilot) {
        level = pc.pilotLevel;
    } else if (kDebiasMode != kDebiasNone) {
        if (kLevelSchedule == kLevelScheduleUniform) {
            Rng levelRng = rngCreate(0xffffffffu, g, pc.seed);  // the same for every pixel
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
    return startSample(pixel, pixelIndex, pc.sampleBase + item / pixelCount, pmf, rng);
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

// ---- Continuation records: a path carried to the next dispatch (kSpecLoopBudget) ----
layout(buffer_reference, std430, buffer_reference_align = 16) buffer RecordRef { uvec4 v[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer LoopStatsRef { uint u[]; };

LoopStatsRef loopStats() { return LoopStatsRef(uvec2(pc.statsAddressLo, pc.statsAddressHi)); }
// The lane's record flags (kRecord*: 0 = no record) and its record (shared/gpu_types.h
// continuationFlagBytes: the flags first, zeroed; the records after them, never read unflagged).
layout(buffer_reference, std430, buffer_reference_align = 16) buffer RecordFlagsRef { uint f[]; };
uint64_t continuationBase() { return packUint2x32(uvec2(pc.stateAddressLo, pc.stateAddressHi)); }
RecordFlagsRef recordFlags() { return RecordFlagsRef(continuationBase()); }
RecordRef recordOf(uint lane) {
    return RecordRef(continuationBase() + uint64_t(continuationFlagBytes(pc.width * pc.height)) +
                     uint64_t(lane) * uint64_t(kContinuationVec4s * 16u));
}

// Record flags (recordFlags): pending; heavy (a step that cannot finish beside other lanes: it runs
// alone in a dispatch that finishes carried paths); safe (the dispatch that ran it reached
// lavapipe's cap or a walk's hard limit: it runs with kSafeLoopBudget).
const uint kRecordPending = 1u, kRecordHeavy = 2u, kRecordSafe = 4u;

// Saves a path that has not taken its next step, its random state, its global sample index and
// what the lane keeps for it. Everything is stored as bits (uvec4): small integers as floats
// would be denormals, which lavapipe flushes to zero.
void saveRecord(uint lane, PathState p, Rng rng, uint g, float rays, uint flags) {
    RecordRef r = recordOf(lane);
    r.v[0] = uvec4(floatBitsToUint(p.origin), floatBitsToUint(p.pdfPrev));
    r.v[1] = uvec4(floatBitsToUint(p.dir), p.vertex);
    r.v[2] = uvec4(floatBitsToUint(p.throughput), p.level);
    r.v[3] = uvec4(floatBitsToUint(p.result.base), p.limit);
    r.v[4] = uvec4(floatBitsToUint(p.result.correction), (p.specularPrev ? 1u : 0u) | (p.fromSurface ? 2u : 0u));
    r.v[5] = uvec4(floatBitsToUint(p.lastVertex), p.medium);
    r.v[6] = uvec4(p.mediumScatters, rng.state, rng.inc, g);
    r.v[7] = uvec4(floatBitsToUint(gFilterWeight), floatBitsToUint(rays), floatBitsToUint(p.etaScale), 0u);
    recordFlags().f[lane] = kRecordPending | flags;
    atomicAdd(loopStats().u[kLoopStatCarried], 1u);
}

// Takes the lane's pending record, if any: false (and nothing changed) when there is none.
// (inout, not out: GLSL copies out parameters back even when the function did not set them.)
bool takeRecord(uint lane, inout PathState p, inout Rng rng, inout uint g, inout float rays) {
    if ((recordFlags().f[lane] & kRecordPending) == 0u) return false;
    recordFlags().f[lane] = 0u;
    RecordRef r = recordOf(lane);
    uvec4 v7 = r.v[7];
    gFilterWeight = uintBitsToFloat(v7.x);
    rays = uintBitsToFloat(v7.y);
    uvec4 v0 = r.v[0], v1 = r.v[1], v2 = r.v[2], v3 = r.v[3], v4 = r.v[4], v5 = r.v[5], v6 = r.v[6];
    p.origin = uintBitsToFloat(v0.xyz);
    p.pdfPrev = uintBitsToFloat(v0.w);
    p.dir = uintBitsToFloat(v1.xyz);
    p.vertex = v1.w;
    p.throughput = uintBitsToFloat(v2.xyz);
    p.level = v2.w;
    p.result.base = uintBitsToFloat(v3.xyz);
    p.limit = v3.w;
    p.result.correction = uintBitsToFloat(v4.xyz);
    p.specularPrev = (v4.w & 1u) != 0u;
    p.fromSurface = (v4.w & 2u) != 0u;
    p.lastVertex = uintBitsToFloat(v5.xyz);
    p.medium = v5.w;
    p.mediumScatters = v6.x;
    p.etaScale = uintBitsToFloat(v7.z);
    rng.state = v6.y;
    rng.inc = v6.z;
    g = v6.w;
    atomicAdd(loopStats().u[kLoopStatResumed], 1u);
    return true;
}

#include "loop_cap.glsl"

// Where a lane starts in this dispatch (the loop budget's records: a path carried from an
// earlier dispatch, or a new sample g). False when the lane has nothing to do here: heavy records
// run alone, and lanes beside a heavy one wait for it.
bool startLane(uvec2 pixel, uint pixelIndex, LevelPmf pmf, uint end, inout uint g, out Rng rng, out PathState path,
               out float rays, out bool alone, out bool safe) {
    rays = 0.0;
    alone = false;
    safe = false;
    bool resumed = false;
    if (kLoopBudget != 0u) {
        uint state = recordFlags().f[pixelIndex];
        bool heavy = (state & kRecordHeavy) != 0u;
        if (heavy) {
            // Heavy records run only in dispatches that finish carried paths (no new samples: the
            // record's samples come first, and such dispatches continue to the batch's end), the
            // lowest lane of the group holding one alone; the others keep their records.
            uvec4 heavyLanes = subgroupBallot(true);
            if (pc.sampleCount != 0u || gl_SubgroupInvocationID != subgroupBallotFindLSB(heavyLanes)) return false;
        }
        uvec4 heavyGroup = subgroupBallot(heavy);
        if (!heavy && pc.sampleCount == 0u && heavyGroup != uvec4(0u)) return false;  // wait for the heavy one
        if (heavy) {
            alone = true;
            gLoopBudget = 1u;  // its heavy step, then it carries the path on
        } else if ((state & kRecordSafe) != 0u) {
            safe = true;
            gLoopBudget = kSafeLoopBudget;
            gLoopHardLimit = kSafeHardLimit;
        }
        if (state != 0u) resumed = takeRecord(pixelIndex, path, rng, g, rays);
    }
    if (!resumed) {
        if (g >= end) return false;
        path = startSample(pixel, pixelIndex, g, pmf, rng);
    }
    return true;
}

// The pmf pilot's per-lane sums (kPilot*): D_j and I(k) of the same paths, and the rays traced.
struct PilotLane { vec3 d, d2, base, base2; float rays, dropped; };

// A finished path's estimate into the lane's sums (or the pilot's).
void addFinishedPath(PathState path, bool overlong, float rays, inout SampleSums sums, inout PilotLane pilot) {
    if (isWideFilter(kFilter)) path.result = PathResult(path.result.base * gFilterWeight, path.result.correction * gFilterWeight);
    if (overlong) path.result = PathResult(vec3(uintBitsToFloat(0x7f800000u)), vec3(0.0));  // counted as dropped
    if (!kPilot) {
        sampleSumsAdd(sums, path.result.base, path.result.correction);
    } else if (!isFiniteVec(path.result.correction) || !isFiniteVec(path.result.base)) {
        pilot.dropped += 1.0;
    } else {
        vec3 d = path.result.correction, b = path.result.base;
        pilot.d += d;
        pilot.d2 += d * d;
        pilot.base += b;
        pilot.base2 += b * b;
        pilot.rays += rays;
    }
}

void writePilotSums(uint pixelIndex, uint pixelCount, PilotLane p) {
    AccumRef pilot = AccumRef(uvec2(pc.pilotAddressLo, pc.pilotAddressHi));
    accumulateAdd(pilot, kPilotCorrection, pixelIndex, pixelCount, vec4(p.d, p.dropped));
    accumulateAdd(pilot, kPilotCorrectionSq, pixelIndex, pixelCount, vec4(p.d2, 0.0));
    accumulateAdd(pilot, kPilotBase, pixelIndex, pixelCount, vec4(p.base, 0.0));
    accumulateAdd(pilot, kPilotBaseSq, pixelIndex, pixelCount, vec4(p.base2, 0.0));
    accumulateAdd(pilot, kPilotRays, pixelIndex, pixelCount, vec4(p.rays, 0.0, 0.0, 0.0));
}

// Where a lane's work in this dispatch started: a retry begins there again.
struct LaneStart { PathState path; Rng rng; uint g; float rays, filterWeight; };

// After the lane's loop: a retry when lavapipe's cap was reached or a walk stopped (this
// dispatch's work of the lane undone), a carried path saved, and the sums accumulated.
void endLane(uint pixelIndex, uint pixelCount, LaneStart start, PathState path, Rng rng, uint g, float rays, bool alone,
             bool safe, bool carried, bool aborted, bool abortedFresh, SampleSums sums, PilotLane pilot) {
    bool capped = loopCapReached(2u + (pc.width >> 31u));
    if (kLoopBudget != 0u && (capped || aborted) && !alone && !(safe && capped)) {
        // Retried from where it started: alone when one step did not fit (from the start of a
        // dispatch, or at the safe budget), else with the safe budget.
        gFilterWeight = start.filterWeight;
        bool heavy = aborted && (abortedFresh || safe);
        saveRecord(pixelIndex, start.path, start.rng, start.g, start.rays, heavy ? kRecordHeavy : kRecordSafe);
        atomicAdd(loopStats().u[kLoopStatRetried], 1u);
        return;
    }
    if (carried) saveRecord(pixelIndex, path, rng, g, rays, safe ? kRecordSafe : 0u);
    if (capped) atomicAdd(loopStats().u[kLoopStatCapHits], 1u);  // not recoverable: an error
    if (kPilot) {
        writePilotSums(pixelIndex, pixelCount, pilot);
        return;
    }
    accumulateSums(AccumRef(uvec2(pc.accumAddressLo, pc.accumAddressHi)), pixelIndex, pixelCount, sums);
}

void main() {
    if (kLevelSchedule == kLevelScheduleQueued) {
        if (pc.sampleCount != 0u) queuedMain(LevelPmf(kPmfType, kPmfR, kPmfAlpha));
        if (loopCapReached(2u + (pc.width >> 31u))) atomicAdd(loopStats().u[kLoopStatCapHits], 1u);
        return;
    }
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= pc.width || pixel.y >= pc.height) return;
    uint pixelIndex = pixel.y * pc.width + pixel.x;
    uint pixelCount = pc.width * pc.height;
    LevelPmf pmf = LevelPmf(kPmfType, kPmfR, kPmfAlpha);
    // This dispatch traces the samples g < end of this pixel: a lane carrying a path from an
    // earlier dispatch (whose samples come just before pc.sampleBase) finishes it first.
    uint end = pc.sampleBase + pc.sampleCount;
    uint g = pc.sampleBase;
    Rng rng;
    PathState path;
    float rays;
    bool alone, safe;
    if (!startLane(pixel, pixelIndex, pmf, end, g, rng, path, rays, alone, safe)) return;
    // Where this dispatch's work for the lane starts: a retry begins here again.
    LaneStart start = LaneStart(path, rng, g, rays, gFilterWeight);

    SampleSums sums = sampleSumsZero();
    PilotLane pilot = PilotLane(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0), 0.0, 0.0);
    bool working = true, carried = false, aborted = false, abortedFresh = false;
    while (working) {
        // ---- Past the budget: carry the path, before its next step, to the next dispatch ----
        if (kLoopBudget != 0u && gLoopTicks > gLoopBudget) {
            carried = true;  // saved after the loop (stores inside it cost the loop registers)
            break;
        }
        if (kPilot) rays += 1.0;
        uint ticksBefore = gLoopTicks;
        LOOP_BUDGET_TICK(8u);  // this loop, and loops of the step entered with no lane active
        bool more = pathStep(path, pmf, rng);
        bool overlong = false;
        if (kLoopBudget != 0u && gLoopTicks > gLoopHardLimit) {
            // A walk stopped at the hard limit: this step is garbage.
            if (!alone) {
                aborted = true;
                abortedFresh = ticksBefore == 0u;  // the step alone passed the hard limit
                break;
            }
            // Running alone with most of the cap, the step still did not fit: the sample is
            // dropped (as a non-finite one), counted, and reported as an error.
            atomicAdd(loopStats().u[kLoopStatOverlong], 1u);
            overlong = true;
            more = false;
        }
        if (!more) {
            // ---- Path finished: accumulate, then start the next sample in the same lane ----
            addFinishedPath(path, overlong, rays, sums, pilot);
            rays = 0.0;
            if (++g >= end) working = false;
            else path = startSample(pixel, pixelIndex, g, pmf, rng);
        }
    }
    endLane(pixelIndex, pixelCount, start, path, rng, g, rays, alone, safe, carried, aborted, abortedFresh, sums, pilot);
}
