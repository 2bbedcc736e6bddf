// The wide reconstruction filters: gaussian, mitchell_netravali, catmull_rom and lanczos, with
// Tungsten's names and its radius of 2 pixels (box has radius 1/2, tent 1: shared/sampling.h).
//
// A pixel's value is the filtered image at its centre, I = int f(x) f(y) L(x, y) / F^2, with the
// separable profile f on [-2, 2] and F = int f. Each sample draws its offset from the pixel
// centre per axis from the tent q(x) = (2 - |x|) / 4 on [-2, 2] and carries the weight
// w(x) = f(x) / (F q(x)), so E[w(x) w(y) L] = I for any L: unbiased, also for the profiles with
// negative lobes (their weights are negative there and are never clamped). Every profile falls
// to 0 at |x| = 2 at least as fast as q, so the weights are bounded (docs/ESTIMATORS.md).
#ifndef TELESCOPE_PIXEL_FILTER_H
#define TELESCOPE_PIXEL_FILTER_H

#include "shared/enums.h"
#include "shared/sampling.h"

SHADER_NAMESPACE_BEGIN

CONST float kWideFilterRadius = 2.0f;

FN bool isWideFilter(uint type) { return type >= kFilterGaussian && type <= kFilterLanczos; }

// The unnormalised profile f(x), 0 outside (-2, 2).
//   gaussian:            exp(-2 x^2) - exp(-8)   (standard deviation 1/2, shifted to 0 at the edge)
//   mitchell_netravali:  the cubic of Mitchell and Netravali 1988 with B = C = 1/3
//   catmull_rom:         the same family with B = 0, C = 1/2
//   lanczos:             sinc(x) sinc(x / 2), sinc(t) = sin(pi t) / (pi t)
FN float filterProfile(uint type, float x) {
    float a = abs(x);
    if (a >= kWideFilterRadius) return 0.0f;
    if (type == kFilterGaussian) return exp(-2.0f * a * a) - exp(-8.0f);
    if (type == kFilterLanczos) {
        if (a < 1e-4f) return 1.0f;
        float p = kPi * a;
        return 2.0f * sin(p) * sin(0.5f * p) / (p * p);
    }
    float b = type == kFilterCatmullRom ? 0.0f : 1.0f / 3.0f;
    float c = type == kFilterCatmullRom ? 0.5f : 1.0f / 3.0f;
    if (a < 1.0f)
        return ((12.0f - 9.0f * b - 6.0f * c) * a * a * a + (-18.0f + 12.0f * b + 6.0f * c) * a * a + (6.0f - 2.0f * b)) /
               6.0f;
    return ((-b - 6.0f * c) * a * a * a + (6.0f * b + 30.0f * c) * a * a + (-12.0f * b - 48.0f * c) * a +
            (8.0f * b + 24.0f * c)) / 6.0f;
}

// F = int_{-2}^{2} f(x) dx. Gaussian: sqrt(pi/2) erf(2 sqrt 2) - 4 exp(-8); lanczos by quadrature;
// the cubics integrate to 1 for every B, C. tests/unit/pixel_filter_test.cpp checks all four.
FN float filterProfileIntegral(uint type) {
    if (type == kFilterGaussian) return 1.25189290f;
    if (type == kFilterLanczos) return 1.00978984f;
    return 1.0f;
}

// Offset from the pixel centre along one axis (pixels) for u uniform in [0, 1), and its weight.
FN float sampleWideFilter(uint type, float u, OUT(float) weight) {
    float x = kWideFilterRadius * sampleTent(u);
    float q = 0.25f * (kWideFilterRadius - abs(x));
    weight = q > 0.0f ? filterProfile(type, x) / (filterProfileIntegral(type) * q) : 0.0f;
    return x;
}

SHADER_NAMESPACE_END

#endif
