// The scene's geometry for the ray queries of shared/intersect.h (GLSL only; after the storage
// buffers prims[] and nodes[]): BVH nodes and primitives read from uniform buffers when they fit
// (kSpecSceneInUniforms: lavapipe loads from a uniform buffer about 1.8x as fast as from a storage
// buffer), and tiny scenes tested primitive by primitive without the BVH (kSpecBruteForcePrims).
// Included by path_trace_main.glsl and photon_scene.glsl.

layout(constant_id = kSpecSceneInUniforms) const bool kSceneInUniforms = false;
layout(std140, binding = kBindingBvhUniform) uniform BvhUniform { BvhNode uniformNodes[kMaxUniformNodes]; };
layout(std140, binding = kBindingPrimsUniform) uniform PrimUniform { Prim uniformPrims[kMaxUniformPrims]; };

// (Functions, not ?: : the uniform and storage structs are distinct SPIR-V types.)
BvhNode sceneNode(uint i) {
    if (kSceneInUniforms) return uniformNodes[i];
    return nodes[i];
}
Prim scenePrim(uint i) {
    if (kSceneInUniforms) return uniformPrims[i];
    return prims[i];
}
#define BVH_NODE(i) sceneNode(i)
#define BVH_PRIM(i) scenePrim(i)
layout(constant_id = kSpecBruteForcePrims) const uint kBruteForcePrims = 0u;
#define BVH_BRUTE_FORCE_PRIMS kBruteForcePrims
#include "shared/intersect.h"
