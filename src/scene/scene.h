// Scene model: what a Tungsten scene file becomes once loaded, in world space.
//
// The loader (scene_loader.h) follows Tungsten's conventions (transform order, quad orientation,
// power -> radiance) and flattens every shape into the geometric primitives the GPU traces:
// triangles, spheres and disks. Lights are listed separately: every emissive primitive is one
// area light, plus point lights and a constant environment.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "shared/enums.h"  // the values of every enum below: one definition for host and shaders

namespace telescope {

enum class BsdfType : uint32_t {
    Lambert = shader::kBsdfLambert, Mirror = shader::kBsdfMirror, Dielectric = shader::kBsdfDielectric,
    Null = shader::kBsdfNull, Forward = shader::kBsdfForward, Conductor = shader::kBsdfConductor,
    RoughConductor = shader::kBsdfRoughConductor, Plastic = shader::kBsdfPlastic, RoughPlastic = shader::kBsdfRoughPlastic,
    OrenNayar = shader::kBsdfOrenNayar, RoughDielectric = shader::kBsdfRoughDielectric,
    ThinSheet = shader::kBsdfThinSheet, Mixed = shader::kBsdfMixed, Transparency = shader::kBsdfTransparency
};

// A texture on a material parameter (Tungsten's constant, checker and bitmap; shared/texture.h).
enum class TextureType : uint32_t {
    Constant = shader::kTextureConstant, Checker = shader::kTextureChecker, Bitmap = shader::kTextureBitmap
};

struct Texture {
    TextureType type = TextureType::Constant;
    std::string key;              // where it was defined ("bsdfs[0].albedo"), for messages
    glm::vec3 on{0.8f};           // constant: the value; checker: on_color; bitmap: scale
    glm::vec3 off{0.2f};          // checker: off_color
    uint32_t resU = 20, resV = 20;  // checker: res_u, res_v; bitmap: width, height
    bool interpolate = true;      // bitmap: bilinear, else nearest
    bool clamp = false;           // bitmap: clamp at the edges, else wrap
    bool gammaCorrect = true;     // bitmap: 8-bit (LDR) files are sRGB, converted to linear
    std::vector<glm::vec4> texels;  // bitmap: linear RGBA, row-major from the top row
};

struct Material {
    std::string name;
    std::string key;               // where it was defined ("bsdfs[2]"), for messages
    BsdfType type = BsdfType::Lambert;
    glm::vec3 albedo{1.0f};
    float ior = 1.5f;              // dielectrics and plastics
    bool enableRefraction = true;  // dielectrics only
    // Microfacet materials: roughness and distribution (shader::kMicrofacet*); conductors: the
    // complex index eta + i k (Tungsten's defaults: copper, GGX, roughness 0.1).
    float roughness = 0.1f;
    uint32_t distribution = shader::kMicrofacetGGX;
    glm::vec3 eta{0.2004376970f, 0.9240334304f, 1.1022119527f};
    glm::vec3 k{3.9129485033f, 2.4528477015f, 2.1421879552f};
    // Plastics: the coat's thickness and absorption (Tungsten's defaults 1 and 0).
    float thickness = 1.0f;
    glm::vec3 sigmaA{0.0f};
    // Textured parameters: index into Scene::textures, -1 = the constant above.
    int32_t albedoTexture = -1;
    int32_t roughnessTexture = -1;
    // thinsheet (thickness, sigmaA above; Tungsten's thickness default is 0.5)
    bool enableInterference = false;
    // mixed: bsdf0 and bsdf1, ratio = the weight of bsdf0; transparency: component[0] = base,
    // alpha = opacity. Indices into Scene::materials once the scene is loaded.
    uint32_t component[2] = {0, 0};
    float ratio = 0.5f;
    float alpha = 1.0f;
};

enum class GeometryType : uint32_t {
    Triangle = shader::kPrimTriangle, Sphere = shader::kPrimSphere, Disk = shader::kPrimDisk, Quad = shader::kPrimQuad
};

// One ray-traceable primitive in world space.
struct Geometry {
    GeometryType type = GeometryType::Triangle;
    glm::vec3 p0{0.0f}, p1{0.0f}, p2{0.0f};  // triangle vertices; quad: a corner and its two
                                             // neighbours; sphere/disk: p0 = centre
    float radius = 0.0f;                     // sphere, disk
    glm::vec3 normal{0.0f, 1.0f, 0.0f};      // unit geometric normal (triangle, quad, disk); the
                                             // emitting side for one-sided emission
    uint32_t material = 0;                   // index into Scene::materials
    glm::vec3 emission{0.0f};                // radiance, already converted from "power"
    uint32_t shape = 0;                      // index into Scene::shapes (the source primitive)
    // Tungsten's uv parameterisation (shared/texture.h primUv): triangle and quad: the uvs of
    // p0, p1, p2; sphere: the world-to-local rotation's rows x, y in uvFrame[0], [1]; disk:
    // Tungsten's bitangent and tangent in uvFrame[0], [1].
    glm::vec2 uv[3] = {glm::vec2(0.0f), glm::vec2(0.0f), glm::vec2(0.0f)};
    glm::vec3 uvFrame[2] = {glm::vec3(1.0f, 0.0f, 0.0f), glm::vec3(0.0f, 1.0f, 0.0f)};
    // Media on the two sides (index into Scene::media, -1 = vacuum); used only if hasMedia
    // (a primitive without int_medium / ext_medium leaves the current medium unchanged).
    bool hasMedia = false;
    int32_t intMedium = -1, extMedium = -1;
    // A smooth-shaded mesh triangle (Tungsten's "smooth"): unit world-space normals at p0, p1, p2,
    // interpolated at a hit for the shading normal; the geometric normal stays `normal`.
    bool smooth = false;
    glm::vec3 vertexNormal[3] = {glm::vec3(0.0f), glm::vec3(0.0f), glm::vec3(0.0f)};
};

// ---- Participating media (docs/MEDIA.md) ----
enum class MediumType : uint32_t {
    Homogeneous = shader::kMediumHomogeneous, Exponential = shader::kMediumExponential, Grid = shader::kMediumGrid
};
enum class PhaseFunction : uint32_t { Isotropic = shader::kPhaseIsotropic, HenyeyGreenstein = shader::kPhaseHenyeyGreenstein };

// A transmittance model (shaders/shared/transmittance.h: kTr* types and their parameters).
// Interpolated: typeA/paramsA and typeB/paramsB are the two models, mixed by ratio.
struct TransmittanceModel {
    uint32_t type = 0;
    glm::vec4 params{0.0f};
    uint32_t typeA = 0, typeB = 0;
    glm::vec4 paramsB{0.0f};
    float ratio = 0.5f;
    std::string name = "exponential";
    bool exponential() const { return type == shader::kTrExponential; }
};

struct DensityGrid {
    glm::uvec3 resolution{0};
    std::vector<float> density;  // x fastest
    // Emission per unit length (3 floats per voxel, x fastest; empty = none), emission_scale
    // applied; times the density where emissionByDensity (Tungsten's scale_emission_by_density).
    std::vector<float> emission;
    bool emissionByDensity = false;
    bool nearest = false;        // nearest-voxel lookups (Tungsten's exact_nearest), else trilinear
    // The unit box [0, 1]^3 (voxel centres at (i + 1/2) / res) to world space, affine.
    glm::mat4 unitToWorld{1.0f};
    // Majorant grid: cells of majorantCell^3 voxels (0 = one majorant for the whole grid).
    uint32_t majorantCell = 8;
    // Test hook (not read from scenes): false builds the majorant cells from their own voxels only,
    // ignoring the neighbours a trilinear lookup reads: a wrong (too small) majorant on purpose.
    bool majorantCoversStencil = true;
    std::string source;          // "procedural_cloud", "constant", "linear", "vdb"
};

struct Medium {
    std::string name;
    MediumType type = MediumType::Homogeneous;
    glm::vec3 sigmaA{0.0f}, sigmaS{0.0f};
    float density = 1.0f;
    float falloffScale = 1.0f;                   // exponential
    glm::vec3 unitPoint{0.0f};                   // exponential
    glm::vec3 falloffDirection{0.0f, 1.0f, 0.0f};  // exponential, unit
    DensityGrid grid;                            // grid
    PhaseFunction phase = PhaseFunction::Isotropic;
    float phaseG = 0.0f;
    TransmittanceModel transmittance;
    uint32_t maxBounces = 1024;  // "max_bounces": Tungsten's per-medium limit (docs/MEDIA.md)
};

enum class TransmittanceEstimatorType : uint32_t {
    RayMarch = shader::kTrEstRayMarch, DebiasedRayMarch = shader::kTrEstDebiasedRayMarch,
    DeltaTracking = shader::kTrEstDeltaTracking, RatioTracking = shader::kTrEstRatioTracking,
    ResidualRatioTracking = shader::kTrEstResidualRatioTracking, UnbiasedRayMarch = shader::kTrEstUnbiasedRayMarch,
    Taylor = shader::kTrEstTaylor
};
const char* transmittanceEstimatorName(TransmittanceEstimatorType t);
// The trackers and Kettunen et al.'s unbiased ray marching estimate exp(-tau) only: they need
// exponential media (the reader refuses them elsewhere; the transmittance study skips those models).
inline bool estimatesExponentialOnly(TransmittanceEstimatorType t) {
    return t == TransmittanceEstimatorType::DeltaTracking || t == TransmittanceEstimatorType::RatioTracking ||
           t == TransmittanceEstimatorType::ResidualRatioTracking || t == TransmittanceEstimatorType::UnbiasedRayMarch;
}

enum class LightType : uint32_t { Point = shader::kLightPoint, Environment = shader::kLightEnvironment, Cap = shader::kLightCap };

// Non-geometric emitters (area lights are the emissive Geometry entries).
// The image of an infinite_sphere's emission (Tungsten's BitmapTexture; shaders/shared/environment_map.h).
struct EnvironmentImage {
    uint32_t width = 0, height = 0;
    std::vector<float> rgb;    // 3 floats a texel, row 0 the top of the image (the +y pole)
    float scale = 1.0f;        // `scale` (and power -> radiance)
    bool interpolate = true;   // `interpolate`: bilinear lookups
    bool clamp = false;        // `clamp`: clamp lookups at the edges, else wrap
    std::string file;          // as resolved, for messages
};

struct PointLikeLight {
    LightType type = LightType::Point;
    glm::vec3 position{0.0f};     // point
    glm::vec3 intensity{0.0f};    // point: radiant intensity (W/sr); environment, cap: radiance
    glm::vec3 direction{0.0f, 1.0f, 0.0f};  // cap: the cone's axis (unit; light arrives from it)
    float cosCap = -1.0f;                    // cap: cosine of the cone's half angle
    // environment with an image: the image (intensity: its mean radiance) and the rotation part
    // of the primitive's transform (local -> world)
    std::shared_ptr<const EnvironmentImage> image;
    glm::mat3 rotation{1.0f};
    std::string name;
};

// The camera's reconstruction filter (shared/pixel_filter.h; values from shared/enums.h).
enum class PixelFilter : uint32_t {
    Box = shader::kFilterBox, Tent = shader::kFilterTent, Dirac = shader::kFilterDirac,
    Gaussian = shader::kFilterGaussian, MitchellNetravali = shader::kFilterMitchellNetravali,
    CatmullRom = shader::kFilterCatmullRom, Lanczos = shader::kFilterLanczos
};

struct Camera {
    glm::vec3 position{0.0f, 0.0f, 0.0f};
    glm::vec3 forward{0.0f, 0.0f, 1.0f};  // unit, z axis of Tungsten's camera basis
    glm::vec3 up{0.0f, 1.0f, 0.0f};       // unit, y axis
    glm::vec3 right{1.0f, 0.0f, 0.0f};    // unit, image right = forward x up (Tungsten)
    float fovDegrees = 60.0f;             // horizontal full angle
    uint32_t width = 512, height = 512;
    PixelFilter filter = PixelFilter::Tent;  // reconstruction filter (names: scene/enum_names.h)
    int32_t medium = -1;                  // index into Scene::media, -1 = vacuum
};

// Settings of the debiasing telescope (docs/ESTIMATORS.md sections 1-2).
// Auto: chosen by a pilot render before the render proper (src/render/pmf_pilot.h); the shaders
// only ever see Geometric or PowerLaw.
enum class PmfType : uint32_t { Geometric = shader::kPmfGeometric, PowerLaw = shader::kPmfPowerLaw, Auto = 0x7fffffff /* host only */ };
enum class DebiasEstimator : uint32_t { None = shader::kDebiasNone, SingleTerm = shader::kDebiasSingleTerm, Sum = shader::kDebiasSum };

struct PmfSettings {
    PmfType type = PmfType::Geometric;
    float r = 0.65f;      // geometric: p(m) = r (1-r)^m
    float alpha = 2.0f / 3.0f;  // power law: P(N >= m) = (m+1)^(alpha-1)
    uint32_t pilotSpp = 4;      // auto: samples per pixel of each pilot level
    uint32_t pilotLevels = 8;   // auto: levels measured by the pilot (the tail is fitted)
    std::string origin = "given in the scene";  // why this pmf: the scene, a default and its reason, the pilot
};

// The pmf a telescope gets when its block names none, per application (docs/ESTIMATORS.md
// section 1, "Defaults"). The photon default is set where photon mapping reads its block.
PmfSettings defaultPathDepthPmf();
PmfSettings defaultTransmittancePmf();

// How per-sample levels are laid out on the device's lanes (shared/gpu_types.h kLevelSchedule*).
enum class LevelSchedule : uint32_t {
    PerPixel = shader::kLevelSchedulePerPixel, Uniform = shader::kLevelScheduleUniform, Queued = shader::kLevelScheduleQueued
};

// Photon mapping's blocks (docs/PHOTON-MAPPING.md, scene/photon_levels.h): level k of a block
// has kernel area s^k times the base and m^k photon passes; levels k < K.
struct PhotonBlockSettings {
    float areaRatio = 0.70710678f;  // s ("area_ratio")
    uint32_t photonGrowth = 3;      // m ("photon_growth")
    uint32_t levelCap = 20;         // K ("level_cap"; the loader's default: s^K < 1e-3)
};

struct DebiasSettings {
    DebiasEstimator estimator = DebiasEstimator::None;
    PmfSettings pmf = defaultPathDepthPmf();
    LevelSchedule schedule = LevelSchedule::PerPixel;  // photon mapping: Uniform or PerPixel
    PhotonBlockSettings photon;                        // photon mapping only
    // Test-only ("test_pmf_weight"): every 1 / p(j) is multiplied by this, a deliberately biased
    // estimator for the positive controls of the unbiasedness tests. 1 in any real render.
    float testPmfWeight = 1.0f;
};

enum class IntegratorType : uint32_t { PathTracer = 0, PhotonMap = 1, ProgressivePhotonMap = 2 };

// Photon mapping (docs/ESTIMATORS.md section 3). Tungsten's key names where Tungsten has the setting.
enum class PhotonKernel : uint32_t { Cone = shader::kKernelCone, Uniform = shader::kKernelUniform, Epanechnikov = shader::kKernelEpanechnikov };
enum class DirectLighting : uint32_t { Photons = 0, NextEvent = 1 };

struct PhotonSettings {
    uint32_t photonCount = 1000000;   // photon paths emitted per pass ("photon_count")
    float gatherRadius = 0.0f;        // r_1 (unbiased), r (biased), r_0 (progressive); "gather_radius"
    float alpha = 2.0f / 3.0f;        // progressive radius schedule (Knaus & Zwicker); "alpha"
    PhotonKernel kernel = PhotonKernel::Cone;             // "kernel"
    DirectLighting directLighting = DirectLighting::NextEvent;  // "direct_lighting"
    // "gather_photon_count": k > 0 gathers the k nearest photons within the radius, with the kernel
    // radius r_k their farthest distance (Tungsten's gather); 0 gathers every photon within the
    // radius. Biased and progressive photon mapping only (the debias block needs nested kernels).
    uint32_t gatherCount = 0;
    // Test-only ("test_radiance_scaling"): false drops the 1/eta^2 of a refraction on the camera
    // side, the old, wrong transport (the positive control of the refraction tests).
    bool testRadianceScaling = true;
    // Test-only ("test_gather_cosine"): true weights each photon at a glossy gather vertex by
    // f |cos wo| instead of f (the cosine counted twice: the positive control of the glossy tests).
    bool testGatherCosine = false;
    // Test-only ("test_coincident_surfaces"): false lets the photon passes resolve coincident
    // surfaces by the order their walks meet them, the old rule (shared/intersect.h "Coincident
    // surfaces"): the positive control of the refraction geometry tests.
    bool testCoincidentSurfaces = true;
};
// "transmittance_estimator": {"type": ..., "level": k, "pmf": {...}} (docs/MEDIA.md).
struct TransmittanceEstimatorSettings {
    TransmittanceEstimatorType type = TransmittanceEstimatorType::DebiasedRayMarch;
    uint32_t level = 1;  // ray marching: 2^k points; debiased: the base level k; taylor: the pivot's 2^k points
    PmfSettings pmf = defaultTransmittancePmf();  // debiased: geometric or power law (levels above k)
    uint32_t terms = 1;   // taylor: terms always evaluated before the roulette
    uint32_t points = 0;  // taylor: points of each factor's comb; 0 = from the segment's density bounds
};


struct IntegratorSettings {
    IntegratorType type = IntegratorType::PathTracer;
    uint32_t minBounces = 0;
    uint32_t maxBounces = 64;
    bool enableLightSampling = true;
    bool enableTwoSidedShading = true;
    DebiasSettings debias;
    PhotonSettings photon;  // photon_map and progressive_photon_map only
    // "transmittance_estimator": how every transmittance factor of a path is estimated.
    TransmittanceEstimatorSettings transmittance;
    // Not a scene key: derivative renders (render/derivative.h) turn Russian roulette off, whose
    // survival decisions depend on the throughput and so on the parameter being varied.
    bool russianRoulette = true;
};

inline bool usesPhotons(const IntegratorSettings& s) { return s.type != IntegratorType::PathTracer; }

// Whether the path-depth pmf, and debiased ray marching's pmf, are "auto" in settings that use
// them: what a pilot resolves (render/pmf_pilot.h resolveScene).
inline bool debiasPmfIsAuto(const IntegratorSettings& s) {
    return s.debias.estimator != DebiasEstimator::None && s.debias.pmf.type == PmfType::Auto;
}
inline bool transmittancePmfIsAuto(const IntegratorSettings& s) {
    return s.transmittance.type == TransmittanceEstimatorType::DebiasedRayMarch && s.transmittance.pmf.type == PmfType::Auto;
}

// The scene key of a pmf "auto" that a pilot has not yet resolved, or "" when there is none: the
// path-depth pmf first, then the transmittance's.
inline const char* autoPmfKey(const IntegratorSettings& s) {
    if (debiasPmfIsAuto(s)) return "integrator.debias.pmf.type";
    if (transmittancePmfIsAuto(s)) return "integrator.transmittance_estimator.pmf.type";
    return "";
}

// The path tracer's depth k: I(k) holds the light of paths with at most k scattering vertices
// (surface bounces, forward-boundary crossings and medium scattering events). Tungsten's
// max_bounces counts the light connection too (PathTracer.cpp: next-event estimation runs while
// bounce < max_bounces - 1; at max_bounces 1 only emitters show), so k = max_bounces - 1. The
// reader rejects max_bounces 0 for the path tracer (Tungsten renders nothing).
inline uint32_t pathDepthK(const IntegratorSettings& s) { return s.maxBounces > 0 ? s.maxBounces - 1 : 0; }

struct RendererSettings {
    uint32_t spp = 32;
};

struct Shape {  // the source primitive, for messages and stats
    std::string name;
    std::string type;
};

struct Scene {
    std::string path;                 // file it was loaded from
    nlohmann::json document;          // the (overridden) JSON, for output metadata
    std::vector<Material> materials;
    std::vector<Texture> textures;    // of material parameters
    std::vector<Geometry> geometry;
    std::vector<PointLikeLight> lights;
    std::vector<Shape> shapes;
    std::vector<Medium> media;
    Camera camera;
    IntegratorSettings integrator;
    RendererSettings renderer;
    std::vector<std::string> ignoredKeys;  // JSON paths read but not used, reported once
};

}  // namespace telescope
