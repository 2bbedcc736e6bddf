// One-dimensional density profiles along a ray segment, t in [0, length]: the closed-form media
// of the renderer (homogeneous = constant, Tungsten's exponential medium = exponential falloff
// along the ray) and the 1-D problems of `telescope study transmittance` (constant, sine,
// Gaussian). One source for GLSL and C++; the exact optical depths (integrals) are C++ only.
#ifndef TELESCOPE_DENSITY_PROFILES_H
#define TELESCOPE_DENSITY_PROFILES_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

CONST uint kProfileConstant = 0u;     // d = a
CONST uint kProfileLinear = 1u;       // d = a + b t
CONST uint kProfileExponential = 2u;  // d = a exp(-b t)
CONST uint kProfileSine = 3u;         // d = a (1 + b sin(2 pi c t)), |b| <= 1
CONST uint kProfileGaussian = 4u;     // d = a exp(-((t - b) / c)^2 / 2)
CONST uint kProfileGrid = 5u;         // a voxel grid: looked up by the includer (medium.glsl)

struct DensityProfile {
    uint type;
    float a; float b; float c;
};

FN DensityProfile makeProfile(uint type, float a, float b, float c) {
    DensityProfile p;
    p.type = type; p.a = a; p.b = b; p.c = c;
    return p;
}

// Density at t (not for grids).
FN float profileDensity(DensityProfile p, float t) {
    if (p.type == kProfileLinear) return p.a + p.b * t;
    if (p.type == kProfileExponential) return p.a * exp(-p.b * t);
    if (p.type == kProfileSine) return p.a * (1.0f + p.b * sin(2.0f * kPi * p.c * t));
    if (p.type == kProfileGaussian) {
        float x = (t - p.b) / p.c;
        return p.a * exp(-0.5f * x * x);
    }
    return p.a;
}

// Lower and upper bound of the density over [t0, t1] (the majorant and minorant of the trackers).
FN vec2 profileBounds(DensityProfile p, float t0, float t1) {
    if (p.type == kProfileLinear || p.type == kProfileExponential) {
        float d0 = profileDensity(p, t0), d1 = profileDensity(p, t1);
        return vec2(min(d0, d1), max(d0, d1));
    }
    if (p.type == kProfileSine) return vec2(p.a * (1.0f - abs(p.b)), p.a * (1.0f + abs(p.b)));
    if (p.type == kProfileGaussian) {
        float d0 = profileDensity(p, t0), d1 = profileDensity(p, t1);
        float hi = (p.b >= t0 && p.b <= t1) ? p.a : max(d0, d1);
        return vec2(min(d0, d1), hi);
    }
    return vec2(p.a, p.a);
}

SHADER_NAMESPACE_END

#ifdef __cplusplus
namespace telescope::shader {
// Exact integral of the density over [t0, t1] (the optical depth per unit sigma_t).
inline double profileIntegral(const DensityProfile& p, double t0, double t1) {
    const double a = p.a, b = p.b, c = p.c;
    switch (p.type) {
        case kProfileLinear: return a * (t1 - t0) + 0.5 * b * (t1 * t1 - t0 * t0);
        case kProfileExponential:
            if (std::abs(b) < 1e-12) return a * (t1 - t0);
            return a * (std::exp(-b * t0) - std::exp(-b * t1)) / b;
        case kProfileSine: {
            const double w = 2.0 * 3.14159265358979323846 * c;
            return a * ((t1 - t0) - b / w * (std::cos(w * t1) - std::cos(w * t0)));
        }
        case kProfileGaussian: {
            const double s = c * std::sqrt(2.0);
            return a * c * std::sqrt(3.14159265358979323846 / 2.0) * (std::erf((t1 - b) / s) - std::erf((t0 - b) / s));
        }
        default: return a * (t1 - t0);
    }
}
}  // namespace telescope::shader
#endif

#endif
