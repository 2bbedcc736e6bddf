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
    bool specular = false;      // mirror or dielectric materials
    bool areaLights = false;
    bool pointLights = false;
    bool environment = false;
    uint32_t environmentLight = 0xffffffffu;  // index in the light table
    uint32_t lightCount = 0;
    float sceneExtent = 1.0f;   // bounding-box diagonal of the geometry (1 when empty)
};

struct GpuScene {
    std::vector<shader::Prim> prims;          // BVH leaf order
    std::vector<shader::BvhNode> nodes;
    std::vector<shader::MaterialGpu> materials;
    std::vector<shader::LightGpu> lights;
    SceneFeatures features;
};

// Lights are picked in proportion to their emitted power (luminance of the radiance times
// pi times the area for area lights, 4 pi times the intensity for point lights); the environment
// gets the power of a sphere around the scene.
GpuScene buildGpuScene(const Scene& scene);

}  // namespace telescope
