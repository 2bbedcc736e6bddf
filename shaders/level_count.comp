// level_count: per chunk of kLevelChunk items, the histogram of their levels.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/gpu_types.h"
#include "shared/rng.h"
#include "shared/level_pmf.h"

layout(local_size_x = kLevelQueueGroupSize) in;
layout(push_constant) uniform Push { PathTracePush pc; };

#include "level_queue.glsl"

void main() {
    uint pixelCount = pc.width * pc.height;
    uint total = pixelCount * pc.sampleCount;
    uint chunk = gl_GlobalInvocationID.x;
    if (chunk * kLevelChunk >= total) return;
    LevelQueueRef q = levelQueue();
    uint base = chunk * kLevelBuckets;
    for (uint b = 0u; b < kLevelBuckets; ++b) q.u[base + b] = 0u;
    LevelPmf pmf = LevelPmf(kPmfType, kPmfR, kPmfAlpha);
    uint end = min(total, (chunk + 1u) * kLevelChunk);
    for (uint item = chunk * kLevelChunk; item < end; ++item)
        q.u[base + levelBucket(drawLevel(item % pixelCount, item / pixelCount, pmf))] += 1u;
}
