// The scene's geometry for the ray queries of shared/intersect.h (GLSL only; after the storage
// buffers prims[] and nodes[]): BVH nodes and primitives read from uniform buffers when they fit
// (kSpecSceneInUniforms: lavapipe loads from a uniform buffer about 1.8x as fast as from a storage
// buffer), else from uniform texel buffers when the device's texel limit allows (kSpecSceneTexels:
// lavapipe fetches the 8 lanes' texels with vector loads, where a divergent storage-buffer load
// loops over the lanes once per component), else from the storage buffers; tiny scenes are tested
// primitive by primitive without the BVH (kSpecBruteForcePrims).
// Included by path_trace_main.glsl and photon_scene.glsl.

layout(std140, binding = kBindingBvhUniform) uniform BvhUniform { BvhNode uniformNodes[kMaxUniformNodes]; };
layout(std140, binding = kBindingPrimsUniform) uniform PrimUniform { Prim uniformPrims[kMaxUniformPrims]; };
layout(binding = kBindingBvhTexels) uniform usamplerBuffer bvhTexels;
layout(binding = kBindingPrimsTexels) uniform usamplerBuffer primTexels;

// Lavapipe (Mesa 22.3) inlines uniform-buffer values read at constant offsets that decide a
// branch: each time such a pipeline is bound it compiles a new shader with the values folded in,
// and never frees it, as long as the folding removes half of the shader. photon_trace's unrolled
// brute-force loop reads every primitive at a constant offset, so it was compiled again in every
// pass: about 1.2 MB of memory and 10 ms per pass on the point-light plane
// (docs/BENCHMARKS.photon-notes.md). The path tracer's brute-force loop did the same on scenes of
// a few primitives (the furnace's one sphere: a new shader every dispatch, LeakSanitizer's
// "indirect leaks" in registerEHFrames of the Stability tests; docs/TESTING.md "Sanitizers").
// A zero the compiler cannot see (gl_NumWorkGroups.z is at least 1) keeps the offsets unknown:
// - the path tracer adds it to the brute-force loop's trip count (BVH_BRUTE_FORCE_COUNT): the loop
//   is no longer unrolled into constant offsets, and the loads keep the plain index. Measured
//   3.6% more paths/s on Tungsten's Cornell box (18 primitives) than the hidden index below, with
//   the same images; the furnace renders 16 and 2048 spp in the same resident memory (95 MB),
//   where constant offsets grow it to 228 MB;
// - photon_trace adds it to every index (SCENE_UNIFORM_INDEX_HIDDEN), as first done here.
// BVH walks read nodes at data-dependent offsets: they keep the plain index in the path tracer.
// Stability.RepeatedPassesDoNotGrowTheProcess checks both.
uint uniformIndex(uint i) {
#ifdef SCENE_UNIFORM_INDEX_HIDDEN
    return i + uint(gl_NumWorkGroups.z == 0u);
#else
    return i;
#endif
}

// (Functions, not ?: : the uniform and storage structs are distinct SPIR-V types.)
BvhNode sceneNode(uint i) {
    if (kSceneInUniforms) return uniformNodes[uniformIndex(i)];
    if (kSceneTexels) {
        uvec4 a = texelFetch(bvhTexels, int(4u * i));
        uvec4 b = texelFetch(bvhTexels, int(4u * i + 1u));
        uvec4 c = texelFetch(bvhTexels, int(4u * i + 2u));
        uvec4 d = texelFetch(bvhTexels, int(4u * i + 3u));
        return BvhNode(uintBitsToFloat(a.xyz), uintBitsToFloat(a.w), b, c.xy, uintBitsToFloat(c.zw), d);
    }
    return nodes[i];
}
Prim scenePrim(uint i) {
    if (kSceneInUniforms) return uniformPrims[uniformIndex(i)];
    if (kSceneTexels) {
        // Texels a caller does not use (the normal when only intersecting) are never fetched.
        uvec4 a = texelFetch(primTexels, int(4u * i));
        uvec4 b = texelFetch(primTexels, int(4u * i + 1u));
        uvec4 c = texelFetch(primTexels, int(4u * i + 2u));
        uvec4 d = texelFetch(primTexels, int(4u * i + 3u));
        return Prim(uintBitsToFloat(a.xyz), a.w, uintBitsToFloat(b.xyz), b.w, uintBitsToFloat(c.xyz), int(c.w),
                    uintBitsToFloat(d.xyz), uintBitsToFloat(d.w));
    }
    return prims[i];
}
#define BVH_NODE(i) sceneNode(i)
#define BVH_PRIM(i) scenePrim(i)
#define BVH_BRUTE_FORCE_PRIMS kBruteForcePrims
#ifndef SCENE_UNIFORM_INDEX_HIDDEN
#define BVH_BRUTE_FORCE_COUNT (kBruteForcePrims + uint(gl_NumWorkGroups.z == 0u))
#endif
#include "shared/intersect.h"
