// The scene as the shaders see it: primitives in BVH leaf order, BVH nodes, materials and the
// light table with its selection distribution. Built on the host, uploaded once.
#pragma once

#include <vector>

#include "scene/bvh.h"
#include "scene/scene.h"
#include "shared/gpu_types.h"

namespace telescope {

struct SceneFeatures {
    bool spheres = false;
    bool disks = false;
    bool specular = false;      // mirror, dielectric or conductor materials
    uint32_t bsdfFamilies = 0;  // shader::kFamily* bits of the glossy materials present
    bool areaLights = false;
    bool pointLights = false;
    bool environment = false;
    uint32_t environmentLight = 0xffffffffu;  // index in the light table
    bool environmentMap = false;              // the environment has an image (kSpecEnvironmentMap)
    uint32_t capLight = 0xffffffffu;          // the infinite_sphere_cap light, index in the light table
    uint32_t lightCount = 0;
    float sceneExtent = 1.0f;   // bounding-box diagonal of the geometry (1 when empty)
    glm::vec3 sceneCentre{0.0f};  // the bounding box's centre: with sceneExtent / 2, a sphere around the geometry
    bool media = false;         // participating media or forward (medium boundary) surfaces
    bool grids = false;         // grid media
    bool inhomogeneous = false; // media whose density varies (exponential falloff or grid)
    uint32_t mediumCount = 0;
    bool fitsUniforms = false;  // nodes and prims fit the path tracer's uniform bindings
    bool tablesFitUniforms = false;  // materials, lights and media fit them too (kSpecTablesInUniforms)
    uint32_t primCount = 0;        // primitive slots (a mesh's triangles count one each)
    uint32_t bruteForcePrims = 0;  // > 0: so few prims (in uniforms) that rays test them all, no BVH
    uint32_t bruteForceCurved = 0; // with bruteForcePrims: bit i set where prim slot i is a sphere or disk
    uint32_t bvhStackNeed = 0;     // the BVH walk's most pending entries (bvhStackNeed)
    bool smoothNormals = false;  // some mesh triangle is smooth-shaded (kSpecSmoothNormals)
    bool interfaces = false;     // some prim is a kPrimInterface (kSpecTieRanks)
    bool textures = false;      // some material has a textured parameter
    uint32_t textureCount = 0;
};

// A plastic's coat reflects this fraction of the cosine-weighted light reaching it from inside
// (2 x the integral of F(mu) mu over [0, 1], total internal reflection included).
double plasticDiffuseFresnel(float ior);

// A material as the shaders see it (diffuseFresnel < 0: computed here for plastics).
shader::MaterialGpu gpuMaterial(const Material& m, double diffuseFresnel = -1.0);

struct GpuScene {
    std::vector<shader::Prim> prims;          // BVH leaf order
    std::vector<shader::BvhNode> nodes;
    std::vector<shader::MaterialGpu> materials;
    std::vector<shader::LightGpu> lights;
    std::vector<shader::MediumGpu> media;    // never empty (a dummy without media)
    std::vector<float> gridData;             // voxels of every grid medium
    std::vector<uint32_t> primMedia;         // per prim slot (shader::kPrimMediaNone or packed)
    std::vector<glm::vec4> textureData;      // shared/texture.h's layout (one dummy vec4 without textures)
    std::vector<float> environment;          // the environment image and its tables (one float without)
    std::vector<glm::vec4> shadingNormals;   // 3 per prim slot with smooth triangles, else one dummy
    SceneFeatures features;
};

// The largest texture buffer: one storage-buffer binding (maxStorageBufferRange, 128 MiB on lavapipe).
constexpr uint64_t kMaxTextureBytes = uint64_t(128) << 20;

// Lights are picked in proportion to their emitted power (luminance of the radiance times
// pi times the area for area lights, 4 pi times the intensity for point lights); the environment
// gets the power of a sphere around the scene.
GpuScene buildGpuScene(const Scene& scene);

// A medium as the shaders see it; a grid's voxels (times the density) are appended to gridData.
shader::MediumGpu mediumToGpu(const Medium& m, std::vector<float>& gridData);

}  // namespace telescope
