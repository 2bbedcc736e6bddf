// Compensated accumulation of per-pixel sums into the film (GLSL only; the arithmetic is
// shared/sample_sums.h).
//
// Each channel of each pixel keeps a float pair (hi, lo) updated with TwoSum. The buffer is
// reached by device address, so it may exceed the storage-buffer binding limit.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#include "shared/sample_sums.h"

layout(buffer_reference, std430, buffer_reference_align = 16) buffer AccumRef { vec4 v[]; };

// Adds value to the (hi, lo) pair at v[i], v[i + 1] of any vec4 buffer.
void addCompensated(AccumRef b, uint i, vec4 value) {
    vec4 error;
    b.v[i] = twoSum(b.v[i], value, error);
    b.v[i + 1u] += error;
}

void accumulateAdd(AccumRef accum, uint channel, uint pixel, uint pixelCount, vec4 value) {
    addCompensated(accum, (channel * pixelCount + pixel) * 2u, value);
}

// The six channels of one pixel's sums.
void accumulateSums(AccumRef accum, uint pixel, uint pixelCount, SampleSums s) {
    accumulateAdd(accum, kChannelEstimate, pixel, pixelCount, vec4(s.z, s.dropped));
    accumulateAdd(accum, kChannelEstimateSq, pixel, pixelCount, vec4(s.z2, s.count));
    accumulateAdd(accum, kChannelBase, pixel, pixelCount, vec4(s.base, 0.0));
    accumulateAdd(accum, kChannelCorrection, pixel, pixelCount, vec4(s.correction, 0.0));
    accumulateAdd(accum, kChannelCorrectionPositive, pixel, pixelCount, vec4(s.correctionPos, 0.0));
    accumulateAdd(accum, kChannelCorrectionNegative, pixel, pixelCount, vec4(s.correctionNeg, 0.0));
}
