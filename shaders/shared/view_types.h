// The viewer's display pass (shaders/view_display.comp), shared by the host and the shader: the
// channels it shows, how each is mapped to colour, and its push constants.
//
// The pass reads the accumulation buffer of the Renderer (by device address, the layout of
// gpu_types.h: a (hi, lo) vec4 pair per channel and pixel) and writes one packed 8-bit pixel per
// window pixel into a buffer that is copied into the swapchain image. The film is scaled to fit
// the window above a legend strip of kViewLegendHeight rows.
#ifndef TELESCOPE_VIEW_TYPES_H
#define TELESCOPE_VIEW_TYPES_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

// ---- Channels shown (keys 1..6) ----
CONST uint kViewEstimate = 0u;            // the estimate Z, tone-mapped like the PNG preview
CONST uint kViewBase = 1u;                // the biased base I(k), tone-mapped
CONST uint kViewCorrection = 2u;          // Z - I(k), signed: false colour (red +, blue -)
CONST uint kViewCorrectionPositive = 3u;  // mean of max(correction, 0), tone-mapped
CONST uint kViewCorrectionNegative = 4u;  // -(mean of min(correction, 0)), tone-mapped
CONST uint kViewStandardError = 5u;       // per-pixel standard error of the estimate: heat map
CONST uint kViewChannelCount = 6u;

// How a channel is mapped to colour.
CONST uint kViewMapTone = 0u;     // rgb x scale, clipped to [0, 1], sRGB encoded
CONST uint kViewMapSigned = 1u;   // luminance x scale in [-1, 1]: blue .. black .. red
CONST uint kViewMapHeat = 2u;     // luminance x scale in [0, 1]: black .. red .. yellow .. white

CONST uint kViewLegendHeight = 12u;  // rows under the image: the colour scale of the channel
CONST uint kViewGroupSize = 8u;      // 8x8 window pixels per workgroup

CONST uint kViewFlagEncodeSrgb = 1u;  // the swapchain is UNORM: encode sRGB in the shader
CONST uint kViewFlagBgra = 2u;        // the swapchain stores B, G, R, A (else R, G, B, A)

struct ViewPush {
    uint accumLo; uint accumHi;   // device address of the Renderer's accumulation buffer
    uint filmWidth; uint filmHeight;
    uint outWidth; uint outHeight;  // the window (swapchain image) in pixels
    int imageX; int imageY;         // window position of the film's top-left corner
    float pixelsPerWindowPixel;     // film pixels per window pixel (the image is scaled to fit)
    uint samples;                   // samples per pixel in the film (0: nothing rendered yet)
    uint channel;                   // kView*
    uint map;                       // kViewMap*
    float scale;                    // display multiplier: 2^EV (tone) or 1 / full-scale value (false colour)
    uint flags;                     // kViewFlag*
    uint pad0; uint pad1;
};

// Rec. 709 luminance, for the false-colour channels.
FN float viewLuminance(vec3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

// Diverging false colour for t in [-1, 1]: black at 0, red for positive, blue for negative;
// brightness grows linearly with |t| (before the sRGB encoding of the display).
FN vec3 viewSignedColour(float t) {
    float a = min(abs(t), 1.0f);
    return t >= 0.0f ? vec3(a, 0.25f * a * a, 0.05f * a) : vec3(0.05f * a, 0.3f * a * a, a);
}

// Sequential heat map for t in [0, 1]: black, red, yellow, white.
FN vec3 viewHeatColour(float t) {
    float a = clamp(t, 0.0f, 1.0f);
    return vec3(clamp(3.0f * a, 0.0f, 1.0f), clamp(3.0f * a - 1.0f, 0.0f, 1.0f), clamp(3.0f * a - 2.0f, 0.0f, 1.0f));
}

SHADER_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(telescope::shader::ViewPush) == 64);
#endif

#endif
