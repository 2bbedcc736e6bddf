// Data layouts shared by the host and the shaders: GPU structs, binding indices, push constants
// and specialisation constants. Every struct is laid out as (vec3, 4-byte scalar) pairs so that
// std430 and the C++ layout agree; the C++ side checks sizes with static_assert.
#ifndef TELESCOPE_GPU_TYPES_H
#define TELESCOPE_GPU_TYPES_H

#include "shared/lang.h"
#include "shared/transmittance.h"

SHADER_NAMESPACE_BEGIN

// ---- Geometry (GeometryType in src/scene/scene.h) ----
CONST uint kPrimTriangle = 0u;
CONST uint kPrimSphere = 1u;
CONST uint kPrimDisk = 2u;

// A ray-traceable primitive. Triangle: p0, p1, p2. Sphere: centre p0, radius p1.x.
// Disk: centre p0, radius p1.x, unit normal n. n is the geometric (emitting) normal.
struct Prim {
    vec3 p0; uint type;
    vec3 p1; uint material;
    vec3 p2; int light;      // index into the light table, -1 if not emissive
    vec3 n;  float area;
};

// BVH node. Inner: count == 0, children first and first + 1. Leaf: prims [first, first+count).
struct BvhNode {
    vec3 lo; uint first;
    vec3 hi; uint count;
};

// ---- Materials ----
CONST uint kBsdfLambert = 0u;
CONST uint kBsdfMirror = 1u;
CONST uint kBsdfDielectric = 2u;
CONST uint kBsdfNull = 3u;
CONST uint kBsdfForward = 4u;  // invisible medium boundary (Tungsten's "forward")

struct MaterialGpu {
    vec3 albedo; uint type;
    float ior; uint flags; float pad0; float pad1;
};
CONST uint kMaterialRefraction = 1u;  // flags: dielectric transmits

// ---- Lights ----
CONST uint kLightArea = 0u;    // an emissive Prim
CONST uint kLightPoint = 1u;
CONST uint kLightEnvironment = 2u;

// Radiance: area light (per unit area, one-sided for triangles/disks, outward for spheres),
// intensity for a point light, radiance for the environment.
struct LightGpu {
    vec3 position; uint type;  // point: position
    vec3 radiance; uint prim;  // area: the primitive index
    float pmf; float cdf; float pad0; float pad1;  // light selection probability, inclusive cdf
};

// ---- Participating media ----
CONST uint kMediumHomogeneous = 0u;
CONST uint kMediumExponential = 1u;  // density exp(-falloffScale dot(x - unitPoint, falloffDir))
CONST uint kMediumGrid = 2u;         // voxel grid over the box [gridMin, gridMax], trilinear
CONST uint kPhaseIsotropic = 0u;
CONST uint kPhaseHenyeyGreenstein = 1u;

struct MediumGpu {
    vec3 sigmaT; uint type;           // sigma_a + sigma_s, per unit density
    vec3 sigmaS; float density;
    vec3 falloffDir; float falloffScale;
    vec3 unitPoint; float phaseG;
    vec3 gridMin; uint gridOffset;    // first voxel in the grid-data buffer
    vec3 gridMax; float gridMaxDensity;
    uvec3 gridRes; float gridMinDensity;
    uint phase; uint pad0; uint pad1; uint pad2;
    TrModel model;
};

// Prim media: bits 0..15 the interior medium + 1, 16..30 the exterior medium + 1 (0 = vacuum);
// kPrimMediaNone: the prim has no media keys and leaves the current medium unchanged.
CONST uint kPrimMediaNone = 0xffffffffu;

SHADER_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(telescope::shader::MediumGpu) == 176);
static_assert(sizeof(telescope::shader::TrModel) == 48);
static_assert(sizeof(telescope::shader::Prim) == 64);
static_assert(sizeof(telescope::shader::BvhNode) == 32);
static_assert(sizeof(telescope::shader::MaterialGpu) == 32);
static_assert(sizeof(telescope::shader::LightGpu) == 48);
#endif

// ---- Path tracer pass (shaders/path_trace.comp) ----
SHADER_NAMESPACE_BEGIN

// Storage buffer bindings.
CONST uint kBindingPrims = 0u;
CONST uint kBindingBvh = 1u;
CONST uint kBindingMaterials = 2u;
CONST uint kBindingLights = 3u;
// Participating media (shaders/medium.glsl): bound for every scene, dummies without media.
CONST uint kBindingMedia = 4u;      // MediumGpu[]
CONST uint kBindingGridData = 5u;   // float voxel densities of every grid medium
CONST uint kBindingPrimMedia = 6u;  // uint per prim slot: media on its two sides (kPrimMedia*)
// The BVH nodes and primitives again, as uniform buffers (lavapipe loads from a uniform buffer
// about 1.8x as fast as from a storage buffer): read from there when they fit
// (kSpecSceneInUniforms). The scene buffers are padded to kUniformSceneBytes so both bindings
// always have a full range.
CONST uint kBindingBvhUniform = 7u;
CONST uint kBindingPrimsUniform = 8u;
CONST uint kPathTraceBindingCount = 9u;
CONST uint kUniformSceneBytes = 65536u;  // maxUniformBufferRange on lavapipe; the Vulkan minimum is 16384
CONST uint kMaxUniformNodes = 2048u;     // kUniformSceneBytes / sizeof(BvhNode)
CONST uint kMaxUniformPrims = 1024u;     // kUniformSceneBytes / sizeof(Prim)
CONST uint kSceneBindingCount = 4u;      // photon_trace and gather: the scene only (no media)

// Specialisation constant ids: features a scene lacks are folded away by the compiler.
CONST uint kSpecMaxBounces = 0u;
CONST uint kSpecMinBounces = 1u;
CONST uint kSpecDebiasMode = 2u;
CONST uint kSpecPmfType = 3u;
CONST uint kSpecPmfR = 4u;
CONST uint kSpecPmfAlpha = 5u;
CONST uint kSpecHasSpheres = 6u;
CONST uint kSpecHasDisks = 7u;
CONST uint kSpecHasSpecular = 8u;
CONST uint kSpecLightCount = 9u;
CONST uint kSpecLightSampling = 10u;
CONST uint kSpecTwoSided = 11u;
CONST uint kSpecFilter = 12u;
CONST uint kSpecEnvironmentLight = 13u;  // light index, or 0xffffffff for none
CONST uint kSpecMaxTraceDepth = 14u;
CONST uint kTraceDepthCap = 4096u;       // rays per path at most (a debiased level beyond adds nothing)
CONST uint kSpecRayEpsilon = 15u;        // absolute ray offset, from the scene size
CONST uint kSpecPilot = 16u;             // pmf pilot: every sample takes the level pc.pilotLevel
CONST uint kSpecLevelSchedule = 17u;     // kLevelSchedule*: how per-sample levels are laid out on lanes
CONST uint kSpecSceneInUniforms = 18u;   // BVH nodes and primitives read from the uniform bindings

// Participating media, ids 32..47 (shaders/medium.glsl).
CONST uint kSpecHasMedia = 32u;          // media or forward (index-matched) boundaries present
CONST uint kSpecTrEstimator = 33u;       // kTrEst* (shared/transmittance_estimators.h)
CONST uint kSpecTrLevel = 34u;
CONST uint kSpecTrPmfType = 35u;
CONST uint kSpecTrPmfR = 36u;
CONST uint kSpecTrPmfAlpha = 37u;
CONST uint kSpecCameraMedium = 38u;      // medium index + 1, 0 = vacuum
CONST uint kSpecHasGrids = 39u;
CONST uint kSpecTrModel = 40u;           // the transmittance model every medium shares, or 0xffffffff

CONST uint kFilterBox = 0u;
CONST uint kFilterTent = 1u;
CONST uint kFilterDirac = 2u;

CONST uint kPathTraceGroupSize = 8u;  // 8x8 pixel tiles

struct PathTracePush {
    vec3 cameraPosition; float planeDistance;
    vec3 cameraRight; uint width;
    vec3 cameraUp; uint height;
    vec3 cameraForward; uint seed;
    uint sampleBase;    // global index of the first sample of this dispatch
    uint sampleCount;   // samples per pixel in this dispatch
    uint accumAddressLo; uint accumAddressHi;  // device address of the accumulation buffer
    uint pilotLevel;    // pmf pilot only (kSpecPilot): the fixed level m = j - k
    uint queueAddressLo; uint queueAddressHi;  // level queue (kLevelScheduleQueued only)
    uint queueCapacity;                        // items the level queue holds
};

// ---- Level scheduling (ESTIMATORS.md section 1; issue "level scheduling") ----
// per_pixel: each lane traces its own pixel's samples, each sample with its own level (the
//            paper's estimator; lanes of a SIMD group hold paths of different lengths).
// uniform:   one level per sample index shared by every pixel of the dispatch: no level
//            divergence, still unbiased per pixel, but errors are correlated across pixels.
// queued:    the per_pixel estimator sample for sample (same random numbers), with the work
//            sorted by level: level_count / level_scan / level_scatter build a queue of
//            (pixel, sample) items ordered by level (a counting sort over chunks of items, one
//            lane per chunk: no atomics, so the queue and the image are repeatable), lane i of
//            path_trace takes queue slots i, i + lanes, ... (neighbouring lanes hold the same
//            level), and path_resolve accumulates the per-item results in sample order.
CONST uint kLevelSchedulePerPixel = 0u;
CONST uint kLevelScheduleUniform = 1u;
CONST uint kLevelScheduleQueued = 2u;
CONST uint kLevelBuckets = 64u;          // levels >= 63 share the last bucket
CONST uint kLevelChunk = 64u;            // items per lane in level_count / level_scatter
CONST uint kLevelQueueGroupSize = 64u;
// Queue block, by device address, for `capacity` items in chunks = ceil(capacity / kLevelChunk):
//   uint chunkOffsets[chunks * kLevelBuckets]  (counts, then slot offsets after level_scan)
//   uint items[capacity]                        (item = sample * pixelCount + pixel)
//   vec4 results[2 * capacity]                  (base rgb + non-finite flag, correction rgb)
// each region starting on a 16-byte boundary.

// Accumulation: per pixel and channel a compensated sum (hi, lo) of vec4.
// index of the hi part = (channel * pixelCount + pixel) * 2, lo = hi + 1.
CONST uint kChannelEstimate = 0u;    // rgb: sum of Z; w: non-finite samples dropped
CONST uint kChannelEstimateSq = 1u;  // rgb: sum of Z^2
CONST uint kChannelBase = 2u;        // rgb: sum of the base I(k)
CONST uint kChannelCorrection = 3u;  // rgb: sum of the correction Z - I(k)
CONST uint kChannelCorrectionPositive = 4u;  // rgb: sum of max(correction, 0)
CONST uint kChannelCorrectionNegative = 5u;  // rgb: sum of min(correction, 0)
CONST uint kChannelCount = 6u;

SHADER_NAMESPACE_END
#ifdef __cplusplus
static_assert(sizeof(telescope::shader::PathTracePush) == 96);
#endif

// ---- Photon mapping passes (photon_trace, hash_grid_build, gather; ESTIMATORS.md section 3) ----
// Specialisation ids 48..63 (32..47 belong to participating media). The photon passes also take
// the scene switches of the path tracer (kSpecHasSpheres ... kSpecRayEpsilon, same ids). Every
// photon buffer is reached by device address, so none is bound by the 128 MiB binding limit.
SHADER_NAMESPACE_BEGIN

CONST uint kSpecPhotonEstimator = 48u;   // kPhotonBiased or kPhotonUnbiased
CONST uint kSpecPhotonKernel = 49u;      // kKernelCone, kKernelUniform, kKernelEpanechnikov
CONST uint kSpecPhotonLevels = 50u;      // kPmfGeometric or kPmfPowerLaw: radius schedule and pmf
CONST uint kSpecPhotonPmfR = 51u;
CONST uint kSpecPhotonPmfAlpha = 52u;
CONST uint kSpecPhotonNextEvent = 53u;   // direct light by next-event estimation, not photons
CONST uint kSpecGridStage = 54u;         // hash_grid_build: which stage this pipeline runs
CONST uint kSpecPhotonMaxBounces = 55u;  // scattering vertices of a photon path / camera chain

CONST uint kPhotonBiased = 0u;    // K_r at the pass radius (fixed radius, or the PPM schedule)
CONST uint kPhotonUnbiased = 1u;  // K_{r_b} + (K_{r_{j+1}} - K_{r_j}) / p(j | j >= b)

CONST uint kGridStageClear = 0u;    // cellCount = 0
CONST uint kGridStageCount = 1u;    // photon -> cell hash, cellCount[h]++
CONST uint kGridStageScan = 2u;     // exclusive scan of 1024-element blocks, block totals out
CONST uint kGridStageAdd = 3u;      // adds the scanned block totals back
CONST uint kGridStageScatter = 4u;  // sorted[cellStart[h]++] = photon (a copy, read in order by the gather)
CONST uint kGridStageQuery = 5u;    // kernel sums at query points (tests)

CONST uint kPhotonTraceGroupSize = 64u;
CONST uint kGridGroupSize = 256u;
CONST uint kScanBlock = 1024u;      // elements per scan workgroup (4 per thread)
CONST uint kGatherGroupSize = 8u;   // 8x8 pixel tiles

// A stored photon: where it landed, where it came from (octahedral, 2 x snorm16) and its power
// (flux per emitted path of the pass). cell is the hash bucket, written by the count stage.
struct Photon {
    vec3 position; uint cell;
    vec3 power; uint direction;
};

// The photon map of one pass, in device memory, reached by address. photon_trace counts every
// photon it stores in storedCount, also those beyond capacity (which it drops): the host then
// grows the buffers and repeats the pass, so no photon is ever lost.
struct PhotonMapHeader {
    uint storedCount; uint capacity; uint tableSize; float cellSize;
    uint photonsLo; uint photonsHi; uint sortedLo; uint sortedHi;  // photons as stored, and in bucket order
    uint cellCountLo; uint cellCountHi; uint cellStartLo; uint cellStartHi;
};

struct PhotonTracePush {
    uint headerLo; uint headerHi;
    uint pathCount;   // photon paths emitted this pass
    uint pass;        // pass index (the sample index of the render)
    uint seed;
    float pathScale;  // 1 / pathCount
    uint rowThreads;  // threads per row of the 2D dispatch: path = y * rowThreads + x
    uint pad0;
};

struct HashGridPush {
    uint headerLo; uint headerHi;
    uint srcLo; uint srcHi;    // scan / add / query: input array
    uint dstLo; uint dstHi;    // scan / add / query: output array
    uint sumsLo; uint sumsHi;  // scan: block totals out; add: scanned block totals in
    uint count;                // scan / add: elements; query: queries
    float radius;              // query: r_b
    float logRadius2;          // query: ln(r_j^2 / r_b^2)
    float logStep2;            // query: ln(r_{j+1}^2 / r_j^2)
};

struct GatherPush {
    vec3 cameraPosition; float planeDistance;
    vec3 cameraRight; uint width;
    vec3 cameraUp; uint height;
    vec3 cameraForward; uint seed;
    uint pass;          // sample index
    uint accumLo; uint accumHi;
    uint headerLo; uint headerHi;
    float radius;       // r_b: the base (largest) radius of this pass
    float baseLevel;    // b: the level of r_b (unbiased), 1 + pass for the progressive variant
    uint pad0;
};

SHADER_NAMESPACE_END
#ifdef __cplusplus
static_assert(sizeof(telescope::shader::Photon) == 32);
static_assert(sizeof(telescope::shader::PhotonMapHeader) == 48);
static_assert(sizeof(telescope::shader::PhotonTracePush) == 32);
static_assert(sizeof(telescope::shader::HashGridPush) == 48);
static_assert(sizeof(telescope::shader::GatherPush) == 96);
#endif

#endif
