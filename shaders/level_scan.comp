// level_scan: turns the per-chunk level counts into queue slot offsets, bucket-major (all of
// level 0 first, chunk by chunk, then level 1, ...): one exclusive prefix sum, in one lane.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/level_pmf.h"

layout(local_size_x = 1) in;
layout(push_constant) uniform Push { PathTracePush pc; };

#include "level_queue.glsl"

void main() {
    uint total = pc.width * pc.height * pc.sampleCount;
    uint chunks = (total + kLevelChunk - 1u) / kLevelChunk;
    LevelQueueRef q = levelQueue();
    uint offset = 0u;
    for (uint b = 0u; b < kLevelBuckets; ++b) {
        for (uint c = 0u; c < chunks; ++c) {
            uint count = q.u[c * kLevelBuckets + b];
            q.u[c * kLevelBuckets + b] = offset;
            offset += count;
        }
    }
}
