// Compensated accumulation of per-pixel sums (GLSL only).
//
// Each channel of each pixel keeps a float pair (hi, lo) updated with Knuth's TwoSum, so sums
// of 10^6 and more samples keep ~40 significant bits. `precise` forbids the compiler from
// reassociating the error terms away. The buffer is reached by device address, so it may exceed
// the storage-buffer binding limit.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(buffer_reference, std430, buffer_reference_align = 16) buffer AccumRef { vec4 v[]; };

void accumulateAdd(AccumRef accum, uint channel, uint pixel, uint pixelCount, vec4 value) {
    uint i = (channel * pixelCount + pixel) * 2u;
    vec4 hi = accum.v[i];
    precise vec4 s = hi + value;
    precise vec4 bp = s - hi;
    precise vec4 err = (hi - (s - bp)) + (value - bp);
    accum.v[i] = s;
    accum.v[i + 1u] += err;
}
