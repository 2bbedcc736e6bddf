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

    vec3 sumZ = vec3(0.0), sumZ2 = vec3(0.0), sumBase = vec3(0.0), sumCorrection = vec3(0.0);
    vec3 sumCorrectionPos = vec3(0.0), sumCorrectionNeg = vec3(0.0);
    float dropped = 0.0;
    for (uint s = 0u; s < pc.sampleCount; ++s) {
        uint item = s * pixelCount + pixelIndex;
        vec4 base = results.v[2u * item], correction = results.v[2u * item + 1u];
        if (base.w != 0.0) {
            dropped += 1.0;
            continue;
        }
        vec3 z = base.rgb + correction.rgb;
        sumZ += z;
        sumZ2 += z * z;
        sumBase += base.rgb;
        sumCorrection += correction.rgb;
        sumCorrectionPos += max(correction.rgb, vec3(0.0));
        sumCorrectionNeg += min(correction.rgb, vec3(0.0));
    }
    AccumRef accum = AccumRef(uvec2(pc.accumAddressLo, pc.accumAddressHi));
    accumulateAdd(accum, kChannelEstimate, pixelIndex, pixelCount, vec4(sumZ, dropped));
    accumulateAdd(accum, kChannelEstimateSq, pixelIndex, pixelCount, vec4(sumZ2, 0.0));
    accumulateAdd(accum, kChannelBase, pixelIndex, pixelCount, vec4(sumBase, 0.0));
    accumulateAdd(accum, kChannelCorrection, pixelIndex, pixelCount, vec4(sumCorrection, 0.0));
    accumulateAdd(accum, kChannelCorrectionPositive, pixelIndex, pixelCount, vec4(sumCorrectionPos, 0.0));
    accumulateAdd(accum, kChannelCorrectionNegative, pixelIndex, pixelCount, vec4(sumCorrectionNeg, 0.0));
}
