// path_resolve: accumulates the per-item results of a queued path_trace dispatch into the film,
// sample by sample in index order, exactly as path_trace accumulates in the per-pixel schedule.
#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require

#include "shared/gpu_types.h"

layout(local_size_x = kPathTraceGroupSize, local_size_y = kPathTraceGroupSize) in;
layout(push_constant) uniform Push { PathTracePush pc; };

#include "shared/rng.h"
#include "shared/level_pmf.h"
#include "level_queue.glsl"
#include "accumulate.glsl"

void main() {
    uvec2 pixel = gl_GlobalInvocationID.xy;
    if (pixel.x >= pc.width || pixel.y >= pc.height) return;
    uint pixelIndex = pixel.y * pc.width + pixel.x;
    uint pixelCount = pc.width * pc.height;
    LevelResultsRef results = levelResults();

    SampleSums sums = sampleSumsZero();
    for (uint s = 0u; s < pc.sampleCount; ++s) {
        uint item = s * pixelCount + pixelIndex;
        vec4 base = results.v[2u * item], correction = results.v[2u * item + 1u];
        if (base.w != 0.0) sums.dropped += 1.0;  // non-finite (path_trace's queued lanes)
        else sampleSumsAdd(sums, base.rgb, correction.rgb);
    }
    accumulateSums(AccumRef(uvec2(pc.accumAddressLo, pc.accumAddressHi)), pixelIndex, pixelCount, sums);
}
