// The table of shader features: every specialisation constant of every pipeline, once.
//
// One row per constant: X(id name, id, GLSL type, GLSL name, default, why). From this table
//   - the shaders get their declarations, `layout(constant_id = id) const type name = default;`
//     (the only constant_id declarations in shaders/: each pass includes shared/gpu_types.h, which
//     includes this file; a pipeline ignores the rows it does not read),
//   - the host gets the ids (shader::kSpec...) and kSpecConstantTable (id, name, type, why), from
//     which `telescope plan` prints each pipeline's specialisation,
// so a new feature switch is one row here, its value in the pass's spec list (render/*_passes.cpp)
// and its use in a shader. The host folds the values into the SPIR-V before pipeline creation
// (gpu/pipeline.h specialiseSpirv): features a scene lacks are compiled out.
//
// Ids 0..31: the scene and the path tracer; 32..47: participating media (shaders/medium.glsl);
// 48..63: photon mapping (photon_trace, hash_grid_build, gather), which also read the scene's
// switches. Defaults are what a shader compiled without specialisation would assume; every
// pipeline the host builds sets the rows it reads.
#ifndef TELESCOPE_SPEC_CONSTANTS_H
#define TELESCOPE_SPEC_CONSTANTS_H

// clang-format off
#define TELESCOPE_SPEC_CONSTANTS(X) \
    X(kSpecMaxBounces,        0, uint,  kMaxBounces,       64u,         "the path tracer's base level k = max_bounces - 1") \
    X(kSpecMinBounces,        1, uint,  kMinBounces,       0u,          "bounces before Russian roulette may end a path") \
    X(kSpecDebiasMode,        2, uint,  kDebiasMode,       0u,          "path-depth debiasing: none, single-term or Russian-roulette sum") \
    X(kSpecPmfType,           3, uint,  kPmfType,          0u,          "the path-depth level pmf (kPmf*)") \
    X(kSpecPmfR,              4, float, kPmfR,             0.65,        "the level pmf's ratio r (geometric)") \
    X(kSpecPmfAlpha,          5, float, kPmfAlpha,         0.6666667,   "the level pmf's exponent alpha (power law)") \
    X(kSpecHasSpheres,        6, bool,  kHasSpheres,       true,        "sphere primitives present") \
    X(kSpecHasDisks,          7, bool,  kHasDisks,         true,        "disk primitives present") \
    X(kSpecHasSpecular,       8, bool,  kHasSpecular,      true,        "mirror, dielectric or conductor materials present") \
    X(kSpecLightCount,        9, uint,  kLightCount,       0u,          "lights in the light table") \
    X(kSpecLightSampling,    10, bool,  kLightSampling,    true,        "next-event estimation (enable_light_sampling and some light)") \
    X(kSpecTwoSided,         11, bool,  kTwoSided,         true,        "two-sided shading (enable_two_sided_shading)") \
    X(kSpecFilter,           12, uint,  kFilter,           kFilterTent, "the camera's reconstruction filter (kFilter*)") \
    X(kSpecEnvironmentLight, 13, uint,  kEnvironmentLight, 0xffffffffu, "the infinite_sphere light's index, or 0xffffffff for none") \
    X(kSpecMaxTraceDepth,    14, uint,  kMaxTraceDepth,    4096u,       "rays per path at most (kTraceDepthCap or beyond the base level)") \
    X(kSpecRayEpsilon,       15, float, kRayEpsilon,       1e-5,        "absolute ray offset, from the scene's size") \
    X(kSpecPilot,            16, bool,  kPilot,            false,       "pmf pilot: every sample takes the level pc.pilotLevel") \
    X(kSpecLevelSchedule,    17, uint,  kLevelSchedule,    kLevelSchedulePerPixel, "how per-sample levels are laid out on lanes (kLevelSchedule*)") \
    X(kSpecTestPmfWeight,    18, float, kTestPmfWeight,    1.0,         "test only: scales every 1 / p(j) (debias.test_pmf_weight)") \
    X(kSpecSceneInUniforms,  19, bool,  kSceneInUniforms,  false,       "BVH nodes and primitives read from the uniform bindings") \
    X(kSpecCapLight,         20, uint,  kCapLight,         0xffffffffu, "the infinite_sphere_cap light's index, or 0xffffffff for none") \
    X(kSpecBsdfFamilies,     21, uint,  kBsdfFamilies,     kFamilyAll,  "kFamily* bits: the non-delta material families present") \
    X(kSpecHasTextures,      22, bool,  kHasTextures,      false,       "some material has a texture (uvs are computed at its hits)") \
    X(kSpecEnvironmentMap,   23, bool,  kEnvironmentMap,   false,       "the environment light has an image") \
    X(kSpecTablesInUniforms, 24, bool,  kTablesInUniforms, false,       "materials, lights and media read from the uniform bindings") \
    X(kSpecSmoothNormals,    25, bool,  kSmoothNormals,    false,       "some triangle is smooth-shaded: read kBindingShadingNormals") \
    X(kSpecLoopBudget,       26, uint,  kLoopBudget,       0u,          "loop iterations a path_trace lane may run per dispatch (0: no limit)") \
    X(kSpecSceneTexels,      27, bool,  kSceneTexels,      false,       "the scene read from the texel bindings, not from storage buffers") \
    X(kSpecTieRanks,         31, bool,  kTieRanks,         true,        "some primitive is an interface (kPrimInterface) that a coincident surface hides") \
    X(kSpecBvhStackNeed,     30, uint,  kBvhStackNeed,     0u,          "n > 0: a BVH walk never holds more than n pending entries (its stack lives in registers)") \
    X(kSpecPointLights,      29, bool,  kHasPointLights,   true,        "point lights present") \
    X(kSpecBruteForceCurved, 28, uint,  kBruteForceCurved, 0u,          "brute-force rays: bit i set where primitive slot i is a sphere or disk (tested apart from the planar ones)") \
    X(kSpecHasMedia,         32, bool,  kHasMedia,         false,       "media or forward (index-matched) boundaries present") \
    X(kSpecTrEstimator,      33, uint,  kTrEstimatorType,  1u,          "the transmittance estimator (kTrEst*, shared/transmittance_estimators.h)") \
    X(kSpecTrLevel,          34, uint,  kTrLevel,          1u,          "ray marching's base level: 2^level points") \
    X(kSpecTrPmfType,        35, uint,  kTrPmfType,        0u,          "debiased marching's level pmf (kPmf*)") \
    X(kSpecTrPmfR,           36, float, kTrPmfR,           0.65,        "that pmf's ratio r") \
    X(kSpecTrPmfAlpha,       37, float, kTrPmfAlpha,       0.6666667,   "that pmf's exponent alpha") \
    X(kSpecCameraMedium,     38, uint,  kCameraMedium,     0u,          "the camera's medium index + 1, 0 = vacuum") \
    X(kSpecHasGrids,         39, bool,  kHasGrids,         false,       "voxel grid media present") \
    X(kSpecTrModels,         40, uint,  kSceneTrModels,    0x1ffu,      "bit t set: some medium uses transmittance model t (kTr*; interpolated sets its two models' bits too)") \
    X(kSpecHasInhomogeneousMedia, 41, bool, kHasInhomogeneous, true,    "a medium whose density varies (exponential or grid)") \
    X(kSpecBruteForcePrims,  42, uint,  kBruteForcePrims,  0u,          "n > 0: rays test the scene's n primitives in turn, no BVH") \
    X(kSpecTrTaylorTerms,    43, uint,  kTrTaylorTerms,    1u,          "taylor: terms evaluated before the roulette") \
    X(kSpecTrTaylorPoints,   44, uint,  kTrTaylorPoints,   0u,          "taylor: points of each factor's comb (0: from the density bounds)") \
    X(kSpecRoulette,         45, bool,  kRoulette,         true,        "Russian roulette on path throughput (off in derivative renders)") \
    X(kSpecTrPilot,          46, bool,  kTrPilot,          false,       "transmittance pmf pilot: debiased marching at the level pc.pilotLevel") \
    X(kSpecGreyMedia,        47, bool,  kGreyMedia,        false,       "every medium's sigma_t is grey (three equal channels): one transmittance serves all three") \
    X(kSpecPhotonEstimator,  48, uint,  kEstimator,        kPhotonBiased, "photon mapping: kPhotonBiased or kPhotonUnbiased") \
    X(kSpecPhotonKernel,     49, uint,  kKernel,           kKernelCone, "the gather kernel: kKernelCone, kKernelUniform, kKernelEpanechnikov") \
    X(kSpecPhotonSchedule,   50, uint,  kSchedule,         kLevelScheduleUniform, "how block levels are drawn: per pixel or per block index") \
    X(kSpecPhotonGatherCount, 51, uint, kGatherCount,      0u,          "k > 0: the k nearest photons within the radius (gather_photon_count); 0: all within r") \
    X(kSpecPhotonRadianceScaling, 52, bool, kRadianceScaling, true,     "1 / eta^2 on the camera side at refraction (off only in a test's control)") \
    X(kSpecPhotonNextEvent,  53, bool,  kNextEvent,        true,        "direct light by next-event estimation, not photons") \
    X(kSpecGridStage,        54, uint,  kStage,            kGridStageCount, "hash_grid_build: which stage this pipeline runs (kGridStage*)") \
    X(kSpecPhotonMaxBounces, 55, uint,  kPhotonMaxBounces, 64u,         "scattering vertices of a photon path or camera chain") \
    X(kSpecSortedTexels,     56, bool,  kSortedTexels,     true,        "the gather reads the sorted photons as texels (1) or by address (0)") \
    X(kSpecPhotonTestCosine, 57, bool,  kTestCosine,       false,       "test only: glossy gathers weight photons by f |cos| (a control)") \
    X(kSpecGatherSliceLength, 58, uint, kGatherSliceLength, kGatherSlicePhotons, "photons of each bucket one gather dispatch reads (PhotonMap::sliceLength)")
// clang-format on

#ifdef __cplusplus
SHADER_NAMESPACE_BEGIN
#define TELESCOPE_SPEC_ID(idName, id, type, name, fallback, why) CONST uint idName = id##u;
TELESCOPE_SPEC_CONSTANTS(TELESCOPE_SPEC_ID)
#undef TELESCOPE_SPEC_ID

struct SpecConstantInfo {
    uint id;
    const char* name;  // the GLSL name
    const char* type;  // uint, bool or float
    const char* why;
};
#define TELESCOPE_SPEC_ROW(idName, id, type, name, fallback, why) SpecConstantInfo{id##u, #name, #type, why},
CONST SpecConstantInfo kSpecConstantTable[] = {TELESCOPE_SPEC_CONSTANTS(TELESCOPE_SPEC_ROW)};
#undef TELESCOPE_SPEC_ROW

// The row of an id, or nullptr.
FN const SpecConstantInfo* specConstantInfo(uint id) {
    for (const SpecConstantInfo& row : kSpecConstantTable)
        if (row.id == id) return &row;
    return nullptr;
}

// Two rows with one id would make two features one: checked at compile time.
FN constexpr bool specIdsUnique() {
    constexpr uint n = uint(sizeof(kSpecConstantTable) / sizeof(kSpecConstantTable[0]));
    for (uint i = 0; i < n; ++i)
        for (uint j = i + 1; j < n; ++j)
            if (kSpecConstantTable[i].id == kSpecConstantTable[j].id) return false;
    return true;
}
static_assert(specIdsUnique(), "two rows of TELESCOPE_SPEC_CONSTANTS share an id");
SHADER_NAMESPACE_END
#else
#define TELESCOPE_SPEC_DECLARATION(idName, id, type, name, fallback, why) \
    layout(constant_id = id) const type name = fallback;
TELESCOPE_SPEC_CONSTANTS(TELESCOPE_SPEC_DECLARATION)
#undef TELESCOPE_SPEC_DECLARATION
#endif

#endif
