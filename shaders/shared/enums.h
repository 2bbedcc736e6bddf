// Every enumeration the host and the shaders share, defined once. The shaders switch on these
// constants; the host's enums (src/scene/scene.h) take their values from them, so a C++ enum
// converts to its shader constant with a plain cast and the two cannot disagree.
#ifndef TELESCOPE_ENUMS_H
#define TELESCOPE_ENUMS_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

// ---- Primitives (GeometryType) ----
CONST uint kPrimTriangle = 0u;
CONST uint kPrimSphere = 1u;
CONST uint kPrimDisk = 2u;
CONST uint kPrimQuad = 3u;  // parallelogram p0 + [0,1] (p1 - p0) + [0,1] (p2 - p0), analytic
// Prim.type holds the shape (above) in its low byte (primShape) and flags above it:
// kPrimInterface marks a surface that only separates two media (a smooth or rough dielectric, a
// forward medium boundary). Where such a surface coincides with another one (water resting on a
// floor, a medium's box on a wall), a ray hits the other: shared/intersect.h "Coincident surfaces".
CONST uint kPrimShapeMask = 0xffu;
CONST uint kPrimInterface = 0x100u;

// ---- Materials (BsdfType) ----
CONST uint kBsdfLambert = 0u;
CONST uint kBsdfMirror = 1u;
CONST uint kBsdfDielectric = 2u;
CONST uint kBsdfNull = 3u;
CONST uint kBsdfForward = 4u;  // invisible medium boundary (Tungsten's "forward")
CONST uint kBsdfConductor = 5u;       // smooth conductor: mirror weighted by the conductor Fresnel term
CONST uint kBsdfRoughConductor = 6u;  // microfacet conductor (shared/microfacet.h)
CONST uint kBsdfPlastic = 7u;         // smooth coat over a diffuse substrate (shared/layered.h)
CONST uint kBsdfRoughPlastic = 8u;    // microfacet coat over a diffuse substrate
CONST uint kBsdfOrenNayar = 9u;       // rough diffuse
CONST uint kBsdfRoughDielectric = 10u;  // microfacet dielectric, reflection and refraction
CONST uint kBsdfThinSheet = 11u;      // thin dielectric slab: specular reflection and straight-through transmission
CONST uint kBsdfMixed = 12u;          // two materials in proportion ratio : 1 - ratio (components 0 and 1)
CONST uint kBsdfTransparency = 13u;   // a base material with opacity alpha; 1 - alpha passes straight through

// Families of non-delta materials a scene may lack (bits of the kSpecBsdfFamilies specialisation
// constant): the path tracer folds out every family the scene does not use.
CONST uint kFamilyRoughConductor = 1u;
CONST uint kFamilyPlastic = 2u;
CONST uint kFamilyRoughPlastic = 4u;
CONST uint kFamilyOrenNayar = 8u;
CONST uint kFamilyRoughDielectric = 16u;
CONST uint kFamilyThinSheet = 32u;     // (these three are delta or composite materials: the path
CONST uint kFamilyMixed = 64u;         // tracer resolves them at the hit, shaders/path_tracer.glsl,
CONST uint kFamilyTransparency = 128u; // and shadow rays pass thin sheets and transparency)
// Materials through which rays pass straight on (shadow rays too): thinsheet and transparency.
CONST uint kFamilyPassThrough = kFamilyThinSheet | kFamilyTransparency;
// Deepest nesting of mixed and transparency materials (a component that is itself one counts one
// level); the scene reader rejects deeper nesting, the shaders' resolution loop stops there.
CONST uint kMaxMaterialNesting = 8u;
CONST uint kFamilyAll = 0xffffffffu;

// Microfacet distributions (Tungsten's "distribution": "beckmann", "phong", "ggx")
CONST uint kMicrofacetBeckmann = 0u;
CONST uint kMicrofacetPhong = 1u;
CONST uint kMicrofacetGGX = 2u;

// ---- Textures (TextureType; Tungsten's "constant", "checker", "bitmap") ----
CONST uint kTextureConstant = 0u;
CONST uint kTextureChecker = 1u;
CONST uint kTextureBitmap = 2u;

// ---- Lights (LightType for the point-like ones; area lights are emissive prims) ----
CONST uint kLightArea = 0u;  // an emissive Prim
CONST uint kLightPoint = 1u;
CONST uint kLightEnvironment = 2u;
CONST uint kLightCap = 3u;  // infinite_sphere_cap: a cone of directions (LightGpu::position, cosCap)

// ---- Participating media (MediumType, PhaseFunction) ----
CONST uint kMediumHomogeneous = 0u;
CONST uint kMediumExponential = 1u;  // density exp(-falloffScale dot(x - unitPoint, falloffDir))
CONST uint kMediumGrid = 2u;         // voxel grid over an affinely placed box (MediumGpu::gridRow*)
CONST uint kPhaseIsotropic = 0u;
CONST uint kPhaseHenyeyGreenstein = 1u;

// ---- Transmittance models (TransmittanceModel::type; Tungsten's "transmittance" type names) ----
CONST uint kTrExponential = 0u;
CONST uint kTrLinear = 1u;             // max_t
CONST uint kTrQuadratic = 2u;          // max_t
CONST uint kTrDoubleExponential = 3u;  // sigma_a, sigma_b
CONST uint kTrErlang = 4u;             // rate
CONST uint kTrDavis = 5u;              // alpha
CONST uint kTrDavisWeinstein = 6u;     // h, c
CONST uint kTrPulse = 7u;              // min, max, num_pulses
CONST uint kTrInterpolated = 8u;       // tr_a, tr_b (simple models), ratio
CONST uint kTrModelCount = 9u;

// ---- Transmittance estimators (TransmittanceEstimatorType) ----
CONST uint kTrEstRayMarch = 0u;              // biased, 2^k jittered points
CONST uint kTrEstDebiasedRayMarch = 1u;      // correlated single-term telescope over levels
CONST uint kTrEstDeltaTracking = 2u;
CONST uint kTrEstRatioTracking = 3u;
CONST uint kTrEstResidualRatioTracking = 4u;
CONST uint kTrEstUnbiasedRayMarch = 5u;      // Kettunen et al. 2021
CONST uint kTrEstTaylor = 6u;                // Taylor series around a comb pivot (Misso et al. 2022)
CONST uint kTrEstCount = 7u;

// ---- Level pmfs (PmfType; "auto" is resolved on the host before any pass sees it) ----
CONST uint kPmfGeometric = 0u;
CONST uint kPmfPowerLaw = 1u;
CONST uint kPmfFixed = 2u;  // shader only, the transmittance pilot: level r, probability alpha

// ---- Path-depth debiasing (DebiasEstimator) ----
CONST uint kDebiasNone = 0u;
CONST uint kDebiasSingleTerm = 1u;
CONST uint kDebiasSum = 2u;

// ---- How per-sample levels are laid out (LevelSchedule; photon blocks use PerPixel and Uniform) ----
CONST uint kLevelSchedulePerPixel = 0u;  // path depth: per sample; photons: each pixel its own block
CONST uint kLevelScheduleUniform = 1u;   // one level per sample index (photons: per block) for all pixels
CONST uint kLevelScheduleQueued = 2u;    // path depth only: (pixel, sample) items sorted by level

// ---- Photon mapping (PhotonKernel; the estimator follows IntegratorType and the debias block) ----
CONST uint kKernelCone = 0u;
CONST uint kKernelUniform = 1u;
CONST uint kKernelEpanechnikov = 2u;
CONST uint kPhotonBiased = 0u;    // K_r at the pass radius (fixed radius, or the PPM schedule)
CONST uint kPhotonUnbiased = 1u;  // blocks: mean K_{r_b} + mean (K_{r_{k+1}} - K_{r_k}) / p(k)

// ---- Reconstruction filters (camera.reconstruction_filter; shared/pixel_filter.h) ----
CONST uint kFilterBox = 0u;
CONST uint kFilterTent = 1u;
CONST uint kFilterDirac = 2u;
CONST uint kFilterGaussian = 3u;
CONST uint kFilterMitchellNetravali = 4u;
CONST uint kFilterCatmullRom = 5u;
CONST uint kFilterLanczos = 6u;

SHADER_NAMESPACE_END

#endif
