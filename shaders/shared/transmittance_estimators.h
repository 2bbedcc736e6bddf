// Transmittance estimators (docs/ESTIMATORS.md section 4), one source for GLSL and C++.
//
// A segment is [0, length] along a ray with density d(t) and material sigma_t (per channel), so
// tau = sigma_t * integral d. Every estimator is a strategy over one of two walkers of sample
// positions, both counting density lookups (the work):
//   comb walker     points l (u + i) / N, a random offset u (ray marching, debiased marching,
//                   unbiased ray marching);
//   tracking walker tentative collisions t += -ln(1 - u) / mu (delta, ratio, residual ratio).
// The comb estimators evaluate any transmittance form g (transmittance.h); the trackers and
// unbiased ray marching estimate exp(-tau) only (exponential media).
//
// Before including, the includer may define TR_GRID_DENSITY(segment, t), the density of a
// kProfileGrid segment at t (medium.glsl looks the grid up); otherwise grids read as empty; and
// TR_TAYLOR_OUTSIDE_DISPATCH, to call trTaylor itself under a specialisation constant: behind
// trEstimate's run-time type it was compiled into every media pipeline (1.3 s more pipeline
// creation on the absorbing slab with ratio tracking).
#ifndef TELESCOPE_TRANSMITTANCE_ESTIMATORS_H
#define TELESCOPE_TRANSMITTANCE_ESTIMATORS_H

#include "shared/density_profiles.h"
#include "shared/level_pmf.h"
#include "shared/rng.h"
#include "shared/transmittance.h"

SHADER_NAMESPACE_BEGIN

// The segment weights the estimators evaluate: the includer may define TR_FORM3 and TR_FORM
// (medium.glsl folds in the model every medium of the scene shares, which the host's optimizer
// cannot see through trForm's model argument: without it, each of the estimators' calls carried
// every model's code into pipeline creation).
#ifndef TR_FORM3
#define TR_FORM3 trForm3
#endif
#ifndef TR_FORM
#define TR_FORM trForm
#endif
// The estimator trEstimate runs: its argument's type, unless the includer names a constant
// (medium.glsl: kTrEstimatorType, so that the host's optimizer drops the other estimators before
// lavapipe optimises them; the transmittance study sweeps them at run time).
#ifndef TR_ESTIMATOR_TYPE
#define TR_ESTIMATOR_TYPE(e) (e).type
#endif

// Largest comb of debiased marching: 2^kTrMaxCombLog2 points; deeper levels are marched at this
// size (a truncation of the telescope). Why a cap at all: (1) in single precision the correction's
// rounding error, about 1e-7 g, is divided by p(j), so its second moment grows like
// sum_j 1e-14 / p(j); (2) lavapipe (llvmpipe) ends every loop of an invocation after 65535
// iterations per SIMD group: a path step with two or three estimates of 2^13 points fits that,
// running alone (gpu_types.h kHeavyLoopBudget), and one of 2^14 would not. The truncation drops
// E[D_j] = O(4^-j) for j >= 12, below 1e-7 for smooth g, with probability 0.35^(12-k) for the
// default pmf.
CONST uint kTrMaxCombLog2 = 13u;
// Unbiased ray marching: highest expansion order kept (P(N >= 16) = 4^-16 with q = 1/4).
CONST uint kTrMaxOrder = 15u;
CONST float kTrOrderQ = 0.25f;

struct TrEstimator {
    uint type;
    uint level;      // k: the base level (ray marching: 2^k points; taylor: the pivot's comb)
    LevelPmf pmf;    // debiased marching: level j = k + m, m ~ pmf
    uint terms;      // taylor: terms always evaluated before the roulette
    uint points;     // taylor: points of each factor's comb (0: from the density bounds)
};

// A segment of one medium along a ray.
struct TrSegment {
    DensityProfile profile;  // d(t); kProfileGrid: TR_GRID_DENSITY
    vec3 sigmaT; float len;
    vec3 origin; float densityMin;   // ray origin (grids)
    vec3 dir; float densityMax;      // unit direction (grids); densityMin/Max bound d on [0, length]
    uint medium; uint pad0; uint pad1; uint pad2;
};

FN float trDensity(TrSegment s, float t) {
#ifdef TR_GRID_DENSITY
    if (s.profile.type == kProfileGrid) return TR_GRID_DENSITY(s, t);
#else
    if (s.profile.type == kProfileGrid) return 0.0f;
#endif
    return profileDensity(s.profile, t);
}

FN float trMaxComponent(vec3 v) { return max(v.x, max(v.y, v.z)); }

#ifdef __cplusplus
#define TR_PRECISE
#else
#define TR_PRECISE precise
#endif

// ---- Comb walker: sum of d at l (u + first + i stride) / n, i < count ----
// Compensated (Kahan) summation: the debiased correction divides rounding errors by p(j).
FN float combSum(TrSegment s, float u, uint first, uint stride, uint count, float n, INOUT(uint) lookups) {
    TR_PRECISE float sum = 0.0f;
    TR_PRECISE float err = 0.0f;
    float scale = s.len / n;
    if (LOOP_BUDGET_SPENT(max(count, 1u))) return 0.0f;
    for (uint i = 0u; i < count; ++i) {
        TR_PRECISE float y = trDensity(s, scale * (u + float(first + i * stride))) - err;
        TR_PRECISE float t = sum + y;
        err = (t - sum) - y;
        sum = t;
    }
    lookups += count;
    return sum;
}

// Biased ray marching: <tau_k> = (l / 2^k) sum d(x_i), <I(k)> = g(<tau_k>).
FN vec3 trRayMarch(uint k, TrModel m, uint form, TrSegment s, INOUT(Rng) rng, INOUT(uint) lookups) {
    float n = float(1u << k);
    float sum = combSum(s, rngNext(rng), 0u, 1u, 1u << k, n, lookups);
    return TR_FORM3(m, form, s.sigmaT * (sum * s.len / n));
}

// Debiased ray marching (docs/ESTIMATORS.md section 4): one comb of 2^(j+1) points, ordered as
// 2^(j+1-k) interleaved sub-combs of 2^k points (sub-comb i holds points i, i + S, ...):
//   <I(k)> = mean over sub-combs of g(tau_sub),
//   <D_j>  = g(tau_all) - (g(tau_even) + g(tau_odd)) / 2   (even/odd = the sub-combs of even/odd i),
//   Z      = <I(k)> + <D_j> / p(j - k).
FN vec3 trDebiasedRayMarch(TrEstimator e, TrModel m, uint form, TrSegment s, INOUT(Rng) rng, INOUT(uint) lookups) {
    uint k = e.level;
    uint level = levelSample(e.pmf, rngNext(rng));
    uint j = k + min(level, kTrMaxCombLog2 - 1u - min(k, kTrMaxCombLog2 - 1u));
    float n = float(1u << (j + 1u));
    uint subCombs = 1u << (j + 1u - k);
    uint subPoints = 1u << k;
    float u = rngNext(rng);
    vec3 base = vec3(0.0f);
    // even/odd: compensated sums over the sub-combs (rounding would not cancel in <D_j>)
    TR_PRECISE float even = 0.0f, odd = 0.0f, evenErr = 0.0f, oddErr = 0.0f;
    for (uint i = 0u; i < subCombs; ++i) {
        if (LOOP_BUDGET_SPENT(1u)) break;
        float sub = combSum(s, u, i, subCombs, subPoints, n, lookups);
        base += TR_FORM3(m, form, s.sigmaT * ldexp(sub * s.len, -int(k)));
        if ((i & 1u) == 0u) {
            TR_PRECISE float y = sub - evenErr;
            TR_PRECISE float t = even + y;
            evenErr = (t - even) - y;
            even = t;
        } else {
            TR_PRECISE float y = sub - oddErr;
            TR_PRECISE float t = odd + y;
            oddErr = (t - odd) - y;
            odd = t;
        }
    }
    base = ldexp(base, ivec3(-int(j + 1u - k)));
    // Scalings by exact powers of two (ldexp): a device's approximate division would make tau_all
    // and tau_even differ by rounding, which <D_j> / p(j) amplifies.
    vec3 gAll = TR_FORM3(m, form, s.sigmaT * ldexp((even + odd) * s.len, -int(j + 1u)));
    vec3 gEven = TR_FORM3(m, form, s.sigmaT * ldexp(even * s.len, -int(j)));
    vec3 gOdd = TR_FORM3(m, form, s.sigmaT * ldexp(odd * s.len, -int(j)));
    vec3 d = gAll - 0.5f * (gEven + gOdd);
    return base + d / levelProbability(e.pmf, j - k);
}

// ---- Tracking walker: tentative collisions with rate mu (majorant of sigma_t) ----

// The weight of one tentative collision where the (control-subtracted) extinction is sigma:
// delta tracking keeps each channel with probability 1 - sigma/mu, the ratio trackers multiply by
// it. Returns false when delta tracking has ended every channel (the walk can stop). One source
// for the walker below and the majorant-grid walker of medium.glsl.
FN bool trCollide(uint mode, vec3 sigma, float mu, INOUT(vec3) result, INOUT(Rng) rng) {
    if (mode == kTrEstDeltaTracking) {
        float xi = rngNext(rng);
        result *= vec3(xi >= sigma.x / mu ? 1.0f : 0.0f, xi >= sigma.y / mu ? 1.0f : 0.0f,
                       xi >= sigma.z / mu ? 1.0f : 0.0f);
        return trMaxComponent(result) != 0.0f;
    }
    result *= vec3(1.0f) - sigma / mu;
    // A product that reached 0 (underflow in an optically thick segment) stays 0: stopping there
    // changes no estimate, and keeps walks through tau = 1e4 short.
    return trMaxComponent(abs(result)) != 0.0f;
}

// mode: delta (1 until a real collision per channel), ratio (prod 1 - sigma/mu), residual ratio
// (exp(-sigma_c l) prod 1 - (sigma - sigma_c)/mu_r with sigma_c at the middle of the density
// bounds and mu_r their half-width).
FN vec3 trTrack(uint mode, TrSegment s, INOUT(Rng) rng, INOUT(uint) lookups) {
    float sMax = trMaxComponent(s.sigmaT);
    float control = 0.0f;
    float mu = sMax * s.densityMax;
    vec3 result = vec3(1.0f);
    if (mode == kTrEstResidualRatioTracking) {
        control = 0.5f * (s.densityMin + s.densityMax);
        mu = sMax * 0.5f * (s.densityMax - s.densityMin);
        result = exp(-s.sigmaT * (control * s.len));
    }
    if (!(mu > 0.0f)) return result;
    float t = 0.0f;
    for (uint guard = 0u; guard < 1000000u; ++guard) {
        if (LOOP_BUDGET_SPENT(1u)) break;
        t -= log(1.0f - rngNext(rng)) / mu;
        if (t >= s.len) break;
        vec3 sigma = s.sigmaT * (trDensity(s, t) - control);
        lookups += 1u;
        if (!trCollide(mode, sigma, mu, result, rng)) break;
    }
    return result;
}

// ---- Unbiased ray marching (Kettunen, d'Eon, Pantaleoni, Novak 2021), our reading ----
// exp(-tau) = exp(-X_p) sum_k (X_p - tau)^k / k! around a pivot comb estimate X_p; each power is
// a product of independent comb estimates (X_p - X_i); the order N is Russian-rouletted with
// P(N >= k) = q^k (most samples stop at order 0), and the estimate averages all N + 1 choices of
// the pivot (a U-statistic; for each pivot the order-k term uses the first k other combs):
//   Z = 1/(N+1) sum_p exp(-X_p) sum_{k<=N} prod_{i in first k others} (X_p - X_i) / (k! q^k).
// Each comb has M points, M from the density bounds so that a comb's error stays below ~1/2.
// Constant density: every X_i = tau, so Z = exp(-tau) exactly (zero variance).
FN vec3 trUnbiasedRayMarch(TrSegment s, INOUT(Rng) rng, INOUT(uint) lookups) {
    float spread = trMaxComponent(s.sigmaT) * (s.densityMax - s.densityMin) * s.len;
    uint points = uint(clamp(ceil(2.0f * spread), 1.0f, 256.0f));
    uint order = 0u;
    while (order < kTrMaxOrder && rngNext(rng) < kTrOrderQ) ++order;
    // The order loop above and the pivot loops below: at most (kTrMaxOrder + 1)^2 + 2 (kTrMaxOrder + 1).
    LOOP_BUDGET_TICK((order + 3u) * (order + 1u) + 1u);
    vec3 x[kTrMaxOrder + 1u];
    for (uint i = 0u; i <= order; ++i)
        x[i] = s.sigmaT * (combSum(s, rngNext(rng), 0u, 1u, points, float(points), lookups) * s.len / float(points));
    vec3 total = vec3(0.0f);
    for (uint p = 0u; p <= order; ++p) {
        vec3 series = vec3(1.0f);
        vec3 product = vec3(1.0f);
        float weight = 1.0f;  // 1 / (k! q^k)
        uint k = 0u;
        for (uint i = 0u; i <= order; ++i) {
            if (i == p) continue;
            ++k;
            product *= x[p] - x[i];
            weight /= float(k) * kTrOrderQ;
            series += product * weight;
        }
        total += exp(-x[p]) * series;
    }
    return total / float(order + 1u);
}

// ---- Taylor series (Misso et al. 2022; docs/ESTIMATORS.md section 5, docs/MEDIA.md) ----
// f(tau) = sum_j c_j(x) (tau - x)^j around a pivot x, a jittered comb estimate of tau; each power
// (tau - x)^j is estimated by a product of j independent comb estimates (X_i - x); the number of
// terms N is Russian-rouletted, term j weighted by 1 / P(N >= j):
//   Z = sum_{j <= N} c_j(x) prod_{i <= j} (X_i - x) / P(N >= j).
// Unbiased where the series converges over the range of the estimates (Davis: |X - x| < x + alpha,
// the singularity at tau = -alpha; the other models here are entire). The coefficients of every
// supported model are sums of at most kTrTaylorMaxParts parts
//   c_j = sum_parts r_j (a + j b),   r_0 given,   r_j = r_{j-1} (-(alpha + beta (j - 1)) / (j gamma)),
// exponential exp(-lambda tau): alpha = lambda, beta = 0, gamma = 1;  Davis (1 + tau/a)^-e:
// alpha = e, beta = 1, gamma = a + x;  Erlang's polynomial factor: a + j b.
// The roulette follows the recipe p(j) ~ sqrt(E[term_j^2]): the j-th factor is kept with
// probability min(1, eps |r_j / r_{j-1}|), eps a bound on |X_i - x| from the segment's density
// bounds; combs have M points, M chosen so that eps |r_j / r_{j-1}| <= 1/2. Constant density: every
// comb is exact, eps = 0, Z = f(x) exactly (zero variance).
CONST uint kTrTaylorMaxParts = 4u;
// Hard cap on the terms: with combs sized from the density bounds a factor is kept with probability
// at most 1/2 once past the forced terms, so P(N >= 40) <= 2^-39; a fixed coarse `points`, or combs
// at their 256-point cap, can keep every factor, and the series is then truncated here.
CONST uint kTrTaylorMaxTerms = 40u;
CONST uint kTrTaylorMaxPoints = 256u;  // largest comb of a factor
// Comb size M = max(8, ceil(4 spread sup_j |r_j / r_{j-1}|)): the 4 keeps eps |r_j / r_{j-1}| <= 1/2.
// Measured with `telescope study transmittance` (geometric mean of work x MSE / T^2 over 150 problems
// a model; exponential / Davis c = 0.8): at least 1, 4, 8, 16 points: 2.2e-6 / 7.6e-7, 1.2e-6 / 4.1e-7,
// 5.6e-7 / 1.9e-7, 5.8e-7 / 2.1e-7; scale 2 instead of 4 (with 8): 6.5e-7 / 2.0e-7.
CONST float kTrTaylorCombScale = 4.0f;
CONST uint kTrTaylorMinPoints = 8u;
// Deliberately wrong variants, for the tests' positive controls only (callers pass a constant).
CONST uint kTaylorExact = 0u;
CONST uint kTaylorControlReusedDepth = 1u;  // one estimate X_1 for every factor of a power
CONST uint kTaylorControlNoSign = 2u;       // (-1)^j dropped: |c_j|
CONST uint kTaylorControlThreeTerms = 3u;   // three terms always, no roulette

struct TrTaylorSeries {
    vec3 r[kTrTaylorMaxParts];
    vec3 alpha[kTrTaylorMaxParts];
    vec3 gamma[kTrTaylorMaxParts];
    vec3 a[kTrTaylorMaxParts];
    vec3 b[kTrTaylorMaxParts];
    float beta[kTrTaylorMaxParts];
    uint count;
};

FN void trTaylorAddPart(INOUT(TrTaylorSeries) s, vec3 r, vec3 alpha, float beta, vec3 gamma, vec3 a, vec3 b) {
    if (s.count >= kTrTaylorMaxParts) return;
    s.r[s.count] = r; s.alpha[s.count] = alpha; s.beta[s.count] = beta; s.gamma[s.count] = gamma;
    s.a[s.count] = a; s.b[s.count] = b;
    s.count += 1u;
}

// Whether the form's Taylor series is supported: exponential, double exponential, Erlang (entire)
// and Davis (radius x + alpha), and interpolations of them. Linear, quadratic and pulse have kinks
// or steps (no series), Davis-Weinstein's exponent alpha(tau) ~ tau^(1 - beta) has a branch point at 0.
FN bool trTaylorSimpleSupported(uint type) {
    return type == kTrExponential || type == kTrDoubleExponential || type == kTrErlang || type == kTrDavis;
}
FN bool trTaylorSupported(TrModel m) {
    if (m.type != kTrInterpolated) return trTaylorSimpleSupported(m.type);
    return trTaylorSimpleSupported(m.typeA) && trTaylorSimpleSupported(m.typeB);
}

// The parts of w * (simple model's form) around x (per channel); see trSimpleForm.
FN void trTaylorSimpleParts(INOUT(TrTaylorSeries) s, uint type, vec4 p, uint form, vec3 x, float w) {
    vec3 one = vec3(1.0f), zero = vec3(0.0f);
    if (type == kTrDavis) {
        float a = p.x;
        float e = a + float(form);  // g: a, T_sm: a + 1, medium-medium: a + 2
        float c = form == kFormMediumMedium ? 1.0f + 1.0f / a : 1.0f;
        vec3 r = vec3(exp(-e * log1pSafe(x.x / a)), exp(-e * log1pSafe(x.y / a)), exp(-e * log1pSafe(x.z / a)));
        trTaylorAddPart(s, (w * c) * r, vec3(e), 1.0f, vec3(a) + x, one, zero);
    } else if (type == kTrDoubleExponential) {
        float sb = 0.5f * (p.x + p.y);
        float wa = 0.5f, wb = 0.5f;
        if (form == kFormSurfaceMedium) { wa = 0.5f * p.x / sb; wb = 0.5f * p.y / sb; }
        if (form == kFormMediumMedium) { wa = 0.5f * p.x * p.x / (sb * sb); wb = 0.5f * p.y * p.y / (sb * sb); }
        trTaylorAddPart(s, (w * wa) * exp(-p.x * x), vec3(p.x), 0.0f, one, one, zero);
        trTaylorAddPart(s, (w * wb) * exp(-p.y * x), vec3(p.y), 0.0f, one, one, zero);
    } else if (type == kTrErlang) {
        // e^(-l x) P(x) with P linear: c_j = (-l)^j / j! e^(-l x) (P(x) - j P' / l)
        float l = p.x;
        vec3 r = w * exp(-l * x);
        if (form == kFormSurfaceSurface) trTaylorAddPart(s, r, vec3(l), 0.0f, one, one + 0.5f * l * x, vec3(-0.5f));
        else if (form == kFormSurfaceMedium) trTaylorAddPart(s, r, vec3(l), 0.0f, one, one + l * x, vec3(-1.0f));
        else trTaylorAddPart(s, r, vec3(l), 0.0f, one, 2.0f * l * x, vec3(-2.0f));  // l^2 x e^(-l x) / (l/2)
    } else {
        trTaylorAddPart(s, w * exp(-x), one, 0.0f, one, one, zero);  // exponential
    }
}

FN TrTaylorSeries trTaylorSeries(TrModel m, uint form, vec3 x) {
    TrTaylorSeries s;
    s.count = 0u;
    if (m.type != kTrInterpolated) {
        trTaylorSimpleParts(s, m.type, m.a, form, x, 1.0f);
        return s;
    }
    // Interpolated (trForm): g = sigmaBar lerp(g_A / sigmaBar_A, g_B / sigmaBar_B), T_sm lerp,
    // medium-medium lerp(f_A sigmaBar_A, f_B sigmaBar_B) / sigmaBar.
    float sa = trSimpleSigmaBar(m.typeA, m.a), sb = trSimpleSigmaBar(m.typeB, m.b), sm = trSigmaBar(m);
    float wa = 1.0f - m.ratio, wb = m.ratio;
    if (form == kFormSurfaceSurface) { wa *= sm / sa; wb *= sm / sb; }
    if (form == kFormMediumMedium) { wa *= sa / sm; wb *= sb / sm; }
    trTaylorSimpleParts(s, m.typeA, m.a, form, x, wa);
    trTaylorSimpleParts(s, m.typeB, m.b, form, x, wb);
    return s;
}

// c_0 = f(x).
FN vec3 trTaylorValue(TrTaylorSeries s) {
    vec3 c = vec3(0.0f);
    for (uint i = 0u; i < s.count; ++i) c += s.r[i] * s.a[i];
    return c;
}

// Moves the parts from r_{j-1} w to r_j w f (j >= 1; w f carries the estimate's product and roulette
// weight, so that no power of a large difference is formed alone) and returns sum r_j w f (a + j b).
// sign: -1 for the series (the sign of each derivative), +1 only for a test's control.
FN vec3 trTaylorNext(INOUT(TrTaylorSeries) s, uint j, vec3 f, float sign) {
    vec3 c = vec3(0.0f);
    for (uint i = 0u; i < s.count; ++i) {
        s.r[i] *= (sign * f) * (s.alpha[i] + s.beta[i] * float(j - 1u)) / (float(j) * s.gamma[i]);
        c += s.r[i] * (s.a[i] + float(j) * s.b[i]);
    }
    return c;
}

// Whether every part is 0 (an underflowed exp(-x)): no later term can add anything.
FN bool trTaylorVanished(TrTaylorSeries s) {
    float m = 0.0f;
    for (uint i = 0u; i < s.count; ++i) m = max(m, trMaxComponent(abs(s.r[i])));
    return m == 0.0f;
}

// |r_j / r_{j-1}| per channel, the largest over the parts (j >= 1; the sup over j when j = 0).
FN vec3 trTaylorRatio(TrTaylorSeries s, uint j) {
    vec3 q = vec3(0.0f);
    for (uint i = 0u; i < s.count; ++i) {
        vec3 num = j == 0u ? max(s.alpha[i], vec3(s.beta[i])) : s.alpha[i] + s.beta[i] * float(j - 1u);
        q = max(q, num / (max(float(j), 1.0f) * s.gamma[i]));
    }
    return q;
}

FN vec3 trTaylor(TrEstimator e, TrModel m, uint form, TrSegment s, INOUT(Rng) rng, INOUT(uint) lookups, uint variant) {
    // The spread of the optical depth over the segment bounds a comb's error (monotone density:
    // |X - tau| <= spread / points); the sizes keep eps * ratio <= 1/2 at the lower bound of tau.
    vec3 spread = s.sigmaT * ((s.densityMax - s.densityMin) * s.len);
    vec3 ratioBound = trTaylorRatio(trTaylorSeries(m, form, s.sigmaT * (s.densityMin * s.len)), 0u);
    float need = trMaxComponent(spread * ratioBound);
    uint points = e.points > 0u ? min(e.points, kTrTaylorMaxPoints)
                                : uint(clamp(ceil(kTrTaylorCombScale * need), float(kTrTaylorMinPoints),
                                             float(kTrTaylorMaxPoints)));
    uint pivotPoints = max(1u << min(e.level, kTrMaxCombLog2), points);
    vec3 x = s.sigmaT * (combSum(s, rngNext(rng), 0u, 1u, pivotPoints, float(pivotPoints), lookups) * s.len /
                         float(pivotPoints));
    TrTaylorSeries series = trTaylorSeries(m, form, x);
    vec3 eps = spread * (1.0f / float(points) + 1.0f / float(pivotPoints));
    vec3 total = trTaylorValue(series);
    vec3 first = vec3(0.0f);
    for (uint j = 1u; j <= kTrTaylorMaxTerms; ++j) {
        if (LOOP_BUDGET_SPENT(1u) || trTaylorVanished(series)) break;
        // P(N >= j) / P(N >= j - 1)
        float q = j <= e.terms ? 1.0f : min(1.0f, trMaxComponent(eps * trTaylorRatio(series, j)));
        if (variant == kTaylorControlThreeTerms) q = j <= 3u ? 1.0f : 0.0f;
        if (!(q > 0.0f)) break;
        if (q < 1.0f && rngNext(rng) >= q) break;
        vec3 xi = s.sigmaT * (combSum(s, rngNext(rng), 0u, 1u, points, float(points), lookups) * s.len / float(points));
        if (variant == kTaylorControlReusedDepth) {
            if (j == 1u) first = xi;
            xi = first;
        }
        total += trTaylorNext(series, j, (xi - x) / q, variant == kTaylorControlNoSign ? 1.0f : -1.0f);
    }
    return total;
}

// ---- Dispatch over the estimators ----
FN vec3 trEstimate(TrEstimator e, TrModel m, uint form, TrSegment s, INOUT(Rng) rng, INOUT(uint) lookups) {
    if (!(s.len > 0.0f)) return vec3(TR_FORM(m, form, 0.0f));
    if (TR_ESTIMATOR_TYPE(e) == kTrEstRayMarch) return trRayMarch(e.level, m, form, s, rng, lookups);
    if (TR_ESTIMATOR_TYPE(e) == kTrEstDebiasedRayMarch) return trDebiasedRayMarch(e, m, form, s, rng, lookups);
    if (TR_ESTIMATOR_TYPE(e) == kTrEstUnbiasedRayMarch) return trUnbiasedRayMarch(s, rng, lookups);
#ifndef TR_TAYLOR_OUTSIDE_DISPATCH
    if (TR_ESTIMATOR_TYPE(e) == kTrEstTaylor) return trTaylor(e, m, form, s, rng, lookups, kTaylorExact);
#endif
    return trTrack(TR_ESTIMATOR_TYPE(e), s, rng, lookups);
}

SHADER_NAMESPACE_END

#endif
