// Phase functions of participating media (Henyey-Greenstein; g = 0 is isotropic), shared by the
// path tracer (medium.glsl) and the CPU tests (tests/unit/phase_test.cpp).
#ifndef TELESCOPE_PHASE_H
#define TELESCOPE_PHASE_H

#include "shared/lang.h"
#include "shared/sampling.h"

SHADER_NAMESPACE_BEGIN

// cosTheta between the propagation direction before and after scattering: g > 0 scatters
// forward, and the mean cosine is g.
FN float phaseHG(float cosTheta, float g) {
    float denom = 1.0f + g * g - 2.0f * g * cosTheta;
    return (1.0f - g * g) / (4.0f * kPi * denom * sqrt(denom));
}

// A direction with density phaseHG(dot(dir, result), g), from two uniform numbers (inverting
// the cumulative distribution of cosTheta; uniform for |g| < 1e-3, where the inversion cancels).
FN vec3 samplePhaseHG(vec3 dir, float g, float u1, float u2) {
    float cosTheta;
    if (abs(g) < 1e-3f) {
        cosTheta = 1.0f - 2.0f * u1;
    } else {
        float s = (1.0f - g * g) / (1.0f - g + 2.0f * g * u1);
        cosTheta = clamp((1.0f + g * g - s * s) / (2.0f * g), -1.0f, 1.0f);
    }
    float sinTheta = sqrt(max(0.0f, 1.0f - cosTheta * cosTheta));
    float phi = 2.0f * kPi * u2;
    vec3 t, b;
    buildFrame(dir, t, b);
    return normalize(t * (sinTheta * cos(phi)) + b * (sinTheta * sin(phi)) + dir * cosTheta);
}

SHADER_NAMESPACE_END

#endif
