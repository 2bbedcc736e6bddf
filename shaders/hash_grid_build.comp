// hash_grid_build: the photon hash grid on the device, one stage per pipeline (kSpecGridStage):
// clear the per-bucket counts, count photons per bucket, exclusive prefix sum of the counts
// (1024-element blocks, block totals scanned recursively, then added back), and scatter copies of
// the photons into bucket order (so that a gather reads each bucket contiguously). After the scatter cellStart[h] holds the END of bucket h's range,
// which starts at cellStart[h] - cellCount[h]. The query stage evaluates gatherPhotons() at
// given points (tests). Loops are grid-stride: the host dispatches for the capacity.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "shared/gpu_types.h"
#include "shared/photon_density.h"

layout(local_size_x = kGridGroupSize) in;
layout(constant_id = kSpecGridStage) const uint kStage = kGridStageClear;
layout(constant_id = kSpecPhotonKernel) const uint kKernel = kKernelCone;
layout(push_constant) uniform Push { HashGridPush pc; };

layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonMapRef { PhotonMapHeader h; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonArrayRef { Photon p[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintArrayRef { uint v[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer Vec4ArrayRef { vec4 v[]; };

#include "photon_gather.glsl"

shared uint threadTotals[kGridGroupSize];

uint threadCount() { return gl_NumWorkGroups.x * kGridGroupSize; }

// Exclusive scan of one block of kScanBlock elements: 4 per thread, then the thread totals in
// shared memory (Hillis-Steele), then the block total to sums[block].
void scanBlock() {
    UintArrayRef src = UintArrayRef(uvec2(pc.srcLo, pc.srcHi));
    UintArrayRef dst = UintArrayRef(uvec2(pc.dstLo, pc.dstHi));
    uint t = gl_LocalInvocationID.x;
    uint first = gl_WorkGroupID.x * kScanBlock + t * 4u;
    uint v[4];
    uint total = 0u;
    for (uint k = 0u; k < 4u; ++k) {
        v[k] = first + k < pc.count ? src.v[first + k] : 0u;
        total += v[k];
    }
    threadTotals[t] = total;
    barrier();
    for (uint offset = 1u; offset < kGridGroupSize; offset <<= 1u) {
        uint add = t >= offset ? threadTotals[t - offset] : 0u;
        barrier();
        threadTotals[t] += add;
        barrier();
    }
    uint running = threadTotals[t] - total;  // exclusive prefix of this thread
    for (uint k = 0u; k < 4u; ++k) {
        if (first + k < pc.count) dst.v[first + k] = running;
        running += v[k];
    }
    if (t == kGridGroupSize - 1u && (pc.sumsLo != 0u || pc.sumsHi != 0u))
        UintArrayRef(uvec2(pc.sumsLo, pc.sumsHi)).v[gl_WorkGroupID.x] = threadTotals[t];
}

void main() {
    PhotonMapRef map = PhotonMapRef(uvec2(pc.headerLo, pc.headerHi));
    uint stored = min(map.h.storedCount, map.h.capacity);
    PhotonArrayRef photons = PhotonArrayRef(uvec2(map.h.photonsLo, map.h.photonsHi));
    UintArrayRef cellCount = UintArrayRef(uvec2(map.h.cellCountLo, map.h.cellCountHi));
    UintArrayRef cellStart = UintArrayRef(uvec2(map.h.cellStartLo, map.h.cellStartHi));
    uint id = gl_GlobalInvocationID.x;

    if (kStage == kGridStageClear) {
        for (uint i = id; i < map.h.tableSize; i += threadCount()) cellCount.v[i] = 0u;
    } else if (kStage == kGridStageCount) {
        for (uint i = id; i < stored; i += threadCount()) {
            uint h = gridHash(gridCell(photons.p[i].position, map.h.cellSize), map.h.tableSize);
            photons.p[i].cell = h;
            atomicAdd(cellCount.v[h], 1u);
        }
    } else if (kStage == kGridStageScan) {
        scanBlock();
    } else if (kStage == kGridStageAdd) {
        UintArrayRef dst = UintArrayRef(uvec2(pc.dstLo, pc.dstHi));
        UintArrayRef sums = UintArrayRef(uvec2(pc.sumsLo, pc.sumsHi));
        for (uint i = id; i < pc.count; i += threadCount()) dst.v[i] += sums.v[i / kScanBlock];
    } else if (kStage == kGridStageScatter) {
        PhotonArrayRef sorted = PhotonArrayRef(uvec2(map.h.sortedLo, map.h.sortedHi));
        for (uint i = id; i < stored; i += threadCount()) {
            Photon ph = photons.p[i];
            sorted.p[atomicAdd(cellStart.v[ph.cell], 1u)] = ph;
        }
    } else if (kStage == kGridStageQuery) {
        // Query i: src.v[2i] = (x, -), src.v[2i+1] = (n, -); out: (base.x, difference.x, found, 0)
        Vec4ArrayRef src = Vec4ArrayRef(uvec2(pc.srcLo, pc.srcHi));
        Vec4ArrayRef dst = Vec4ArrayRef(uvec2(pc.dstLo, pc.dstHi));
        for (uint i = id; i < pc.count; i += threadCount()) {
            GatherSums s = gatherPhotons(map, src.v[2u * i].xyz, src.v[2u * i + 1u].xyz, pc.radius * pc.radius, true,
                                         pc.logRadius2, pc.logStep2, kKernel);
            dst.v[i] = vec4(s.base.x, s.difference.x, float(s.found), 0.0);
        }
    }
}
