// Transmittance models of participating media (Tungsten's set, Bitterli et al. 2018,
// "A radiative transfer framework for non-exponential media"), one source for GLSL and C++.
//
// Every model is a function of the optical depth tau = integral sigma_t(x) dx through
//   g(tau)   = T_ss, surface to surface (the survival function of the free flight),
//   sigmaBar = -g'(0),
//   T_ms(tau) = T_sm(tau) = -g'(tau) / sigmaBar          (Tungsten's mediumSurface),
//   mediumMedium(tau)     = g''(tau) / sigmaBar,
// and a segment between path vertices is weighted (Tungsten's Transmittance::eval) by
//   surface-surface  g,   surface-medium and medium-surface  T_sm,   medium-medium  mediumMedium / sigmaBar.
// A scattering vertex in the medium is weighted by sigma_s * sigmaBar, so that the collision
// density from a surface is sigma_t (-g') and from a medium point sigma_t g'' / sigmaBar; both
// integrate with the passing probability to one (checked in tests/unit/transmittance_test.cpp).
// For the exponential model every form is exp(-tau) and sigmaBar = 1.
#ifndef TELESCOPE_TRANSMITTANCE_H
#define TELESCOPE_TRANSMITTANCE_H

#include "shared/enums.h"
#include "shared/level_pmf.h"  // log1pSafe

SHADER_NAMESPACE_BEGIN

// Model types: kTr* (shared/enums.h).

// ---- Segment forms by endpoint type ----
CONST uint kFormSurfaceSurface = 0u;
CONST uint kFormSurfaceMedium = 1u;  // also medium-surface
CONST uint kFormMediumMedium = 2u;

// A model as the shaders see it. Simple models: type == typeA and their parameters in a.
// Interpolated: typeA / a and typeB / b are the two simple models, mixed by ratio.
struct TrModel {
    uint type; uint typeA; uint typeB; float ratio;
    vec4 a;
    vec4 b;
};

FN TrModel trSimple(uint type, vec4 params) {
    TrModel m;
    m.type = type; m.typeA = type; m.typeB = type; m.ratio = 0.0f;
    m.a = params; m.b = params;
    return m;
}

// ---- Simple models: g, -g'/sigmaBar (ms), g''/sigmaBar (mm), sigmaBar ----

FN float trSimpleSigmaBar(uint type, vec4 p) {
    if (type == kTrLinear) return 1.0f / p.x;
    if (type == kTrQuadratic) return 2.0f / p.x;
    if (type == kTrDoubleExponential) return 0.5f * (p.x + p.y);
    if (type == kTrErlang) return 0.5f * p.x;
    if (type == kTrPulse) return 2.0f / (p.y - p.x);
    return 1.0f;  // exponential, davis, davis_weinstein
}

// Davis-Weinstein: alpha(tau) = tau^(1-beta) / c^(1+beta), beta = 2h - 1, g = (1 + tau/alpha)^-alpha.
// With u = tau/alpha:  g'/g = -h(tau),  h = beta/(1+u) + (1-beta) (alpha/tau) ln(1+u),
//                      g''/g = h^2 - h',  h' = -beta^2 u/(tau (1+u)^2) + (1-beta) beta (1/(tau(1+u)) - (alpha/tau^2) ln(1+u)).
FN vec3 trDavisWeinsteinTerms(float tau, vec4 p) {
    float t = max(tau, 1e-7f);
    float beta = 2.0f * p.x - 1.0f;
    float alpha = pow(t, 1.0f - beta) / pow(p.y, 1.0f + beta);
    float u = t / alpha;
    float l = log(1.0f + u);
    float g = exp(-alpha * l);
    float h = beta / (1.0f + u) + (1.0f - beta) * (alpha / t) * l;
    float hp = -beta * beta * u / (t * (1.0f + u) * (1.0f + u)) +
               (1.0f - beta) * beta * (1.0f / (t * (1.0f + u)) - (alpha / (t * t)) * l);
    return vec3(g, g * h, g * (h * h - hp));  // g, -g', g''
}

// Pulse: x = clamp(n (tau - min)/(max - min) + 1/2, 0, n); -g'/sigmaBar = 1 - floor(x)/n and
// g = 1 - (2/n) (integral_0^x (1 - floor(s)/n) ds - 1/2); medium-medium is a Dirac comb (0 here).
FN float trPulseG(float tau, vec4 p) {
    float n = p.z;
    float x = clamp(n * (tau - p.x) / (p.y - p.x) + 0.5f, 0.0f, n);
    float i = floor(x);
    float integral = i - i * (i - 1.0f) / (2.0f * n) + (x - i) * (1.0f - i / n);
    return 1.0f - (2.0f / n) * (integral - 0.5f);
}

// One function per simple model (tau >= 0), so that a shader can call the one its scene uses
// (medium.glsl mediumForm); trSimpleForm dispatches on the type.
FN float trLinearForm(vec4 p, uint form, float tau) {
    float m = p.x;
    if (form == kFormSurfaceSurface) return max(1.0f - tau / m, 0.0f);
    if (form == kFormSurfaceMedium) return tau < m ? 1.0f : 0.0f;
    return 0.0f;  // Dirac at tau = max_t
}

FN float trQuadraticForm(vec4 p, uint form, float tau) {
    float sb = trSimpleSigmaBar(kTrQuadratic, p);
    float m = p.x;
    float s = max(1.0f - tau / m, 0.0f);
    if (form == kFormSurfaceSurface) return s * s;
    if (form == kFormSurfaceMedium) return s;
    return tau < m ? (2.0f / (m * m)) / (sb * sb) : 0.0f;
}

FN float trDoubleExponentialForm(vec4 p, uint form, float tau) {
    float sb = trSimpleSigmaBar(kTrDoubleExponential, p);
    float ea = exp(-p.x * tau), eb = exp(-p.y * tau);
    if (form == kFormSurfaceSurface) return 0.5f * (ea + eb);
    if (form == kFormSurfaceMedium) return 0.5f * (p.x * ea + p.y * eb) / sb;
    return 0.5f * (p.x * p.x * ea + p.y * p.y * eb) / (sb * sb);
}

FN float trErlangForm(vec4 p, uint form, float tau) {
    float sb = trSimpleSigmaBar(kTrErlang, p);
    float lt = p.x * tau;
    float e = exp(-lt);
    if (form == kFormSurfaceSurface) return e * (1.0f + 0.5f * lt);
    if (form == kFormSurfaceMedium) return e * (1.0f + lt);
    return p.x * p.x * tau * e / sb;
}

// (1 + tau/a)^-e as exp(-e log1p(tau/a)): pow(1 + tau/a, -a) rounds 1 + tau/a to float first,
// and for large a (the exponential limit) an error of an ulp there is multiplied by a. On
// lavapipe the exact pow hid it; an NVIDIA H200's pow was 3460 standard errors off at
// a = 1e6 (Stability.DavisNearItsLimits, first GPU run).
FN float trDavisForm(vec4 p, uint form, float tau) {
    float a = p.x;
    float lb = log1pSafe(tau / a);
    if (form == kFormSurfaceSurface) return exp(-a * lb);
    if (form == kFormSurfaceMedium) return exp(-(a + 1.0f) * lb);
    return (1.0f + 1.0f / a) * exp(-(a + 2.0f) * lb);
}

FN float trDavisWeinsteinForm(vec4 p, uint form, float tau) {
    if (tau <= 0.0f) return form == kFormMediumMedium ? 0.0f : 1.0f;
    vec3 d = trDavisWeinsteinTerms(tau, p);
    if (form == kFormSurfaceSurface) return d.x;
    if (form == kFormSurfaceMedium) return d.y;
    return d.z;
}

FN float trPulseForm(vec4 p, uint form, float tau) {
    if (form == kFormSurfaceSurface) return trPulseG(tau, p);
    if (form == kFormSurfaceMedium) {
        float n = p.z;
        float x = clamp(floor(n * (tau - p.x) / (p.y - p.x) + 0.5f), 0.0f, n);
        return 1.0f - x / n;
    }
    return 0.0f;  // Dirac comb
}

FN float trSimpleForm(uint type, vec4 p, uint form, float tau) {
    tau = max(tau, 0.0f);
    if (type == kTrLinear) return trLinearForm(p, form, tau);
    if (type == kTrQuadratic) return trQuadraticForm(p, form, tau);
    if (type == kTrDoubleExponential) return trDoubleExponentialForm(p, form, tau);
    if (type == kTrErlang) return trErlangForm(p, form, tau);
    if (type == kTrDavis) return trDavisForm(p, form, tau);
    if (type == kTrDavisWeinstein) return trDavisWeinsteinForm(p, form, tau);
    if (type == kTrPulse) return trPulseForm(p, form, tau);
    return exp(-tau);  // exponential: every form
}

// ---- Any model ----

FN float trSigmaBar(TrModel m) {
    if (m.type != kTrInterpolated) return trSimpleSigmaBar(m.type, m.a);
    return 1.0f / mix(1.0f / trSimpleSigmaBar(m.typeA, m.a), 1.0f / trSimpleSigmaBar(m.typeB, m.b), m.ratio);
}

// The segment weight of Transmittance::eval for the given form (see the top of this file).
FN float trForm(TrModel m, uint form, float tau) {
    if (m.type != kTrInterpolated) return trSimpleForm(m.type, m.a, form, tau);
    // Interpolated: g = sigmaBar lerp(g_A/sigmaBar_A, g_B/sigmaBar_B), T_sm and mediumMedium lerp.
    float sa = trSimpleSigmaBar(m.typeA, m.a), sb = trSimpleSigmaBar(m.typeB, m.b), s = trSigmaBar(m);
    float fa = trSimpleForm(m.typeA, m.a, form, tau), fb = trSimpleForm(m.typeB, m.b, form, tau);
    if (form == kFormSurfaceSurface) return s * mix(fa / sa, fb / sb, m.ratio);
    if (form == kFormSurfaceMedium) return mix(fa, fb, m.ratio);
    // eval(mm) = mediumMedium / sigmaBar; trSimpleForm returns mediumMedium_X / sigmaBar_X
    return mix(fa * sa, fb * sb, m.ratio) / s;
}

FN vec3 trForm3(TrModel m, uint form, vec3 tau) {
    if (m.type == kTrExponential) return exp(-tau);
    return vec3(trForm(m, form, tau.x), trForm(m, form, tau.y), trForm(m, form, tau.z));
}

FN uint trFormOf(bool startOnSurface, bool endOnSurface) {
    if (startOnSurface && endOnSurface) return kFormSurfaceSurface;
    if (!startOnSurface && !endOnSurface) return kFormMediumMedium;
    return kFormSurfaceMedium;
}

SHADER_NAMESPACE_END

#endif
