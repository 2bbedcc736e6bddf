// view_display: one thread per window pixel maps a channel of the accumulated film to 8-bit
// colour for the viewer's swapchain (shared/view_types.h), and draws the legend strip.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/gpu_types.h"
#include "shared/view_types.h"

#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(local_size_x = kViewGroupSize, local_size_y = kViewGroupSize) in;

layout(buffer_reference, std430, buffer_reference_align = 16) readonly buffer AccumRef { vec4 v[]; };
layout(std430, binding = 0) writeonly buffer Pixels { uint pixels[]; };

layout(push_constant) uniform Push { ViewPush pc; };

// Mean of a channel: the compensated sum (hi + lo) over the sample count.
vec4 channelMean(AccumRef accum, uint channel, uint pixel) {
    uint pixelCount = pc.filmWidth * pc.filmHeight;
    uint i = (channel * pixelCount + pixel) * 2u;
    return (accum.v[i] + accum.v[i + 1u]) / float(pc.samples);
}

// The same encoding as the PNG preview (image_output.cpp): non-finite -> 0, clip, sRGB.
float srgbEncode(float linear) {
    float c = (isnan(linear) || isinf(linear)) ? 0.0 : clamp(linear, 0.0, 1.0);
    if ((pc.flags & kViewFlagEncodeSrgb) == 0u) return c;
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

// Linear colour -> the swapchain's byte order, alpha 255.
uint pack(vec3 linear) {
    uvec3 b = uvec3(floor(255.0 * vec3(srgbEncode(linear.x), srgbEncode(linear.y), srgbEncode(linear.z)) + 0.5));
    if ((pc.flags & kViewFlagBgra) != 0u) b = b.zyx;
    return b.x | (b.y << 8) | (b.z << 16) | (255u << 24);
}

// The colour of display value v (already multiplied by pc.scale) under the channel's map.
vec3 mapColour(vec3 v) {
    if (pc.map == kViewMapSigned) return viewSignedColour(viewLuminance(v));
    if (pc.map == kViewMapHeat) return viewHeatColour(viewLuminance(v));
    return v;
}

vec3 filmColour(uint pixel) {
    if (pc.samples == 0u) return vec3(0.0);
    AccumRef accum = AccumRef(uvec2(pc.accumLo, pc.accumHi));
    vec3 v;
    if (pc.channel == kViewEstimate) v = channelMean(accum, kChannelEstimate, pixel).rgb;
    else if (pc.channel == kViewBase) v = channelMean(accum, kChannelBase, pixel).rgb;
    else if (pc.channel == kViewCorrection) v = channelMean(accum, kChannelCorrection, pixel).rgb;
    else if (pc.channel == kViewCorrectionPositive) v = channelMean(accum, kChannelCorrectionPositive, pixel).rgb;
    else if (pc.channel == kViewCorrectionNegative) v = -channelMean(accum, kChannelCorrectionNegative, pixel).rgb;
    else {
        // Standard error of the mean: sqrt((S2 - S1^2 / n) / (n - 1) / n), 0 below 2 samples.
        float n = float(pc.samples);
        vec3 s1 = channelMean(accum, kChannelEstimate, pixel).rgb * n;
        vec3 s2 = channelMean(accum, kChannelEstimateSq, pixel).rgb * n;
        v = n < 2.0 ? vec3(0.0) : sqrt(max((s2 - s1 * s1 / n) / (n - 1.0), vec3(0.0)) / n);
    }
    return mapColour(v * pc.scale);
}

// Legend: the map's colours across the window width, for display values 0..1 (tone, heat) or
// -1..1 (signed); the window title gives the values they stand for.
vec3 legendColour(uint x, uint row) {
    if (row == 0u) return vec3(0.0);  // separator
    float u = (float(x) + 0.5) / float(pc.outWidth);
    if (pc.map == kViewMapSigned) return viewSignedColour(2.0 * u - 1.0);
    if (pc.map == kViewMapHeat) return viewHeatColour(u);
    return vec3(u);
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.outWidth || p.y >= pc.outHeight) return;
    uint legendTop = pc.outHeight > kViewLegendHeight ? pc.outHeight - kViewLegendHeight : 0u;
    vec3 colour = vec3(0.1);  // letterbox
    if (p.y >= legendTop) {
        colour = legendColour(p.x, p.y - legendTop);
    } else {
        // Nearest film pixel under the window pixel's centre.
        vec2 f = (vec2(ivec2(p) - ivec2(pc.imageX, pc.imageY)) + 0.5) * pc.pixelsPerWindowPixel;
        if (f.x >= 0.0 && f.y >= 0.0 && f.x < float(pc.filmWidth) && f.y < float(pc.filmHeight))
            colour = filmColour(uint(f.y) * pc.filmWidth + uint(f.x));
    }
    pixels[p.y * pc.outWidth + p.x] = pack(colour);
}
