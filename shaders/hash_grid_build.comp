// hash_grid_build: the photon hash grid on the device, one stage per pipeline (kSpecGridStage):
// count photons per bucket, exclusive prefix sum of the counts (kScanBlock-element blocks, block
// totals scanned recursively, then added back), and scatter copies of the photons into bucket
// order (so that a gather reads each bucket contiguously). After the scatter cellStart[h] holds the
// END of bucket h's range, which is where bucket h + 1's begins: a gather reads a bucket's range
// from two neighbouring entries, and the counts are not needed after the scan, which zeroes them
// as it reads them (the next pass's count starts from zero with no clearing pass). The scan of the
// counts also records the fullest bucket (PhotonMapHeader::maxBucket), from which the host sizes
// the gather's slices. The query stage evaluates one slice of gatherPhotons() at given points (tests).
// Loops are grid-stride over at most 4096 x 256 threads, so a thread runs at most 2^31 / 2^20 =
// 2048 iterations (lavapipe stops the loops of an invocation after 65535 iterations in all).
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require  // [[unroll]]: photon_gather.glsl
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require
#extension GL_KHR_shader_subgroup_arithmetic : require

#include "shared/gpu_types.h"
#include "shared/photon_density.h"

layout(local_size_x = kGridGroupSize) in;
layout(push_constant) uniform Push { HashGridPush pc; };

layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonMapRef { PhotonMapHeader h; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonArrayRef { Photon p[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintArrayRef { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4ArrayRef { vec4 v[]; };

// The photon arrays as texels of 4 x uint32 (two per photon) when they fit a texel buffer
// (kSpecSortedTexels, photon_gather.glsl): the photons as stored (read by the count and the
// scatter), and in bucket order (written by the scatter, read by the query). Lavapipe reads and
// writes a texel for all lanes at once, where a storage-buffer or address access loops over the
// lanes once per component.
layout(binding = kGridBindingSortedTexels) uniform usamplerBuffer sortedTexels;
layout(binding = kGridBindingPhotonTexels) uniform usamplerBuffer photonTexels;
layout(binding = kGridBindingSortedImage, rgba32ui) uniform writeonly uimageBuffer sortedImage;
// The table's counts and starts, 4 buckets a texel (the scan and add of the table's own level).
layout(binding = kGridBindingCountImage, rgba32ui) uniform uimageBuffer countImage;
layout(binding = kGridBindingStartImage, rgba32ui) uniform uimageBuffer startImage;
#include "photon_gather.glsl"

// Per subgroup of the workgroup: its total and its largest count (at most one subgroup per thread).
shared uint subgroupTotals[kGridGroupSize];
shared uint subgroupMaxima[kGridGroupSize];

uint threadCount() { return gl_NumWorkGroups.x * kGridGroupSize; }


// Exclusive scan of one block of kScanBlock elements: 16 per thread (4 texels), the thread totals
// scanned within each subgroup (subgroupInclusiveAdd), then across the subgroups through shared
// memory with one barrier (a Hillis-Steele scan over the 256 threads took 16 barriers, and on
// lavapipe each barrier switches every invocation of the workgroup), then the block total to
// sums[block]. 16 elements a thread rather than 4 made the table's scan about 2x cheaper on
// lavapipe (docs/BENCHMARKS.photon-notes.md): a quarter of the subgroup operations and barriers.
void scanBlock() {
    UintArrayRef src = UintArrayRef(uvec2(pc.srcLo, pc.srcHi));
    UintArrayRef dst = UintArrayRef(uvec2(pc.dstLo, pc.dstHi));
    uint t = gl_LocalInvocationID.x;
    const uint kPer = kScanBlock / kGridGroupSize;  // elements per thread
    uint first = gl_WorkGroupID.x * kScanBlock + t * kPer;
    uint v[kPer];
    uint total = 0u;
    bool texels = kSortedTexels && pc.tableLevel != 0u;  // the table: a whole number of blocks
    // The bucket counts are read once, here: each is zeroed for the next pass's count.
    if (texels) {
        for (uint q = 0u; q < kPer / 4u; ++q) {
            uvec4 c = imageLoad(countImage, int(first / 4u + q));
            imageStore(countImage, int(first / 4u + q), uvec4(0u));
            v[4u * q] = c.x, v[4u * q + 1u] = c.y, v[4u * q + 2u] = c.z, v[4u * q + 3u] = c.w;
        }
    } else {
        for (uint k = 0u; k < kPer; ++k) {
            v[k] = first + k < pc.count ? src.v[first + k] : 0u;
            if (pc.tableLevel != 0u && first + k < pc.count) src.v[first + k] = 0u;
        }
    }
    uint largestHere = 0u;
    for (uint k = 0u; k < kPer; ++k) total += v[k], largestHere = max(largestHere, v[k]);
    uint inclusive = subgroupInclusiveAdd(total);
    uint largest = subgroupMax(largestHere);
    if (gl_SubgroupInvocationID == gl_SubgroupSize - 1u) {
        subgroupTotals[gl_SubgroupID] = inclusive;
        subgroupMaxima[gl_SubgroupID] = largest;
    }
    barrier();
    // Exclusive prefix of this thread: within its subgroup, plus the totals of the subgroups before
    // it, which its lanes read a few each and add up together (a loop over all of them in every
    // thread read 15.5 of them on average, one lane at a time on lavapipe).
    uint before = 0u;
    for (uint k = gl_SubgroupInvocationID; k < gl_SubgroupID; k += gl_SubgroupSize) before += subgroupTotals[k];
    uint running = inclusive - total + subgroupAdd(before);
    if (texels) {
        for (uint q = 0u; q < kPer / 4u; ++q) {
            uvec4 starts = running + uvec4(0u, v[4u * q], v[4u * q] + v[4u * q + 1u], v[4u * q] + v[4u * q + 1u] + v[4u * q + 2u]);
            imageStore(startImage, int(first / 4u + q), starts);
            running += v[4u * q] + v[4u * q + 1u] + v[4u * q + 2u] + v[4u * q + 3u];
        }
    } else {
        for (uint k = 0u; k < kPer; ++k) {
            if (first + k < pc.count) dst.v[first + k] = running;
            running += v[k];
        }
    }
    if (t == kGridGroupSize - 1u && (pc.sumsLo != 0u || pc.sumsHi != 0u))
        UintArrayRef(uvec2(pc.sumsLo, pc.sumsHi)).v[gl_WorkGroupID.x] = running;  // the block total

    // ---- The fullest bucket: one atomic per workgroup ----
    if (pc.tableLevel == 0u || t != 0u) return;
    uint fullest = 0u;
    for (uint k = 0u; k < gl_NumSubgroups; ++k) fullest = max(fullest, subgroupMaxima[k]);
    atomicMax(PhotonMapRef(uvec2(pc.headerLo, pc.headerHi)).h.maxBucket, fullest);
}

// Test-only stage (tests/photon_grid_test.cpp): gathers at given points through the built grid.
void queryStage(PhotonMapRef map, uint id) {
    // Query i: src.v[2i] = (x, -), src.v[2i+1] = (n, -); out: (base.x, difference.x, found, 0),
    // added up over the slices (one query per thread: the host dispatches enough threads).
    Vec4ArrayRef src = Vec4ArrayRef(uvec2(pc.srcLo, pc.srcHi));
    Vec4ArrayRef dst = Vec4ArrayRef(uvec2(pc.dstLo, pc.dstHi));
    if (id < pc.count && kGatherCount > 0u) {
        // k nearest: per query (base.x, 0, found, 0) then the nearest photons so far
        // (nearestStore), rewritten by every slice; the last slice's sums are the answer.
        uint stride = 1u + (kGatherCount + 1u) / 2u;
        NearestStateRef state = NearestStateRef(uvec2(pc.dstLo, pc.dstHi));
        NearestPhotons nearest;
        if (pc.sliceBegin == 0u) nearestClear(nearest);
        else nearestLoad(state, id * stride + 1u, nearest);
        bool more;  // (unused, as below)
        nearestSearch(map, src.v[2u * id].xyz, pc.radius * pc.radius, pc.sliceBegin, nearest, more);
        nearestStore(state, id * stride + 1u, nearest);
        GatherSums s = nearestSums(map, nearest, src.v[2u * id + 1u].xyz, pc.radius * pc.radius,
                                   kKernel, 0xffffffffu);
        dst.v[id * stride] = vec4(s.base.x, 0.0, float(s.found), 0.0);
    } else if (id < pc.count) {
        bool more;  // (the host runs every slice of the queries: unused)
        GatherSums s = gatherPhotons(map, src.v[2u * id].xyz, src.v[2u * id + 1u].xyz, pc.radius * pc.radius, true,
                                     pc.logRadius2, pc.logStep2, kKernel, pc.sliceBegin, 0xffffffffu, more);
        vec4 sums = vec4(s.base.x, s.difference.x, float(s.found), 0.0);
        dst.v[id] = pc.sliceBegin == 0u ? sums : dst.v[id] + sums;
    }
}

void main() {
    PhotonMapRef map = PhotonMapRef(uvec2(pc.headerLo, pc.headerHi));
    uint stored = min(map.h.storedCount, map.h.capacity);
    PhotonArrayRef photons = PhotonArrayRef(uvec2(map.h.photonsLo, map.h.photonsHi));
    UintArrayRef cellCount = UintArrayRef(uvec2(map.h.cellCountLo, map.h.cellCountHi));
    UintArrayRef cellStart = UintArrayRef(uvec2(map.h.cellStartLo, map.h.cellStartHi));
    uint id = gl_GlobalInvocationID.x;

    if (kStage == kGridStageCount) {
        // The scatter computes the same bucket again from the position (cheaper than storing it).
        for (uint i = id; i < stored; i += threadCount()) {
            vec3 p = kSortedTexels ? uintBitsToFloat(texelFetch(photonTexels, int(2u * i)).xyz) : photons.p[i].position;
            atomicAdd(cellCount.v[gridHash(gridCell(p, map.h.cellSize), map.h.tableSize)], 1u);
        }
    } else if (kStage == kGridStageScan) {
        scanBlock();
    } else if (kStage == kGridStageAdd) {
        UintArrayRef dst = UintArrayRef(uvec2(pc.dstLo, pc.dstHi));
        UintArrayRef sums = UintArrayRef(uvec2(pc.sumsLo, pc.sumsHi));
        if (kSortedTexels && pc.tableLevel != 0u) {
            for (uint i = id; i < pc.count / 4u; i += threadCount())
                imageStore(startImage, int(i), imageLoad(startImage, int(i)) + sums.v[i / (kScanBlock / 4u)]);
        } else {
            for (uint i = id; i < pc.count; i += threadCount()) dst.v[i] += sums.v[i / kScanBlock];
        }
    } else if (kStage == kGridStageScatter) {
        PhotonArrayRef sorted = PhotonArrayRef(uvec2(map.h.sortedLo, map.h.sortedHi));
        // Under Tungsten's cap photon_trace divided the powers by the paths it might trace; the
        // copy in bucket order carries them per path traced (powerPaths 0: nothing to rescale).
        bool rescale = map.h.powerPaths != 0u && map.h.tracedPaths != 0u;
        float scale = rescale ? float(map.h.powerPaths) / float(map.h.tracedPaths) : 1.0;
        for (uint i = id; i < stored; i += threadCount()) {
            if (kSortedTexels) {
                uvec4 a = texelFetch(photonTexels, int(2u * i)), b = texelFetch(photonTexels, int(2u * i + 1u));
                uint h = gridHash(gridCell(uintBitsToFloat(a.xyz), map.h.cellSize), map.h.tableSize);
                int slot = int(atomicAdd(cellStart.v[h], 1u));
                if (rescale) b.xyz = floatBitsToUint(uintBitsToFloat(b.xyz) * scale);
                imageStore(sortedImage, 2 * slot, a);
                imageStore(sortedImage, 2 * slot + 1, b);
            } else {
                Photon ph = photons.p[i];
                if (rescale) ph.power *= scale;
                sorted.p[atomicAdd(cellStart.v[gridHash(gridCell(ph.position, map.h.cellSize), map.h.tableSize)], 1u)] = ph;
            }
        }
    } else if (kStage == kGridStageQuery) {
        queryStage(map, id);
    }
}
