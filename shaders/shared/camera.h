// The pinhole camera of every camera pass (path_trace, gather), after Tungsten's: pixel (0, 0) is
// the top-left one, the field of view is horizontal and the image plane sits at planeDistance
// along the forward axis. One source for GLSL and C++ (tests/unit/camera_test.cpp).
#ifndef TELESCOPE_CAMERA_H
#define TELESCOPE_CAMERA_H

#include "shared/pixel_filter.h"

SHADER_NAMESPACE_BEGIN

// Distance of the image plane for a horizontal field of view (the plane spans x in [-1, 1]).
FN float cameraPlaneDistance(float fovDegrees) { return 1.0f / tan(0.5f * radians(fovDegrees)); }

// Unit direction through film point `film` (pixels, x right, y down, (0, 0) the top-left corner).
FN vec3 cameraRayDirection(vec2 film, uint width, uint height, float planeDistance, vec3 right, vec3 up,
                           vec3 forward) {
    float w = float(width);
    vec3 local = vec3(-1.0f + 2.0f * film.x / w, float(height) / w - 2.0f * film.y / w, planeDistance);
    return normalize(right * local.x + up * local.y + forward * local.z);
}

// Film point of a sample of `pixel` drawn from two uniforms by the reconstruction filter, and the
// sample's filter weight (1 for dirac, box and tent, which are sampled exactly; shared/pixel_filter.h
// for the wide ones).
FN vec2 cameraFilmPoint(uint filterType, uvec2 pixel, vec2 u, OUT(float) weight) {
    weight = 1.0f;
    vec2 offset = u;  // box
    if (filterType == kFilterTent) offset = vec2(sampleTent(u.x), sampleTent(u.y)) + 0.5f;
    else if (filterType == kFilterDirac) offset = vec2(0.5f);
    else if (isWideFilter(filterType)) {
        float wx, wy;
        offset = vec2(sampleWideFilter(filterType, u.x, wx), sampleWideFilter(filterType, u.y, wy)) + 0.5f;
        weight = wx * wy;
    }
    return vec2(pixel) + offset;
}

SHADER_NAMESPACE_END

#endif
