// Data layouts shared by the host and the shaders: GPU structs, binding indices, push constants
// and specialisation constants. Every struct is laid out as (vec3, 4-byte scalar) pairs so that
// std430 and the C++ layout agree; the C++ side checks sizes with static_assert.
#ifndef TELESCOPE_GPU_TYPES_H
#define TELESCOPE_GPU_TYPES_H

#include "shared/enums.h"
#include "shared/transmittance.h"

SHADER_NAMESPACE_BEGIN

// ---- Geometry (type: kPrim*, shared/enums.h) ----
// A ray-traceable primitive. Triangle: p0, p1, p2. Sphere: centre p0, radius p1.x.
// Disk: centre p0, radius p1.x, unit normal n. n is the geometric (emitting) normal.
struct Prim {
    vec3 p0; uint type;
    vec3 p1; uint material;
    vec3 p2; int light;      // index into the light table, -1 if not emissive
    vec3 n;  float area;
};
FN uint primShape(Prim p) { return p.type & kPrimShapeMask; }  // kPrim*, without the flags

// BVH node with four children (src/scene/bvh.h collapseBvh; 64 bytes, 4 texels). Child c's box is
// origin + q * scale per axis, q the byte c of the quantised bounds (qLo.x: lo.x, qLo.y: lo.y,
// qLo.z: lo.z, qLo.w: hi.x; qHi.x: hi.y, qHi.y: hi.z); scale is a power of two, so q * scale is
// exact and every device decodes the same floats the host checked to enclose the child. child[c]:
// a node index, or a leaf (kBvhLeaf | first << 4 | count: prims [first, first + count)), or
// kBvhNoChild with an empty box (lo > hi). Node 0 is the root.
struct BvhNode {
    vec3 origin; float scaleX;
    uvec4 qLo;
    uvec2 qHi; vec2 scaleYZ;
    uvec4 child;
};
CONST uint kBvhLeaf = 0x80000000u;
CONST uint kBvhNoChild = 0xffffffffu;
CONST uint kBvhMaxLeafSize = 15u;  // the count's four bits

// ---- Materials (type: kBsdf*) ----
struct MaterialGpu {
    vec3 albedo; uint type;
    float ior; uint flags; float roughness; uint distribution;  // roughness, kMicrofacet*: microfacet types
    vec3 eta; float diffuseFresnel;    // conductors: complex index eta + i k; plastics: Fdr,
    vec3 k; float substrateWeight;     // k = tau = thickness sigma_a, mean(albedo) exp(-2 mean(tau)) (layered.h)
    uint albedoTexture; uint roughnessTexture; uint texturePad0; uint texturePad1;  // kNoTexture or a TextureGpu index
    // mixed: components 0 and 1 (material indices), ratio = the weight of component 0; transparency:
    // component0 = the base, alpha = its opacity (thinsheet: roughness = thickness, k = thickness sigma_a)
    uint component0; uint component1; float ratio; float alpha;
};
CONST uint kMaterialRefraction = 1u;  // flags: dielectric transmits
CONST uint kMaterialInterference = 2u;  // flags: thinsheet with thin-film interference
CONST uint kMaterialBothSides = 4u;  // flags: photons are stored on both sides (a rough dielectric, or a composite with one)

// ---- Textures (type: kTexture*; shared/texture.h) ----
// Constant: value = on. Checker: on, off, res = (res_u, res_v). Bitmap: scale = on, res = (width,
// height), texels (RGBA float, row-major from the top row) from vec4 index `offset` of the texture
// buffer; flags kTexture*.
struct TextureGpu {
    vec3 on; uint type;
    vec3 off; uint flags;
    uvec2 res; uint offset; uint pad;
};
CONST uint kNoTexture = 0xffffffffu;
CONST uint kTextureInterpolate = 1u;  // bilinear (Tungsten's "interpolate"), else nearest
CONST uint kTextureClamp = 2u;        // clamp to the edge (Tungsten's "clamp"), else wrap

// ---- Lights (type: kLight*) ----
// Radiance: area light (per unit area, one-sided for triangles/disks, outward for spheres),
// intensity for a point light, radiance for the environment.
struct LightGpu {
    vec3 position; uint type;  // point: position
    vec3 radiance; uint prim;  // area: the primitive index
    float pmf; float cdf; float cosCap; float pad1;  // light selection probability, inclusive cdf;
                                                     // cap: cosine of the half angle (position: its axis)
};

// ---- Participating media (type: kMedium*, phase: kPhase*) ----
struct MediumGpu {
    vec3 sigmaT; uint type;           // sigma_a + sigma_s, per unit density
    vec3 sigmaS; float density;
    vec3 falloffDir; float falloffScale;
    vec3 unitPoint; float phaseG;
    // Grids (docs/MEDIA.md): world -> unit box [0, 1]^3, the rows of an affine map
    vec4 gridRow0; vec4 gridRow1; vec4 gridRow2;
    uvec3 gridRes; uint gridOffset;            // first voxel in the grid-data buffer
    uvec3 majorantRes; uint majorantOffset;    // majorant cells: (min, max) density pairs
    vec3 majorantScale; uint gridFlags;        // cell coordinate = unit point * majorantScale; kGrid*
    float gridMaxDensity; float gridMinDensity; uint emissionOffset; uint phase;  // emission: 3 floats a voxel
    uint maxBounces; uint pad0; uint pad1; uint pad2;  // maxBounces: Tungsten's per-medium limit
    TrModel model;
};
CONST uint kGridNearest = 1u;            // nearest-voxel lookups (else trilinear)
CONST uint kGridEmission = 2u;           // the medium emits (emissionOffset is valid)
CONST uint kGridEmissionByDensity = 4u;  // emission times the density

// Prim media: bits 0..15 the interior medium + 1, 16..30 the exterior medium + 1 (0 = vacuum);
// kPrimMediaNone: the prim has no media keys and leaves the current medium unchanged.
CONST uint kPrimMediaNone = 0xffffffffu;

SHADER_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(telescope::shader::MediumGpu) == 240);
static_assert(sizeof(telescope::shader::TrModel) == 48);
static_assert(sizeof(telescope::shader::Prim) == 64);
static_assert(sizeof(telescope::shader::BvhNode) == 64);
static_assert(sizeof(telescope::shader::MaterialGpu) == 96);
static_assert(sizeof(telescope::shader::TextureGpu) == 48);
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
// Textures (shared/texture.h): one vec4 buffer with the texture table, per-prim uv maps and texels;
// a dummy vec4 without textures.
CONST uint kBindingTextures = 9u;
// The environment image of an infinite_sphere and its sampling tables (shared/environment_map.h;
// one dummy float without): every path_trace pipeline binds it, only kSpecEnvironmentMap reads it.
CONST uint kBindingEnvironment = 10u;
// The materials, lights and media again, as uniform buffers of kUniformSceneBytes: read from there
// when all three fit (kSpecTablesInUniforms). Lavapipe serves a divergent uniform-buffer load with
// vector gathers, where a storage-buffer load loops over the lanes once per component.
CONST uint kBindingMaterialsUniform = 11u;
CONST uint kBindingLightsUniform = 12u;
CONST uint kBindingMediaUniform = 13u;
// Smooth-shaded triangles' vertex normals (scene_common.glsl shadingNormal): three vec4 per prim
// slot, (n0, 1 if smooth), (n1, 0), (n2, 0); one dummy vec4 in scenes without smooth triangles.
CONST uint kBindingShadingNormals = 14u;
// The BVH nodes (4 texels each: origin, scale x; the low bytes; the high bytes, scale y, z; the
// children) and primitives (4 texels each: p0, type; p1, material; p2, light; n, area) once
// more, as uniform texel buffers of 4 x uint32 texels: read from
// there when they do not fit the uniform bindings but fit maxTexelBufferElements
// (kSpecSceneTexels). Lavapipe fetches a texel for all 8 lanes of a SIMD group with vector loads,
// where a divergent storage-buffer load loops over the lanes once per component. The shading
// normals (kBindingShadingNormals) likewise, 3 texels per prim slot.
CONST uint kBindingBvhTexels = 15u;
CONST uint kBindingPrimsTexels = 16u;
CONST uint kBindingShadingNormalTexels = 17u;
// The prims' media (kBindingPrimMedia) again, as a uniform buffer of kUniformSceneBytes (uvec4s of
// four prim slots), read with the uniform scene (kSpecSceneInUniforms: at most kMaxUniformPrims
// slots). Lavapipe loads a storage buffer at lane-varying indices in a loop over the lanes that
// stalls on every lane's store; from a uniform buffer the load is a gather.
CONST uint kBindingPrimMediaUniform = 18u;
CONST uint kPathTraceBindingCount = 19u;
CONST uint kUniformSceneBytes = 65536u;  // maxUniformBufferRange on lavapipe; the Vulkan minimum is 16384
CONST uint kMaxUniformNodes = 1024u;     // kUniformSceneBytes / sizeof(BvhNode)
CONST uint kMaxUniformPrims = 1024u;     // kUniformSceneBytes / sizeof(Prim)
CONST uint kMaxUniformMaterials = 682u;  // kUniformSceneBytes / sizeof(MaterialGpu), rounded down
CONST uint kMaxUniformLights = 1365u;    // ... / sizeof(LightGpu)
CONST uint kMaxUniformMedia = 273u;      // ... / sizeof(MediumGpu)
CONST uint kMaxUniformPrimMediaVec4s = 4096u;  // ... / sizeof(uvec4)
CONST uint kSceneBindingCount = 18u;     // photon_trace and gather: the scene only (4-6 and 13 unused; the gather's texels at 4)

// Specialisation constants (ids, GLSL declarations): shared/spec_constants.h, included at the end.
CONST uint kTraceDepthCap = 4096u;       // rays per path at most (a debiased level beyond adds nothing)

// ---- Lavapipe's loop cap and path_trace's loop budget (docs/ARCHITECTURE.md "Loop budget") ----
// Lavapipe (llvmpipe) keeps one loop counter per SIMD group and shader invocation: every
// iteration of every loop, in any lane or in none (a loop under a branch no lane took still runs
// once), counts, and at 65535 every loop of the invocation ends, without a word. path_trace
// therefore counts the loop iterations of each lane (gLoopTicks): a lane past its budget starts no
// new step but carries its path to the next dispatch in a continuation record (the host
// dispatches again until no record is left); the long walks of media stop at a hard limit. A
// probe after the work (loop_cap.glsl) sees whether the cap was reached anyway (the counts of
// BVH walks are estimates): then the lane undoes its dispatch (nothing is accumulated) and
// retries it from where it started at the safe budget, a quarter of the cap per group; a walk that stopped
// at the hard limit is retried alone (heavy). Only a cap reached at the safe budget, or a step too
// long to run even alone, is an error, counted and reported.
CONST uint kLavapipeLoopCap = 65535u;
CONST uint kLoopBudgetLanes = 8u;  // lavapipe's SIMD width for 32-bit lanes (256-bit llvmpipe)
CONST uint kDefaultLoopBudget = 16384u;  // per lane and dispatch; lanes of a group mostly walk together
CONST uint kRayLoopTicks = 32u;          // a BVH walk counts as this many iterations (intersect.h)
CONST uint kSafeLoopBudget = 2048u;  // 8 lanes x 2048: a quarter of the cap, room for walks 3x their estimate
CONST uint kSafeHardLimit = kLavapipeLoopCap / kLoopBudgetLanes;        // 8191
// A heavy step (a walk past the hard limit) runs alone in a dispatch that finishes carried paths:
// the lowest lane of its group holding one, the others waiting, with most of the cap.
CONST uint kHeavyLoopBudget = kLavapipeLoopCap / 8u * 7u;  // 57337
// The loop statistics buffer (by device address, uint counters, cumulative over a render):
CONST uint kLoopStatCapHits = 0u;   // lanes that reached lavapipe's cap at the safe budget or alone (an error)
CONST uint kLoopStatCarried = 1u;   // continuation records written
CONST uint kLoopStatResumed = 2u;   // continuation records taken up
CONST uint kLoopStatOverlong = 3u;  // samples dropped: one step did not fit the cap even alone (an error)
CONST uint kLoopStatRetried = 4u;   // lane dispatches undone and retried (the cap or a hard limit reached)
CONST uint kLoopStatCount = 5u;
// A continuation record: kContinuationVec4s vec4 per lane (path_trace_main.glsl saveRecord).
CONST uint kContinuationVec4s = 8u;
// The continuation buffer: each lane's record flags first (one uint per lane, kRecord*; zeroed
// before the first dispatch), padded to 16 bytes, then the records, each written before it is read.
// The records are never zeroed: only lanes that carry a path touch their pages (zeroing the 8 MiB
// of a 256x256 render cost 16 ms of a 0.32 s render on lavapipe: docs/BENCHMARKS.md).
FN uint continuationFlagBytes(uint lanes) { return (lanes * 4u + 15u) & ~15u; }

// The largest scene traced primitive by primitive (kSpecBruteForcePrims; break-even ~24:
// docs/BENCHMARKS.md).
CONST uint kMaxBruteForcePrims = 20u;
// The path tracer's own limit (unrolled loops of scalar loads against BVH walks over texels with
// the stack in registers, 2026-12-06, taking turns, M paths/s: Tungsten's volumetric caustic, 8
// primitives, 3.12-3.25 brute force against 1.78-2.10 BVH; its Cornell box, 18, 4.42-5.65 against
// 5.75-6.09).
CONST uint kMaxBruteForcePathPrims = 12u;
// The largest BVH walk stack the path tracer keeps in registers (kSpecBvhStackNeed).
CONST uint kMaxRegisterBvhStack = 16u;
// The transmittance pilot's (kSpecTrPilot) pc.pilotLevel bit: the correction weighted by 2, not 1.
CONST uint kTrPilotHalfWeight = 0x80000000u;

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
    uint pilotAddressLo; uint pilotAddressHi;  // pmf pilot only: its result buffer (kPilot*)
    uint stateAddressLo; uint stateAddressHi;  // continuation records (kContinuationVec4s per lane)
    uint statsAddressLo; uint statsAddressHi;  // loop statistics (kLoopStat*)
};

// The pmf pilot's result buffer (render/pmf_pilot.h): per pixel, compensated (hi, lo) sums of
// its own channels, laid out like the film's: index of the hi part = (channel * pixels + pixel) * 2.
CONST uint kPilotCorrection = 0u;     // rgb: sum of the unweighted correction D_j; w: non-finite samples
CONST uint kPilotCorrectionSq = 1u;   // rgb: sum of D_j^2
CONST uint kPilotBase = 2u;           // rgb: sum of the base I(k) of the same paths
CONST uint kPilotBaseSq = 3u;         // rgb: sum of I(k)^2
CONST uint kPilotRays = 4u;           // x: rays traced (the pilot's cost model)
CONST uint kPilotChannelCount = 5u;

// ---- Level scheduling (docs/ESTIMATORS.md section 1; issue "level scheduling") ----
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
CONST uint kChannelEstimateSq = 1u;  // rgb: sum of Z^2; w: samples of this pixel when pixels differ
                                     // (photon per_pixel schedule), else 0 (every pixel has spp)
CONST uint kChannelBase = 2u;        // rgb: sum of the base I(k)
CONST uint kChannelCorrection = 3u;  // rgb: sum of the correction Z - I(k)
CONST uint kChannelCorrectionPositive = 4u;  // rgb: sum of max(correction, 0)
CONST uint kChannelCorrectionNegative = 5u;  // rgb: sum of min(correction, 0)
CONST uint kChannelCount = 6u;

SHADER_NAMESPACE_END
#ifdef __cplusplus
static_assert(sizeof(telescope::shader::PathTracePush) == 120);  // at most 128 (Vulkan's guaranteed push constants)
#endif

// ---- Photon mapping passes (photon_trace, hash_grid_build, gather; docs/ESTIMATORS.md section 3) ----
// Their specialisation constants are ids 48..63 of shared/spec_constants.h; they also take the
// scene switches of the path tracer (kSpecHasSpheres ... kSpecRayEpsilon, same ids). Every
// photon buffer is reached by device address, so none is bound by the 128 MiB binding limit; the
// gather also binds the sorted photons as a texel buffer (photon_gather.glsl).
SHADER_NAMESPACE_BEGIN

// The counts are zero before the count stage: the host clears them once, when it allocates them,
// and the scan zeroes each count as it reads it, for the next pass.
CONST uint kGridStageCount = 0u;    // photon -> cell hash, cellCount[h]++
CONST uint kGridStageScan = 1u;     // exclusive scan of kScanBlock-element blocks, block totals out
CONST uint kGridStageAdd = 2u;      // adds the scanned block totals back
CONST uint kGridStageScatter = 3u;  // sorted[cellStart[h]++] = photon (a copy, read in order by the gather)
CONST uint kGridStageQuery = 4u;    // kernel sums at query points (tests)
// hash_grid_build's bindings: the photon arrays as texels (read) and storage texels (written);
// stages built without them (kSpecSortedTexels off) reach the arrays by address.
CONST uint kGridBindingSortedTexels = 0u;  // the sorted photons (query stage)
CONST uint kGridBindingPhotonTexels = 1u;  // the photons as traced (scatter stage)
CONST uint kGridBindingSortedImage = 2u;   // the sorted photons, written by the scatter
CONST uint kGridBindingCountImage = 3u;    // bucket counts
CONST uint kGridBindingStartImage = 4u;    // bucket starts (ends after the scatter)
CONST uint kGridBindingCount = 5u;

// The gather's bindings: the scene's (kSceneBindingCount), the sorted photons as a uniform texel
// buffer (photon_gather.glsl) in the media's place (photon mapping scenes have no media).
CONST uint kBindingSortedTexels = 4u;
CONST uint kGatherBindingCount = 18u;

CONST uint kPhotonTraceGroupSize = 64u;
CONST uint kGridGroupSize = 256u;
CONST uint kScanBlock = 4096u;      // elements per scan workgroup (16 per thread)
CONST uint kGatherGroupSize = 8u;   // 8x8 pixel tiles
// Lavapipe ends the loops of a shader invocation after 65535 iterations in all (one counter per
// SIMD group for every loop of the shader, without a word). A gather therefore reads at most
// kGatherSlicePhotons photons of each of its 8 buckets per dispatch: a pass whose fullest bucket
// holds more runs the gather in several slices (dispatches), each adding its part of the sums.
CONST uint kGatherSlicePhotons = 4096u;
CONST uint kGatherBlockVec4s = 12u;  // per-pixel block buffer of the gather (gather.comp)
// k-nearest gathers keep the k nearest photons (squared distance, sorted index) of a pixel across
// slices: after the block vec4s, kMaxGatherCount / 2 vec4 more per pixel.
CONST uint kMaxGatherCount = 64u;
// A k-nearest gather searches cells of side r_b / kNearestCellsPerRadius, the 5x5x5 around x's own
// (photon_gather.glsl nearestSearch).
CONST uint kNearestCellsPerRadius = 2u;
CONST uint kNearestCellsPerAxis = 2u * kNearestCellsPerRadius + 1u;
CONST uint kNearestCells = kNearestCellsPerAxis * kNearestCellsPerAxis * kNearestCellsPerAxis;  // 125
// It keeps the k nearest in slots whose loops are unrolled (photon_gather.glsl): one loop
// iteration a photon. Its slices read 320 photons of each of its 125 buckets: at most
// 125 x (1 + 320) = 40125 loop iterations, within lavapipe's 65535 with the camera chain's
// traversal. (A slice is a dispatch over every pixel still gathering, about 11 ms on the water
// caustic even when few pixels have photons left: 48 photons a slice, when a max-heap's sift took
// up to 6 iterations more a photon, made 340 slices of its 32 passes, 320 make 83.)
CONST uint kGatherSliceNearestPhotons = 320u;
// Photons of each bucket one gather dispatch reads (gatherCount: the k of a k-nearest gather, or 0).
FN uint gatherSlicePhotons(uint gatherCount) {
    return gatherCount > 0u ? kGatherSliceNearestPhotons : kGatherSlicePhotons;
}
// The slice length the gather and the query stage are built with (photon_gather.glsl,
// kSpecGatherSliceLength): the host's PhotonMap::sliceLength, gatherSlicePhotons unless a test
// lowers it.

// A stored photon: where it landed, where it came from (octahedral, 2 x snorm16) and its power
// (flux per emitted path of the pass).
struct Photon {
    vec3 position; uint vertex;  // vertex: the light path's vertex index v >= 1 where it was stored
    vec3 power; uint direction;
};

// Rounds of a pass under Tungsten's photon_count cap, at most (render/photon_passes.cpp,
// photonBudget); a round has at least kPhotonCapRoundPaths paths.
CONST uint kPhotonCapRounds = 64u;
CONST uint kPhotonCapRoundPaths = 1024u;

// The photon map of one pass, in device memory, reached by address. photon_trace counts every
// photon it stores in storedCount, also those beyond capacity (which it drops): the host then
// grows the buffers and repeats the pass, so no photon is ever lost.
// maxBucket: the photons of the fullest bucket (written by the scan), which sets the gather's slices.
// The two counters that shaders change with atomics have a 64-byte cache line of their own: next to
// the fields every photon store reads (capacity, addresses), each atomic on one core made the
// other core's next read of those fields a miss (lavapipe; the header's first 128 bytes are for
// that). photon_trace's round counters follow, one per round (only the round in flight is written).
struct PhotonMapHeader {
    uint capacity; uint tableSize; float cellSize;
    uint powerPaths;  // the paths the stored powers were divided by when fewer were traced (Tungsten's cap), else 0

    uint photonsLo; uint photonsHi; uint sortedLo; uint sortedHi;  // photons as stored, and in bucket order
    uint cellCountLo; uint cellCountHi; uint cellStartLo; uint cellStartHi;
    uint pad1; uint pad2; uint pad3; uint pad4;
    uint storedCount; uint maxBucket; uint loopCapHits;  // written by atomics: a cache line of their own
    uint tracedPaths;  // photon paths traced this pass (photon_trace counts them)
    uint cappedAtRound;  // capped passes: the first round whose photons reached storeCap (~0u: none yet)
    uint pad8; uint pad9; uint pad10;
    uint pad11; uint pad12; uint pad13; uint pad14;
    uint pad15; uint pad16; uint pad17; uint pad18;
    uint roundTaken[kPhotonCapRounds];  // the lanes of round r that photon_trace's subgroups have taken
};

// One photon_trace dispatch, round roundIndex of the pass: lane l traces path
// roundIndex * laneCount + l if it is below pathCount (a dispatch has a thread for every lane, and
// its subgroups take the lanes in chunks: photon_trace.comp traceLanes). Uncapped (storeCap ~0u): one round of pathCount
// lanes, path i in stretch i of pathCount of the emission curve. Capped (Tungsten's photon_count:
// render/photon_passes.cpp "Photon budget"): a round is traced only while the earlier rounds
// stored fewer than storeCap photons; lane l's path of round r takes the stretch
// l 2^roundBits + bitfieldReverse(r) (roundBits bits) of the curve, shifted by curveShift.
struct PhotonTracePush {
    uint headerLo; uint headerHi;
    uint pathCount;   // photon paths this pass may trace (photon_count)
    uint pass;        // pass index (the sample index of the render)
    uint seed;
    float pathScale;  // 1 / pathCount
    uint passInBlock; // pass within the block (unbiased photon mapping), else 0
    uint pad0;        // (std430 puts the vec3 at 16 bytes)
    vec3 sceneCentre; float sceneRadius;  // a sphere around the geometry: lights at infinity emit through its disk
    uint laneCount; uint roundIndex; uint roundBits;
    uint storeCap;    // capped: photons after which no further round starts; ~0u: uncapped
    uint curveShift;  // capped: a uniform shift of the emission curve, drawn per pass
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
    uint sliceBegin;           // query: first photon of each bucket this dispatch reads
    uint tableLevel;           // scan / add: 1 for the table's own level: the scan reads the bucket
                               // counts (texels where the stages use them), zeroes them, sets maxBucket
    uint pad1; uint pad2;
};

// One gather dispatch: slice `slice` of `sliceCount` of a photon pass. Unbiased photon mapping:
// `pass` is the block index (uniform schedule) or the pass index (per_pixel), `passInBlock` the
// pass within the block; level is the uniform schedule's (per_pixel draws its own from the pmf
// below).
struct GatherPush {
    vec3 cameraPosition; float planeDistance;
    vec3 cameraRight; uint width;
    vec3 cameraUp; uint height;
    vec3 cameraForward; uint seed;
    uint pass;          // pass index (biased, progressive), block or pass index (unbiased)
    uint accumLo; uint accumHi;
    uint headerLo; uint headerHi;
    float radius;       // r_b: the base (largest) radius of this pass
    uint blockLo; uint blockHi;  // per-pixel block sums (unbiased) and the slices' partial sums
    uint slice; uint sliceCount;
    uint level;         // uniform schedule: the block's level k (of photonBlockPasses() passes)
    uint passInBlock;
    float pmfR;         // p(k) = r (1 - r)^k / (1 - (1 - r)^K), k < K
    float logAreaRatio; // ln s: r_k^2 = r_b^2 s^k
    uint photonGrowth;  // m: a level-k block has m^k passes
    uint levelCap;      // K
};

SHADER_NAMESPACE_END
#ifdef __cplusplus
#include <cstddef>
static_assert(sizeof(telescope::shader::Photon) == 32);
static_assert(sizeof(telescope::shader::PhotonMapHeader) == 384);
static_assert(sizeof(telescope::shader::PhotonTracePush) == 68);
static_assert(offsetof(telescope::shader::PhotonTracePush, sceneCentre) % 16 == 0);  // std430 aligns a vec3 to 16
static_assert(sizeof(telescope::shader::HashGridPush) == 64);
static_assert(sizeof(telescope::shader::GatherPush) == 128);
#endif

// Last: the table's defaults name the constants above.
#include "shared/spec_constants.h"

#endif
