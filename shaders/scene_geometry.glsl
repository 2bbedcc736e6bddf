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
// A zero the compiler cannot see, added to every index, keeps the offsets unknown. Which zero
// decides how lavapipe loads: an offset built from constants and push constants alone is one
// scalar load for all lanes, any other offset (a loop counter, gl_NumWorkGroups) a gather that
// loads each lane's value of each component apart (16 loads a lane for a Prim).
// - the path tracer adds pc.width >> 31 (its push constants; images are narrower than 2^31) and
//   unrolls the brute-force loops (BVH_UNROLL): each primitive is read by scalar loads. Against a
//   loop whose trip count hid a zero from gl_NumWorkGroups (gathers), taking turns, 2026-12-06,
//   M paths/s at 128 spp: Tungsten's volumetric caustic (8 primitives) 2.30-2.43 -> 3.26-3.40
//   (with the light sample once a step), its Cornell box (18) 5.45 -> 5.61 (it walks the BVH now:
//   kMaxBruteForcePathPrims), the images bit-identical; the furnace renders 16 and 2048 spp in the same resident memory (95.5 MB), where
//   plain constant offsets grew it to 228 MB;
// - photon_trace adds gl_NumWorkGroups.z == 0 (SCENE_UNIFORM_INDEX_HIDDEN), as first done here.
// Stability.RepeatedPassesDoNotGrowTheProcess checks both.
uint uniformIndex(uint i) {
#ifdef SCENE_UNIFORM_INDEX_HIDDEN
    return i + uint(gl_NumWorkGroups.z == 0u);
#else
    return i + (pc.width >> 31u);
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
#define BVH_BRUTE_FORCE_CURVED kBruteForceCurved
#define BVH_TIE_RANKS kTieRanks
#define BVH_TIE_DISTANCE kRayEpsilon
#define BVH_UNROLL [[unroll]]  // GL_EXT_control_flow_attributes (every includer enables it)
// BVH walks whose stack fits kMaxRegisterBvhStack entries keep it in registers (shared/intersect.h).
#define BVH_STACK_LENGTH (kBvhStackNeed != 0u ? kBvhStackNeed : kBvhStackSize)
#define BVH_STACK_IN_REGISTERS (kBvhStackNeed != 0u)
#include "shared/intersect.h"
