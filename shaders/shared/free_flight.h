// Free-flight optical depths of the transmittance models (shared/transmittance.h), one source for
// GLSL and C++ (tests/unit/free_flight_test.cpp checks them against the forms).
//
// From a surface the free flight tau has the survival function T_ss = g; from a medium point
// T_ms = -g'/sigmaBar (Tungsten's Transmittance::sampleSurface / sampleMedium). For `linear` and
// `pulse` the flight from a medium point is discrete (Tungsten's mediumMedium is a Dirac at max_t,
// or a comb of n Diracs of mass 1/n at min + (i + 1/2)(max - min)/n): sampleDiracDepth draws it.
#ifndef TELESCOPE_FREE_FLIGHT_H
#define TELESCOPE_FREE_FLIGHT_H

#include "shared/transmittance.h"
#ifndef TR_FORM
#define TR_FORM trForm  // the includer may fold in the scene's model (shared/transmittance_estimators.h)
#endif
#ifndef TR_FORM3
#define TR_FORM3 trForm3
#endif
// The includer may also fold out sampleGuideDepth's code for models its scene lacks: TR_GUIDE_HAS(t)
// false (a constant) for a model type t no medium uses, TR_GUIDE_BISECTION false when every model
// present has a closed form there.
#ifndef TR_GUIDE_HAS
#define TR_GUIDE_HAS(t) true
#endif
#ifndef TR_GUIDE_BISECTION
#define TR_GUIDE_BISECTION true
#endif

SHADER_NAMESPACE_BEGIN

// True for the simple models whose flight from a medium point is a Dirac (comb).
FN bool trModelIsDirac(TrModel m) { return m.type == kTrLinear || m.type == kTrPulse; }

// The optical depth of a Dirac free flight from a medium point; u in [0, 1) picks the pulse.
FN float sampleDiracDepth(TrModel m, float u) {
    if (m.type == kTrLinear) return m.a.x;
    float n = m.a.z;
    return m.a.x + (0.5f + min(floor(u * n), n - 1.0f)) / n * (m.a.y - m.a.x);
}

// Draws the depth with survival function F = T_ss (from a surface) or T_ms (from a medium point).
// Closed forms where the inverse has one (exponential, Davis, linear, quadratic, pulse from a
// surface) and a pick of one
// exponential for double_exponential (both forms are mixtures of two exponentials: T_ss with
// weights 1/2, T_ms with a/(a+b), b/(a+b)); the others invert F by bisection (on a step of F, as
// the Dirac flights of linear and pulse, it returns the step). The bisection costs about 40
// evaluations of F per flight, which was most of the render time of the non-exponential scene.
FN float sampleGuideDepth(TrModel model, bool fromSurface, float u) {
    if (TR_GUIDE_HAS(kTrExponential)) {
        if (model.type == kTrExponential) return -log(1.0f - u);
    }
    if (TR_GUIDE_HAS(kTrDavis)) {
        if (model.type == kTrDavis) {
            float a = model.a.x;
            return a * (pow(1.0f - u, -1.0f / (fromSurface ? a : a + 1.0f)) - 1.0f);
        }
    }
    if (TR_GUIDE_HAS(kTrLinear)) {
        if (model.type == kTrLinear) return fromSurface ? model.a.x * u : model.a.x;  // F = 1 - tau/m; a step at m
    }
    if (TR_GUIDE_HAS(kTrQuadratic)) {
        if (model.type == kTrQuadratic) {  // F = (1 - tau/m)^2 from a surface, 1 - tau/m from a medium point
            float s = fromSurface ? sqrt(1.0f - u) : 1.0f - u;
            return model.a.x * (1.0f - s);
        }
    }
    if (TR_GUIDE_HAS(kTrPulse)) {
        if (model.type == kTrPulse && fromSurface) {
            // T_ss = 1 - (2/n) (I(x) - 1/2), I piecewise linear with I(i) = i - i (i - 1) / (2n) at the
            // integers (shared/transmittance.h, trPulseG): solve I(x) = 1/2 + n u / 2 on its piece.
            float n = model.a.z, target = 0.5f + 0.5f * n * u;
            float b2 = 2.0f * n + 1.0f;
            float i = clamp(floor(0.5f * (b2 - sqrt(max(b2 * b2 - 8.0f * n * target, 0.0f)))), 0.0f, n - 1.0f);
            float x = i + (target - (i - i * (i - 1.0f) / (2.0f * n))) / (1.0f - i / n);
            return max(model.a.x + (x - 0.5f) * (model.a.y - model.a.x) / n, 0.0f);
        }
    }
    if (TR_GUIDE_HAS(kTrDoubleExponential)) {
        if (model.type == kTrDoubleExponential) {
            float a = model.a.x, b = model.a.y;
            float wa = fromSurface ? 0.5f : a / (a + b);
            if (u < wa) return -log(1.0f - u / wa) / a;
            return -log(1.0f - (u - wa) / (1.0f - wa)) / b;
        }
    }
    if (!TR_GUIDE_BISECTION) return 0.0f;  // no model of the includer's scene comes here
    uint form = fromSurface ? kFormSurfaceSurface : kFormSurfaceMedium;
    float target = 1.0f - u;
    float lo = 0.0f, hi = 1.0f;
    LOOP_BUDGET_TICK(96u);  // the two loops below
    for (uint i = 0u; i < 64u && TR_FORM(model, form, hi) > target; ++i) hi *= 2.0f;
    for (uint i = 0u; i < 32u; ++i) {
        float mid = 0.5f * (lo + hi);
        if (TR_FORM(model, form, mid) > target) lo = mid;
        else hi = mid;
    }
    return 0.5f * (lo + hi);
}

// One free flight of length-l segment from a medium point of a homogeneous medium whose model is
// a Dirac flight (trModelIsDirac), as Tungsten's HomogeneousMedium::sampleDistance: a colour
// channel c is picked uniformly (uc), the flight ends at t = depth / sigma_t,c (ud picks the
// depth). The channels whose optical depth at t hits the same Dirac share the sample, so the
// weight of scattering at t (returns true) is sigma_s m / mean(sigma_t m), m the mask of those
// channels (the Dirac masses cancel); of passing to the surface at l (returns false)
// T_ms(tau) / mean(T_ms(tau)), T_ms the probability of no Dirac before tau. A zero weight means
// no channel can take the sample.
FN bool sampleDiracFlight(TrModel model, vec3 sigmaT, vec3 sigmaS, float l, float uc, float ud, INOUT(float) t,
                          INOUT(vec3) weight) {
    uint c = min(uint(uc * 3.0f), 2u);
    float depth = sampleDiracDepth(model, ud);
    float sc = c == 0u ? sigmaT.x : (c == 1u ? sigmaT.y : sigmaT.z);
    t = l;
    if (sc > 0.0f && depth < sc * l) {
        t = depth / sc;
        vec3 tau = sigmaT * t;
        // the channels at the same Dirac (Tungsten's tolerance, 1e-3 in optical depth)
        vec3 m = vec3(lessThan(abs(tau - vec3(depth)), vec3(1e-3f * max(depth, 1.0f))));
        float pdf = (sigmaT.x * m.x + sigmaT.y * m.y + sigmaT.z * m.z) / 3.0f;
        weight = pdf > 0.0f ? sigmaS * m / pdf : vec3(0.0f);
        return true;
    }
    vec3 pass = TR_FORM3(model, kFormSurfaceMedium, sigmaT * l);
    float pdf = (pass.x + pass.y + pass.z) / 3.0f;
    weight = pdf > 0.0f ? pass / pdf : vec3(0.0f);
    return false;
}

SHADER_NAMESPACE_END

#endif
