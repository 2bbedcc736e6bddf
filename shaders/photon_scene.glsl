// Scene access shared by photon_trace.comp and gather.comp (GLSL only): the scene buffers, the
// scene switches (same specialisation ids as path_trace), ray offsets, emission, light picking,
// the materials (shared/bsdf.h, textures, mixed), and the photon map reached by device address. The geometry comes through
// scene_geometry.glsl: photon_trace reads it from uniform buffers when it fits and skips the BVH in
// tiny scenes, as the path tracer does; the host turns both off for the gather (measured slower
// there). The bindings keep the path tracer's numbers; 4-6 (media) hold the gather's sorted photons.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

#define BSDF_FAMILIES kBsdfFamilies  // shared/bsdf.h: the glossy families this scene uses

layout(std430, binding = kBindingPrims) readonly buffer PrimBuffer { Prim prims[]; };
layout(std430, binding = kBindingBvh) readonly buffer BvhBuffer { BvhNode nodes[]; };
layout(std430, binding = kBindingMaterials) readonly buffer MaterialBuffer { MaterialGpu materials[]; };
layout(std430, binding = kBindingLights) readonly buffer LightBuffer { LightGpu lights[]; };
layout(std430, binding = kBindingTextures) readonly buffer TextureBuffer { vec4 textureData[]; };
// The environment image and its sampling tables (shared/environment_map.h), read only when the
// environment light has one.
layout(std430, binding = kBindingEnvironment) readonly buffer EnvironmentBuffer { float envData[]; };
#define ENV_DATA(i) envData[i]
#include "shared/environment_map.h"

#define SCENE_UNIFORM_INDEX_HIDDEN  // scene_geometry.glsl: no shader compiled again per pass
#include "scene_geometry.glsl"

// The materials and lights as uniform buffers when they fit (kSpecTablesInUniforms, as in the
// path tracer), with the hidden zero of scene_geometry.glsl in the index: a light read at a
// constant index (one light; the environment light) must not be folded into the shader.
layout(std140, binding = kBindingMaterialsUniform) uniform MaterialUniform { MaterialGpu uniformMaterials[kMaxUniformMaterials]; };
layout(std140, binding = kBindingLightsUniform) uniform LightUniform { LightGpu uniformLights[kMaxUniformLights]; };
MaterialGpu sceneMaterial(uint i) {
    if (kTablesInUniforms) return uniformMaterials[uniformIndex(i)];
    return materials[i];
}
LightGpu sceneLight(uint i) {
    if (kTablesInUniforms) return uniformLights[uniformIndex(i)];
    return lights[i];
}

layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonMapRef { PhotonMapHeader h; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer PhotonArrayRef { Photon p[]; };
layout(buffer_reference, std430, buffer_reference_align = 4) buffer UintArrayRef { uint v[]; };

#include "scene_common.glsl"
