// Participating media for the path tracer (GLSL only; included by path_trace.comp after the
// scene buffers and intersect.h, before path_tracer.glsl). Compiled in always, folded away by
// kHasMedia for scenes without media.
//
// Every transmittance factor of a path comes from the chosen estimator
// (shared/transmittance_estimators.h), on camera segments and on shadow rays, so a path's
// contribution is unbiased exactly when the estimator is. Free-flight distances are drawn from a
// guide: the medium's own transmittance model over a homogeneous density mu (optical depth
// mu (t - t0), mu from a coarse independent comb of the segment); the estimated transmittance divided by the guide pdf weights the sample:
//   scatter at t:  sigma_s(x_t) sigmaBar <T_{start,medium}(0, t)> / (mu sigmaBar F_{start,medium}(mu (t - t0)))
//   pass to l:     <T_{start,surface}(0, l)> / F_{start,surface}(mu (l - t0))
// (forms of shared/transmittance.h; start = surface or medium vertex). Media are indexed + 1
// (0 = vacuum) in the path state.

#include "shared/bsdf.h"  // thinSheetReflectance (shadow rays through thin sheets)

layout(std430, binding = kBindingMedia) readonly buffer MediaBuffer { MediumGpu media[]; };
layout(std140, binding = kBindingMediaUniform) uniform MediaUniform { MediumGpu uniformMedia[kMaxUniformMedia]; };
MediumGpu sceneMedium(uint i) {
    if (kTablesInUniforms) return uniformMedia[i];
    return media[i];
}
layout(std430, binding = kBindingGridData) readonly buffer GridBuffer { float gridData[]; };
layout(std430, binding = kBindingPrimMedia) readonly buffer PrimMediaBuffer { uint primMedia[]; };
layout(std140, binding = kBindingPrimMediaUniform) uniform PrimMediaUniform { uvec4 uniformPrimMedia[kMaxUniformPrimMediaVec4s]; };

// With only homogeneous media in the scene (kHasInhomogeneous false) the code of varying densities
// folds away. Code a specialisation constant removes is gated by the constant alone (a nested `if`,
// or a constant expression such as kCombExactEverywhere below), never by `constant && runtime
// value` through a function call: glslang turns such a condition into short-circuit control flow
// that lavapipe folds only after optimising everything it guards, which made the path tracer's
// creation 4x slower (docs/BENCHMARKS.media-notes.md).

// ---- Density ----
#include "shared/density_grid.h"
#include "shared/majorant_walk.h"

// World point / direction -> the grid's unit box [0, 1]^3 (an affine map, MediumGpu::gridRow*).
vec3 gridUnitPoint(uint mi, vec3 p) {
    vec4 q = vec4(p, 1.0);
    return vec3(dot(sceneMedium(mi).gridRow0, q), dot(sceneMedium(mi).gridRow1, q), dot(sceneMedium(mi).gridRow2, q));
}
vec3 gridUnitDir(uint mi, vec3 d) {
    return vec3(dot(sceneMedium(mi).gridRow0.xyz, d), dot(sceneMedium(mi).gridRow1.xyz, d), dot(sceneMedium(mi).gridRow2.xyz, d));
}

// The lookup stencil of grid medium mi at world point p (nearest-voxel grids: one corner).
bool gridStencilAt(uint mi, vec3 p, out GridStencil g) {
    if (!gridStencil(sceneMedium(mi).gridRes, gridUnitPoint(mi, p), g)) return false;
    if ((sceneMedium(mi).gridFlags & kGridNearest) != 0u) g.t = gridNearestWeights(g.t);
    return true;
}

// Trilinear (or nearest) lookup of a grid medium at world point p (shared/density_grid.h).
float gridDensityAt(uint mi, vec3 p) {
    GridStencil g;
    if (!gridStencilAt(mi, p, g)) return 0.0;
    uint i = sceneMedium(mi).gridOffset + g.corner, x = g.step.x, y = g.step.y, z = g.step.z;
    return gridTrilinear(g.t, gridData[i], gridData[i + x], gridData[i + y], gridData[i + x + y], gridData[i + z],
                         gridData[i + x + z], gridData[i + y + z], gridData[i + x + y + z]);
}

// Emission per unit length of a grid medium at world point p (Tungsten's voxel medium: the
// emission grid, times the density where scale_emission_by_density).
vec3 gridEmissionAt(uint mi, vec3 p) {
    uint flags = sceneMedium(mi).gridFlags;
    GridStencil g;
    if ((flags & kGridEmission) == 0u || !gridStencilAt(mi, p, g)) return vec3(0.0);
    uint x = 3u * g.step.x, y = 3u * g.step.y, z = 3u * g.step.z;
    vec3 e;
    for (uint c = 0u; c < 3u; ++c) {
        uint i = sceneMedium(mi).emissionOffset + 3u * g.corner + c;
        e[c] = gridTrilinear(g.t, gridData[i], gridData[i + x], gridData[i + y], gridData[i + x + y], gridData[i + z],
                             gridData[i + x + z], gridData[i + y + z], gridData[i + x + y + z]);
    }
    if ((flags & kGridEmissionByDensity) != 0u) e *= gridDensityAt(mi, p);
    return e;
}

// trForm and trForm3 with the models the scene's media use (kSceneTrModels) called by name:
// conditions on the constant alone, which the host's optimizer removes with everything they guard.
// Lavapipe runs every branch of a dispatch on a run-time type with masks, so trForm's dispatch cost
// every model's code at each of the estimators' calls: with trEstimate's dispatch on
// kTrEstimatorType (TR_ESTIMATOR_TYPE below), pipeline creation of the media scenes went from
// 2.2-2.9 s to 0.2-0.5 s (docs/BENCHMARKS.md "Media pipelines"); scenes whose media use several
// models (Tungsten's non-exponential: four) dispatch over theirs alone (mediumSimpleForm), and
// grey media (kGreyMedia) evaluate one channel for three.
#define SCENE_HAS_TR_MODEL(t) ((kSceneTrModels & (1u << (t))) != 0u)
// The one model every medium uses, or 0xffffffff.
const uint kSceneTrModel =
    kSceneTrModels == (1u << kTrExponential)         ? kTrExponential
    : kSceneTrModels == (1u << kTrLinear)            ? kTrLinear
    : kSceneTrModels == (1u << kTrQuadratic)         ? kTrQuadratic
    : kSceneTrModels == (1u << kTrDoubleExponential) ? kTrDoubleExponential
    : kSceneTrModels == (1u << kTrErlang)            ? kTrErlang
    : kSceneTrModels == (1u << kTrDavis)             ? kTrDavis
    : kSceneTrModels == (1u << kTrDavisWeinstein)    ? kTrDavisWeinstein
    : kSceneTrModels == (1u << kTrPulse)             ? kTrPulse
                                                     : 0xffffffffu;
// trSimpleForm over the scene's simple models (tau >= 0).
float mediumSimpleForm(uint type, vec4 p, uint form, float tau) {
    if (SCENE_HAS_TR_MODEL(kTrLinear)) {
        if (type == kTrLinear) return trLinearForm(p, form, tau);
    }
    if (SCENE_HAS_TR_MODEL(kTrQuadratic)) {
        if (type == kTrQuadratic) return trQuadraticForm(p, form, tau);
    }
    if (SCENE_HAS_TR_MODEL(kTrDoubleExponential)) {
        if (type == kTrDoubleExponential) return trDoubleExponentialForm(p, form, tau);
    }
    if (SCENE_HAS_TR_MODEL(kTrErlang)) {
        if (type == kTrErlang) return trErlangForm(p, form, tau);
    }
    if (SCENE_HAS_TR_MODEL(kTrDavis)) {
        if (type == kTrDavis) return trDavisForm(p, form, tau);
    }
    if (SCENE_HAS_TR_MODEL(kTrDavisWeinstein)) {
        if (type == kTrDavisWeinstein) return trDavisWeinsteinForm(p, form, tau);
    }
    if (SCENE_HAS_TR_MODEL(kTrPulse)) {
        if (type == kTrPulse) return trPulseForm(p, form, tau);
    }
    return exp(-tau);  // exponential: every form
}
float mediumForm(TrModel m, uint form, float tau) {
    // (With one model its type is a constant here too.)
    if (!SCENE_HAS_TR_MODEL(kTrInterpolated))
        return mediumSimpleForm(kSceneTrModel != 0xffffffffu ? kSceneTrModel : m.type, m.a, form, max(tau, 0.0));
    return trForm(m, form, tau);
}
vec3 mediumForm3(TrModel m, uint form, vec3 tau) {
    if (kGreyMedia) return vec3(mediumForm(m, form, tau.x));
    if (kSceneTrModel == kTrExponential) return exp(-tau);
    if (!SCENE_HAS_TR_MODEL(kTrInterpolated))  // the scene's models alone, as mediumForm
        return vec3(mediumForm(m, form, tau.x), mediumForm(m, form, tau.y), mediumForm(m, form, tau.z));
    return trForm3(m, form, tau);
}
#define TR_FORM3 mediumForm3
#define TR_FORM mediumForm
// sampleGuideDepth's closed forms for the scene's models alone, and its bisection only for models
// without one (shared/free_flight.h).
#define TR_GUIDE_HAS(t) SCENE_HAS_TR_MODEL(t)
// (Bits, not ||: glslang writes a chain of || between specialisation constants as control flow.)
const uint kBisectionModels = (1u << kTrErlang) | (1u << kTrDavisWeinstein) | (1u << kTrInterpolated) |
                              (uint(kHasInhomogeneous) << kTrPulse);
const bool kGuideBisection = (kSceneTrModels & kBisectionModels) != 0u;
#define TR_GUIDE_BISECTION kGuideBisection
#define TR_GRID_DENSITY(s, t) gridDensityAt((s).medium, (s).origin + (s).dir * (t))
#define TR_TAYLOR_OUTSIDE_DISPATCH  // mediumTransmittance calls trTaylor under kTrEstimatorType alone
#define TR_ESTIMATOR_TYPE(e) kTrEstimatorType  // trEstimate keeps only the scene's estimator
#include "shared/transmittance_estimators.h"
#include "shared/free_flight.h"

// The model of medium mi; when every medium of the scene has the same simple model its type is a
// specialisation constant, so the compiler keeps only that model's code.
TrModel mediumModel(uint mi) {
    TrModel m = sceneMedium(mi).model;
    if (kSceneTrModel != 0xffffffffu) {
        m.type = kSceneTrModel;
        m.typeA = kSceneTrModel;
        m.typeB = kSceneTrModel;
    }
    return m;
}

// Density (relative to sigma_a, sigma_s) of medium mi at world point p.
float mediumDensityAt(uint mi, vec3 p) {
    if (!kHasInhomogeneous) return sceneMedium(mi).density;
    uint type = sceneMedium(mi).type;
    if (type == kMediumExponential)
        return sceneMedium(mi).density * exp(-sceneMedium(mi).falloffScale * dot(p - sceneMedium(mi).unitPoint, sceneMedium(mi).falloffDir));
    if (kHasGrids && type == kMediumGrid) return gridDensityAt(mi, p);
    return sceneMedium(mi).density;
}

// The segment o + t d, t in [0, l], of medium mi as a density profile; grid segments are clipped
// to the grid box (density 0 outside), so their origin moves to the box entry.
TrSegment mediumSegment(uint mi, vec3 o, vec3 d, float l) {
    MediumGpu m = sceneMedium(mi);
    TrSegment s;
    s.sigmaT = m.sigmaT;
    s.origin = o;
    s.dir = d;
    s.len = l;
    s.medium = mi;
    s.pad0 = 0u; s.pad1 = 0u; s.pad2 = 0u;
    if (kHasInhomogeneous && m.type == kMediumExponential) {
        float h0 = dot(o - m.unitPoint, m.falloffDir);
        s.profile = makeProfile(kProfileExponential, m.density * exp(-m.falloffScale * h0),
                                m.falloffScale * dot(d, m.falloffDir), 0.0);
    } else if (kHasGrids && m.type == kMediumGrid) {
        // Clip to the unit box in grid space (an affine map keeps the ray parameter t).
        vec3 uo = gridUnitPoint(mi, o), ud = gridUnitDir(mi, d);
        vec3 inv = safeInverse(ud);
        vec3 ta = -uo * inv, tb = (vec3(1.0) - uo) * inv;
        vec3 tn = min(ta, tb), tf = max(ta, tb);
        float t0 = max(max(tn.x, tn.y), max(tn.z, 0.0));
        float t1 = min(min(tf.x, tf.y), min(tf.z, l));
        s.profile = makeProfile(kProfileGrid, 0.0, 0.0, 0.0);
        s.origin = o + d * t0;
        s.len = max(t1 - t0, 0.0);
        s.densityMin = m.gridMinDensity;
        s.densityMax = m.gridMaxDensity;
        return s;
    } else {
        s.profile = makeProfile(kProfileConstant, m.density, 0.0, 0.0);
    }
    vec2 b = profileBounds(s.profile, 0.0, l);
    s.densityMin = b.x;
    s.densityMax = b.y;
    return s;
}

// The transmittance pmf pilot (render/pmf_pilot.h) fixes debiased marching's level at
// m = pc.pilotLevel and weights the correction by 1 or 2 (kTrPilotHalfWeight): the difference of
// the two renders is the path's unweighted correction.
TrEstimator sceneTrEstimator() {
    LevelPmf pmf = LevelPmf(kTrPmfType, kTrPmfR, kTrPmfAlpha);
    if (kTrPilot)
        pmf = LevelPmf(kPmfFixed, float(pc.pilotLevel & ~kTrPilotHalfWeight),
                       (pc.pilotLevel & kTrPilotHalfWeight) != 0u ? 0.5 : 1.0);
    return TrEstimator(kTrEstimatorType, kTrLevel, pmf, kTrTaylorTerms, kTrTaylorPoints);
}

// ---- Trackers through the majorant grid ----
// The (min, max) density over the voxels lookups in majorant cell c of medium mi may read.
vec2 majorantCell(uint mi, ivec3 c) {
    uvec3 r = sceneMedium(mi).majorantRes;
    uint i = sceneMedium(mi).majorantOffset + 2u * ((uint(c.z) * r.y + uint(c.y)) * r.x + uint(c.x));
    return vec2(gridData[i], gridData[i + 1u]);
}

// Steps of one tracking estimate (collisions plus cells crossed): lavapipe ends any loop after
// 65535 iterations per SIMD group, so the loop is bounded far below that; a segment reaching the
// bound (a majorant optical depth in the thousands) keeps the product so far.
const uint kTrMaxGridSteps = 16384u;

// Delta, ratio or residual ratio tracking of a grid segment, cell by cell: a 3-D DDA walks the
// majorant cells the segment crosses and each piece is tracked at its own cell's majorant
// (residual ratio: its own control and residual). Exponential transmittance only.
vec3 trTrackGrid(uint mode, TrSegment s, inout Rng rng, inout uint lookups) {
    vec3 result = vec3(1.0);
    if (!(s.len > 0.0)) return result;
    uint mi = s.medium;
    float sMax = trMaxComponent(s.sigmaT);
    vec3 scale = sceneMedium(mi).majorantScale;
    MajorantWalk walk = majorantWalkStart(gridUnitPoint(mi, s.origin) * scale, gridUnitDir(mi, s.dir) * scale,
                                          ivec3(sceneMedium(mi).majorantRes), s.len);
    float t = 0.0;
    float tCell = majorantWalkCellEnd(walk);
    vec2 mm = majorantCell(mi, walk.cell);
    float control = mode == kTrEstResidualRatioTracking ? 0.5 * (mm.x + mm.y) : 0.0;
    float mu = sMax * (mode == kTrEstResidualRatioTracking ? 0.5 * (mm.y - mm.x) : mm.y);
    if (mode == kTrEstResidualRatioTracking) result *= exp(-s.sigmaT * (control * tCell));
    for (uint guard = 0u; guard < kTrMaxGridSteps; ++guard) {
        if (LOOP_BUDGET_SPENT(1u)) break;
        float tc = mu > 0.0 ? t - log(1.0 - rngNext(rng)) / mu : kInfinity;
        if (tc < tCell) {
            // A tentative collision inside the cell
            t = tc;
            vec3 sigma = s.sigmaT * (trDensity(s, t) - control);
            lookups += 1u;
            if (!trCollide(mode, sigma, mu, result, rng)) break;
            continue;
        }
        // Into the next cell (the exponential steps are memoryless, so the piece restarts there)
        t = tCell;
        if (!majorantWalkNext(walk)) break;
        tCell = majorantWalkCellEnd(walk);
        mm = majorantCell(mi, walk.cell);
        if (mode == kTrEstResidualRatioTracking) {
            control = 0.5 * (mm.x + mm.y);
            mu = sMax * 0.5 * (mm.y - mm.x);
            result *= exp(-s.sigmaT * (control * max(tCell - t, 0.0)));
        } else {
            mu = sMax * mm.y;
        }
    }
    return result;
}

// Estimated transmittance of medium mi over [0, l] with the form of the endpoint types.
// Homogeneous media with a comb estimator (ray marching, debiased or unbiased ray marching, taylor): every
// comb of a constant density sees the exact optical depth, so every comb estimator returns
// g(sigma_t density l) exactly (debiased marching: the correction is exactly 0); it is returned
// without marching. Besides the work, marching would only add rounding: at a kink or step of g
// (linear, pulse) the sub-comb depths can round to opposite sides, and the correction divides
// that difference by p(j). The trackers stay stochastic (what the scene asked for).
const bool kCombEstimator = kTrEstimatorType == kTrEstRayMarch || kTrEstimatorType == kTrEstDebiasedRayMarch ||
                            kTrEstimatorType == kTrEstUnbiasedRayMarch || kTrEstimatorType == kTrEstTaylor;
const bool kCombExactEverywhere = kCombEstimator && !kHasInhomogeneous;
const bool kGridTracking = kHasGrids && (kTrEstimatorType == kTrEstDeltaTracking || kTrEstimatorType == kTrEstRatioTracking ||
                                          kTrEstimatorType == kTrEstResidualRatioTracking);
vec3 mediumTransmittance(uint mi, vec3 o, vec3 d, float l, bool startOnSurface, bool endOnSurface, inout Rng rng) {
    if (kCombExactEverywhere)
        return mediumForm3(mediumModel(mi), trFormOf(startOnSurface, endOnSurface),
                           sceneMedium(mi).sigmaT * (sceneMedium(mi).density * max(l, 0.0)));
    if (kCombEstimator && sceneMedium(mi).type == kMediumHomogeneous)
        return mediumForm3(mediumModel(mi), trFormOf(startOnSurface, endOnSurface),
                           sceneMedium(mi).sigmaT * (sceneMedium(mi).density * max(l, 0.0)));
    uint lookups = 0u;
    TrSegment s = mediumSegment(mi, o, d, l);
    if (kGridTracking) {
        if (sceneMedium(mi).type == kMediumGrid) return trTrackGrid(kTrEstimatorType, s, rng, lookups);
    }
    if (kTrEstimatorType == kTrEstTaylor)
        return trTaylor(sceneTrEstimator(), mediumModel(mi), trFormOf(startOnSurface, endOnSurface), s, rng, lookups,
                        kTaylorExact);
    return trEstimate(sceneTrEstimator(), mediumModel(mi), trFormOf(startOnSurface, endOnSurface), s, rng, lookups);
}

// ---- Medium boundaries ----

// The medium (index + 1) a ray continuing in dir is in after crossing prim with geometric normal ng:
// the interior one on the back side of ng, the exterior one on the front side; prims without media
// keep the current medium.
uint mediumAcrossPacked(uint packed, vec3 ng, vec3 dir, uint current) {
    if (packed == kPrimMediaNone) return current;
    return dot(dir, ng) < 0.0 ? (packed & 0xffffu) : (packed >> 16u);
}
// The same from prim's entry of primMedia. Lavapipe loads a storage buffer at lane-varying indices
// in a loop over the lanes (the hottest instructions of the volumetric caustic), so the entry comes
// from the uniform copy where the scene has one, and the path tracer reads a hit's entry once
// (primMediaOf) for all its uses.
uint primMediaOf(uint prim) {
    if (kSceneInUniforms) return uniformPrimMedia[prim >> 2u][prim & 3u];
    return primMedia[prim];
}
uint mediumAcross(uint prim, vec3 ng, vec3 dir, uint current) {
    return mediumAcrossPacked(primMediaOf(prim), ng, dir, current);
}

// Transmittance along a shadow ray from o to o + tMax d: forward surfaces let it through (each
// counts as a bounce, as in Tungsten), anything else blocks it; every medium segment is estimated.
// Thin sheets and transparency let shadow rays through (scene_common.glsl shadowPass).
vec3 shadowTransmittance(vec3 o, vec3 d, float tMax, uint medium, bool startOnSurface, inout Rng rng,
                         out uint crossings) {
    crossings = 0u;
    vec3 tr = vec3(1.0);
    for (uint guard = 0u; guard < 256u; ++guard) {
        if (LOOP_BUDGET_SPENT(1u)) break;
        Hit hit;
        bool found = traceClosest(o, d, tMax, hit);
        float end = found ? hit.t : tMax;
        if (medium != 0u) {
            // an unbounded medium absorbs everything; a grid ends at its box
            bool grid = kHasGrids && sceneMedium(medium - 1u).type == kMediumGrid;
            if (!(end < kInfinity) && !grid) return vec3(0.0);
            tr *= mediumTransmittance(medium - 1u, o, d, end, startOnSurface, true, rng);
        }
        if (!found) return tr;
        if (!kHasPassThrough && sceneMaterial(BVH_PRIM(hit.prim).material).type != kBsdfForward) return vec3(0.0);
        vec3 ng;
        tr *= shadowPass(hit, o, d, tMax, rng, ng);
        if (tr == vec3(0.0)) return tr;
        if (kHasMedia) medium = mediumAcross(hit.prim, ng, d, medium);
        startOnSurface = true;
        ++crossings;
    }
    return vec3(0.0);
}

// ---- Phase functions: shared/phase.h (Henyey-Greenstein; g = 0 is isotropic) ----
#include "shared/phase.h"

float mediumPhaseG(uint mi) { return sceneMedium(mi).phase == kPhaseHenyeyGreenstein ? sceneMedium(mi).phaseG : 0.0; }

// ---- Dirac free flights: linear and pulse from a medium point ----
// From a medium point the free flight of `linear` is a Dirac at tau = max_t, that of `pulse` a
// comb of n Diracs of mass 1/n at tau_i = min + (i + 1/2) (max - min) / n (Tungsten's
// mediumMedium; sampleMedium draws them). True for simple models of those types.
// A segment of length l from a medium point of homogeneous medium mi whose model is a Dirac free
// flight (shared/free_flight.h: sampleDiracFlight).
bool sampleDiracSegment(uint mi, vec3 o, vec3 d, float l, inout vec3 throughput, out vec3 p, inout Rng rng) {
    float uc = rngNext(rng), ud = rngNext(rng);
    float t;
    vec3 weight;
    bool scattered = sampleDiracFlight(mediumModel(mi), sceneMedium(mi).sigmaT * sceneMedium(mi).density,
                                       sceneMedium(mi).sigmaS * sceneMedium(mi).density, l, uc, ud, t, weight);
    p = o + d * t;
    throughput *= weight;
    return scattered;
}

// One camera segment of length l through medium mi. Returns true when the path scatters in the
// medium: p is the scattering point, throughput carries the scattering weight and emitted the
// medium's emission collected there (already times the throughput before the segment); otherwise
// throughput carries the weight of passing to the surface at l. A zero throughput ends the path.
bool sampleMediumSegment(uint mi, vec3 o, vec3 d, float l, bool fromSurface, inout vec3 throughput, out vec3 p,
                         out vec3 emitted, inout Rng rng) {
    p = o;
    emitted = vec3(0.0);
    bool emits = kHasGrids && sceneMedium(mi).type == kMediumGrid && (sceneMedium(mi).gridFlags & kGridEmission) != 0u;
    TrModel model = mediumModel(mi);
    if (!fromSurface && (!kHasInhomogeneous || sceneMedium(mi).type == kMediumHomogeneous) && trModelIsDirac(model) &&
        trMaxComponent(sceneMedium(mi).sigmaS) > 0.0)
        return sampleDiracSegment(mi, o, d, l, throughput, p, rng);
    TrSegment whole = mediumSegment(mi, o, d, l);
    // The guide works on the part of [0, l] with density (grids: the box).
    float t0 = (kHasGrids && sceneMedium(mi).type == kMediumGrid) ? dot(whole.origin - o, d) : 0.0;
    // The guide's homogeneous density: an 8-point comb average of the segment, drawn independently
    // of everything else (so the pdf is fixed given it), at least 10% of the majorant so that every
    // point with density keeps a positive pdf. Purely absorbing media never scatter (mu = 0).
    float guideDensity = whole.densityMax;
    if (kHasInhomogeneous) {
        if (sceneMedium(mi).type != kMediumHomogeneous && whole.len > 0.0) {
            uint lookups = 0u;
            float average = combSum(whole, rngNext(rng), 0u, 1u, 8u, 8.0, lookups) / 8.0;
            guideDensity = max(average, 0.1 * whole.densityMax);
        }
    }
    float mu = (trMaxComponent(sceneMedium(mi).sigmaS) > 0.0 || emits) ? trMaxComponent(whole.sigmaT) * guideDensity : 0.0;
    float sigmaBar = trSigmaBar(model);
    float u = rngNext(rng);
    bool guided = mu > 0.0 && whole.len > 0.0;
    float depth = guided ? sampleGuideDepth(model, fromSurface, u) : 0.0;
    float t = t0 + depth / mu;
    bool scatter = guided && t < t0 + whole.len;
    // Both outcomes share one evaluation of the guide's form and one transmittance estimate (lanes
    // with masks run every call site): scatter at t with density
    //   pdf = mu sigmaBar F_{start,medium}(depth),
    // or pass to the surface at l with probability F_{start,surface}(mu len) (1 without a guide).
    float form = guided ? mediumForm(model, trFormOf(fromSurface, !scatter), scatter ? depth : mu * whole.len) : 1.0;
    float pdf = scatter ? mu * sigmaBar * form : form;
    if (scatter) p = o + d * t;
    if (!(pdf > 0.0)) {
        throughput = vec3(0.0);
        return scatter;
    }
    vec3 w = mediumTransmittance(mi, o, d, scatter ? t : l, fromSurface, !scatter, rng) / pdf;
    if (!scatter) {
        throughput *= w;
        return false;
    }
    // Emission collected at the collision (Tungsten's voxel medium): the emission per unit length
    // times T_{start,medium}(t) / pdf(t), an estimate of integral T e dt.
    if (emits) emitted = throughput * w * gridEmissionAt(mi, p);
    throughput *= sceneMedium(mi).sigmaS * mediumDensityAt(mi, p) * sigmaBar * w;
    return true;
}
