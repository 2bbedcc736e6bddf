// Ray-primitive intersection and BVH traversal, one source for the shaders and the CPU tests.
//
// Part 1 (always): intersectBox, intersectTriangle, intersectQuad, intersectSphere, intersectDisk.
// Part 2 (only when the includer has defined BVH_NODE and BVH_PRIM): intersectPrim,
// traceClosest, traceAny. Before including this file the includer defines
//   BVH_NODE(i)              the BvhNode i of the tree from collapseBvh (src/scene/bvh.h),
//   BVH_PRIM(i)              the Prim in leaf slot i (input primitives permuted by Bvh::order),
//   kHasSpheres, kHasDisks   bool constants (specialisation constants in GLSL, true in C++),
//   BVH_COUNT_NODE_VISIT()   optional: a statement run once per node entered (a test counter),
//   BVH_BRUTE_FORCE_PRIMS    optional: a constant n > 0 tests the n primitives one after the other
//                            instead of walking the tree (tiny scenes; see kSpecBruteForcePrims);
//   BVH_BRUTE_FORCE_CURVED   optional, with it: a constant whose bit i is set where slot i is a
//                            sphere or disk: the planar slots are tested by the planar test alone,
//                            the curved ones after them;
//   BVH_UNROLL               optional: the brute-force loops' attribute ([[unroll]] in GLSL);
//   BVH_TIE_RANKS            optional: a bool constant, true where some primitive carries
//                            kPrimInterface (the ranks below are then read; false: every prim
//                            ranks alike and the walk is the plain closest-hit walk);
//   BVH_TIE_DISTANCE         optional, with it: hits this close along the ray are coincident.
// Part 2 has internal linkage in C++, so each translation unit binds its own buffers.
//
// Rays are origin + t dir with dir non-zero (not necessarily unit); hits count for t strictly
// inside (tMin, tMax). The traversal queries use tMin = 0: callers offset secondary origins.
//
// Coincident surfaces. Where two surfaces coincide (a water cube's bottom face on the floor it
// stands on, a medium's box against a wall), which one a closest-hit query returns would depend on
// rounding and on the order the walk meets them, and that order differs between the BVH walk and
// the brute-force loop: the path tracer and the photon passes of one scene saw different surfaces
// (water on a floor: a camera chain that hit the water's bottom face left the water below the floor
// and was lost, the photon-mapped floor 25-40% dark against the path tracer). The rule, the same for
// every walk: hits within BVH_TIE_DISTANCE of each other along the ray are ordered by rank first,
// the surface that only separates two media (kPrimInterface: a dielectric's or a medium's
// boundary, rank 1) behind any other (rank 0): where water touches a floor the light in the water
// meets the floor, there is no water-air interface between them. Otherwise the nearer hit wins.
// BVH_TIE_DISTANCE is the ray offset (kRayEpsilon), the scale below which the renderer does not
// resolve two surfaces anyway: a ray leaving one starts beyond the other.
#ifndef TELESCOPE_INTERSECT_H
#define TELESCOPE_INTERSECT_H

#include "shared/gpu_types.h"

SHADER_NAMESPACE_BEGIN

// Traversal stack entries. collapseBvh keeps a walk's pending entries within this (bvh.cpp).
CONST uint kBvhStackSize = 64u;
CONST uint kNoPrim = 0xffffffffu;

// Closest hit: t, leaf slot of the primitive (index for BVH_PRIM), and for triangles the
// parameters of p1 and p2 (see intersectPlanar; zero for spheres and disks).
struct Hit {
    float t;
    uint prim;
    vec2 bary;
};

// ---- Ray-box ----

// Reciprocal direction for the slab test. A zero component becomes a huge finite value, so the
// slab products are finite or infinite but never 0 * inf = NaN.
FN float safeReciprocal(float x) {
    const float tiny = 1e-30f;
    return 1.0f / (abs(x) > tiny ? x : (x < 0.0f ? -tiny : tiny));
}

FN vec3 safeInverse(vec3 dir) {
    return vec3(safeReciprocal(dir.x), safeReciprocal(dir.y), safeReciprocal(dir.z));
}

// Slab test (Kay and Kajiya) of the ray against [lo, hi], clipped to [tMin, tMax]; tEnter is the
// entry distance. The entry plane of each axis is chosen by the sign of the direction, so an
// empty box (lo > hi, the root of an empty BVH) is never hit. The exit distance is widened by
// 1 + 2 gamma(3) (pbrt-v4, section 6.8.2) so that rounding cannot cull a box the ray touches.
// With a zero direction component a ray lying in the lo face plane enters and one in the hi
// face plane does not; buildBvh widens node boxes by one ulp so no primitive lies on a face.
FN bool intersectBox(vec3 lo, vec3 hi, vec3 origin, vec3 invDir, float tMin, float tMax,
                     OUT(float) tEnter) {
    bvec3 positive = greaterThanEqual(invDir, vec3(0.0f));
    vec3 tIn = (mix(hi, lo, positive) - origin) * invDir;
    vec3 tOut = (mix(lo, hi, positive) - origin) * invDir;
    float t0 = max(max(tIn.x, tIn.y), max(tIn.z, tMin));
    float t1 = min(min(min(tOut.x, tOut.y), tOut.z) * 1.00000036f, tMax);
    tEnter = t0;
    return t0 <= t1;
}

// ---- Ray-triangle ----

// Moller and Trumbore (1997), two-sided, for the triangle (quad false) or the parallelogram
// (quad true) spanned by p0, p1, p2. bary = (b1, b2): hit = p0 + b1 (p1 - p0) + b2 (p2 - p0),
// inside when b1, b2 >= 0 and b1 + b2 <= 1 (triangle) or b1, b2 <= 1 (parallelogram). Rays
// parallel to the plane and shapes that are degenerate within rounding (|det| below 1e-6 of
// |e1| |e2| |dir|, in L1 norms) report no hit. The parallelogram costs what the triangle does,
// so a quad as one primitive halves the primitives of Tungsten's quads and cubes.
FN bool intersectPlanar(vec3 origin, vec3 dir, vec3 p0, vec3 p1, vec3 p2, bool quad, float tMin,
                        float tMax, OUT(float) t, OUT(vec2) bary) {
    vec3 e1 = p1 - p0;
    vec3 e2 = p2 - p0;
    vec3 pv = cross(dir, e2);
    float det = dot(e1, pv);
    vec3 one = vec3(1.0f);
    float scale = dot(abs(e1), one) * dot(abs(e2), one) * dot(abs(dir), one);
    if (!(abs(det) > 1e-6f * scale)) return false;
    float invDet = 1.0f / det;
    vec3 s = origin - p0;
    float b1 = dot(s, pv) * invDet;
    if (!(b1 >= 0.0f && b1 <= 1.0f)) return false;
    vec3 qv = cross(s, e1);
    float b2 = dot(dir, qv) * invDet;
    if (!(b2 >= 0.0f && (quad ? b2 : b1 + b2) <= 1.0f)) return false;
    float th = dot(e2, qv) * invDet;
    if (!(th > tMin && th < tMax)) return false;
    t = th;
    bary = vec2(b1, b2);
    return true;
}

FN bool intersectTriangle(vec3 origin, vec3 dir, vec3 p0, vec3 p1, vec3 p2, float tMin,
                          float tMax, OUT(float) t, OUT(vec2) bary) {
    return intersectPlanar(origin, dir, p0, p1, p2, false, tMin, tMax, t, bary);
}

FN bool intersectQuad(vec3 origin, vec3 dir, vec3 p0, vec3 p1, vec3 p2, float tMin, float tMax,
                      OUT(float) t, OUT(vec2) bary) {
    return intersectPlanar(origin, dir, p0, p1, p2, true, tMin, tMax, t, bary);
}

// ---- Ray-sphere ----

// Nearest root in (tMin, tMax), from outside or inside. The discriminant is computed from the
// closest-approach vector and the roots by the citardauq pair, which avoids the cancellations
// of the textbook formula (Haines et al., Ray Tracing Gems, chapter 7).
FN bool intersectSphere(vec3 origin, vec3 dir, vec3 centre, float radius, float tMin,
                        float tMax, OUT(float) t) {
    vec3 f = origin - centre;
    float a = dot(dir, dir);
    float b = -dot(f, dir);
    vec3 l = f + (b / a) * dir;
    float r2 = radius * radius;
    float disc = a * (r2 - dot(l, l));
    if (!(disc >= 0.0f)) return false;
    float c = dot(f, f) - r2;
    float root = sqrt(disc);
    float q = b >= 0.0f ? b + root : b - root;
    float tA = q / a;
    float tB = q != 0.0f ? c / q : tA;
    float tNear = min(tA, tB);
    float tFar = max(tA, tB);
    if (tNear > tMin && tNear < tMax) {
        t = tNear;
        return true;
    }
    if (tFar > tMin && tFar < tMax) {
        t = tFar;
        return true;
    }
    return false;
}

// ---- Ray-disk ----

// Plane hit within the radius, two-sided; normal is unit.
FN bool intersectDisk(vec3 origin, vec3 dir, vec3 centre, float radius, vec3 normal,
                      float tMin, float tMax, OUT(float) t) {
    float denom = dot(normal, dir);
    if (denom == 0.0f) return false;
    float th = dot(centre - origin, normal) / denom;
    if (!(th > tMin && th < tMax)) return false;
    vec3 d = origin + th * dir - centre;
    if (!(dot(d, d) <= radius * radius)) return false;
    t = th;
    return true;
}

// ---- Four-child BVH nodes (gpu_types.h BvhNode) ----

// The box of child c of node as every reader decodes it: origin + q * scale per axis.
FN void bvhChildBox(BvhNode node, uint c, OUT(vec3) lo, OUT(vec3) hi) {
    uint shift = 8u * c;
    vec3 scale = vec3(node.scaleX, node.scaleYZ.x, node.scaleYZ.y);
    vec3 qLo = vec3(float((node.qLo.x >> shift) & 0xffu), float((node.qLo.y >> shift) & 0xffu),
                    float((node.qLo.z >> shift) & 0xffu));
    vec3 qHi = vec3(float((node.qLo.w >> shift) & 0xffu), float((node.qHi.x >> shift) & 0xffu),
                    float((node.qHi.y >> shift) & 0xffu));
    lo = node.origin + qLo * scale;
    hi = node.origin + qHi * scale;
}

// A leaf reference (a child >= kBvhLeaf): prims [first, first + count).
FN uint bvhLeafRef(uint first, uint count) { return kBvhLeaf | first << 4u | count; }
FN uint bvhLeafFirst(uint ref) { return (ref & ~kBvhLeaf) >> 4u; }
FN uint bvhLeafCount(uint ref) { return ref & 15u; }

SHADER_NAMESPACE_END

#endif  // TELESCOPE_INTERSECT_H

// ---- Part 2: queries against the scene's BVH (see the heading) ----
#if defined(BVH_NODE) && defined(BVH_PRIM) && !defined(TELESCOPE_INTERSECT_TRACE_H)
#define TELESCOPE_INTERSECT_TRACE_H

#ifndef BVH_COUNT_NODE_VISIT
#define BVH_COUNT_NODE_VISIT()
#endif

#ifndef BVH_BRUTE_FORCE_PRIMS
#define BVH_BRUTE_FORCE_PRIMS 0u
#endif
#ifndef BVH_UNROLL
#define BVH_UNROLL
#endif
// The walk's stack: arrays of BVH_STACK_LENGTH entries, indexed at run time unless the includer
// keeps them in registers (BVH_STACK_IN_REGISTERS, a constant, with BVH_STACK_LENGTH the walk's
// most pending entries): then every access is unrolled into compare-and-select over the entries
// (lavapipe keeps an array indexed at run time in memory it reads and writes one lane at a time).
#ifndef BVH_STACK_LENGTH
#define BVH_STACK_LENGTH kBvhStackSize
#define BVH_STACK_IN_REGISTERS false
#endif
#define BVH_STACK_WRITE(i, r, t)                                                         \
    if (BVH_STACK_IN_REGISTERS) {                                                        \
        BVH_UNROLL for (uint k = 0u; k < BVH_STACK_LENGTH; ++k) if (k == (i)) {          \
            stack[k] = (r);                                                              \
            stackT[k] = (t);                                                             \
        }                                                                                \
    } else {                                                                             \
        stack[i] = (r);                                                                  \
        stackT[i] = (t);                                                                 \
    }
#define BVH_STACK_READ(i, r, t)                                                          \
    if (BVH_STACK_IN_REGISTERS) {                                                        \
        r = 0u;                                                                          \
        t = kBoxMiss;                                                                    \
        BVH_UNROLL for (uint k = 0u; k < BVH_STACK_LENGTH; ++k) if (k == (i)) {          \
            r = stack[k];                                                                \
            t = stackT[k];                                                               \
        }                                                                                \
    } else {                                                                             \
        r = stack[i];                                                                    \
        t = stackT[i];                                                                   \
    }

#ifdef __cplusplus
#define TRACE_FN static inline
#else
#define TRACE_FN
#endif

SHADER_NAMESPACE_BEGIN

// A sphere or disk primitive; each branch vanishes when its constant is false.
TRACE_FN bool intersectCurved(Prim p, vec3 origin, vec3 dir, float tMin, float tMax, OUT(float) t) {
    if (kHasSpheres) {
        if (primShape(p) == kPrimSphere) return intersectSphere(origin, dir, p.p0, p.p1.x, tMin, tMax, t);
    }
    if (kHasDisks) {
        if (primShape(p) == kPrimDisk) return intersectDisk(origin, dir, p.p0, p.p1.x, p.n, tMin, tMax, t);
    }
    return false;
}

// One primitive of any type (triangles and quads share one test); sphere and disk branches
// vanish when their constant is false.
TRACE_FN bool intersectPrim(Prim p, vec3 origin, vec3 dir, float tMin, float tMax, OUT(float) t,
                            OUT(vec2) bary) {
    bary = vec2(0.0f);
    uint shape = primShape(p);
    if (shape == kPrimTriangle || shape == kPrimQuad)
        return intersectPlanar(origin, dir, p.p0, p.p1, p.p2, shape == kPrimQuad, tMin, tMax, t, bary);
    return intersectCurved(p, origin, dir, tMin, tMax, t);
}

#ifndef BVH_TIE_RANKS
#define BVH_TIE_RANKS false
#define BVH_TIE_DISTANCE 0.0f
#endif

// The rank of a primitive in ties (see "Coincident surfaces" above): 1 for an interface, else 0.
TRACE_FN uint tieRank(Prim p) { return BVH_TIE_RANKS && (p.type & kPrimInterface) != 0u ? 1u : 0u; }

// How far along the ray a primitive of rank `rank` may lie and still replace the closest hit so
// far (hit.t, of rank `hitRank`): a lower rank wins ties, a higher one must be nearer by more than
// the tie distance; never beyond the query's tMax, which is the limit while nothing is hit.
TRACE_FN float tieLimit(Hit hit, uint hitRank, uint rank, float tMax) {
    if (!BVH_TIE_RANKS || hit.prim == kNoPrim || rank == hitRank) return hit.t;
    return rank < hitRank ? min(hit.t + BVH_TIE_DISTANCE, tMax) : hit.t - BVH_TIE_DISTANCE;
}

// How far the walk must still look: a closer hit of any rank, or one of rank 0 tying an interface.
TRACE_FN float walkReach(Hit hit, uint hitRank, float tMax) {
    return hitRank != 0u ? min(hit.t + BVH_TIE_DISTANCE, tMax) : hit.t;
}

// A primitive's hit at t (bary for planar ones) becomes the closest so far.
TRACE_FN void takeHit(INOUT(Hit) hit, INOUT(uint) hitRank, float t, uint prim, vec2 bary, uint rank) {
    hit.t = t;
    hit.prim = prim;
    hit.bary = bary;
    hitRank = rank;
}

// A box test's result for a child the ray misses (above every tMax a query passes, kInfinity).
CONST float kBoxMiss = 3.4e38f;

// Entry distance of the ray into child c of node (kBoxMiss if it misses the box or the slot is
// empty), clipped to (0, tMax). The box is decoded as gpu_types.h BvhNode says.
TRACE_FN float childEntry(BvhNode node, uint c, vec3 origin, vec3 invDir, float tMax) {
    vec3 lo, hi;
    bvhChildBox(node, c, lo, hi);
    float t = 0.0f;
    bool entered = intersectBox(lo, hi, origin, invDir, 0.0f, tMax, t);
    return entered && node.child[c] != kBvhNoChild ? t : kBoxMiss;
}

// Orders two (entry, reference) pairs by entry.
TRACE_FN void orderPair(INOUT(float) ta, INOUT(uint) ra, INOUT(float) tb, INOUT(uint) rb) {
    if (tb < ta) {
        float t = ta;
        ta = tb;
        tb = t;
        uint r = ra;
        ra = rb;
        rb = r;
    }
}

// One traversal for both queries. Closest hit (anyHit false): t in (0, tMax); a node's children
// that the ray enters are ordered by entry distance, the nearest entered next and the others
// pushed with their entry distance, each dropped on pop if a closer hit has been found meanwhile.
// Any hit (anyHit true, shadow rays): stops at the first hit found. Callers pass a constant
// anyHit, so each use compiles to one specialised loop. The walk's entries are node indices and
// leaf references (gpu_types.h BvhNode child).
TRACE_FN bool traceRay(vec3 origin, vec3 dir, float tMax, bool anyHit, OUT(Hit) hit) {
    hit.t = tMax;
    hit.prim = kNoPrim;
    hit.bary = vec2(0.0f);
    uint hitRank = 0u;  // tieRank of hit.prim
    if (BVH_BRUTE_FORCE_PRIMS > 0u) {
        // Every primitive in turn: a loop of constant length over uniform data, with no stack.
        LOOP_BUDGET_TICK(BVH_BRUTE_FORCE_PRIMS);
#ifdef BVH_BRUTE_FORCE_CURVED
        // SIMD lanes with masks (lavapipe) run every type's test for every primitive of a loop
        // that dispatches on the type. Unrolled, each slot's kind is a constant: the planar slots
        // get the planar test alone, then the few curved ones their own.
        BVH_UNROLL for (uint i = 0u; i < BVH_BRUTE_FORCE_PRIMS; ++i) {
            if (((BVH_BRUTE_FORCE_CURVED >> i) & 1u) == 0u) {
                Prim p = BVH_PRIM(i);
                float t = 0.0f;
                vec2 bary = vec2(0.0f);
                uint rank = tieRank(p);
                if (intersectPlanar(origin, dir, p.p0, p.p1, p.p2, primShape(p) == kPrimQuad, 0.0f,
                                    tieLimit(hit, hitRank, rank, tMax), t, bary)) {
                    takeHit(hit, hitRank, t, i, bary, rank);
                    if (anyHit) return true;
                }
            }
        }
        BVH_UNROLL for (uint i = 0u; i < BVH_BRUTE_FORCE_PRIMS; ++i) {
            if (((BVH_BRUTE_FORCE_CURVED >> i) & 1u) != 0u) {
                Prim p = BVH_PRIM(i);
                float t = 0.0f;
                uint rank = tieRank(p);
                if (intersectCurved(p, origin, dir, 0.0f, tieLimit(hit, hitRank, rank, tMax), t)) {
                    takeHit(hit, hitRank, t, i, vec2(0.0f), rank);
                    if (anyHit) return true;
                }
            }
        }
        return hit.prim != kNoPrim;
#endif
        for (uint i = 0u; i < BVH_BRUTE_FORCE_PRIMS; ++i) {
            Prim p = BVH_PRIM(i);
            float t = 0.0f;
            vec2 bary = vec2(0.0f);
            uint rank = tieRank(p);
            if (intersectPrim(p, origin, dir, 0.0f, tieLimit(hit, hitRank, rank, tMax), t, bary)) {
                takeHit(hit, hitRank, t, i, bary, rank);
                if (anyHit) return true;
            }
        }
        return hit.prim != kNoPrim;
    }
    // A walk visits each node at most once; the loop budget counts a ray as kRayLoopTicks
    // iterations (an estimate, not a bound: counting every node cost 5% of the path tracer's
    // speed; the cap probe catches what the estimate misses, gpu_types.h).
    LOOP_BUDGET_TICK(kRayLoopTicks);
    vec3 invDir = safeInverse(dir);
    uint stack[BVH_STACK_LENGTH];
    float stackT[BVH_STACK_LENGTH];
    uint sp = 0u;
    uint ref = 0u;  // the root
    while (true) {
        BVH_COUNT_NODE_VISIT();
        if (ref >= kBvhLeaf) {
            // Leaf: test its primitives against the shrinking interval
            uint first = bvhLeafFirst(ref);
            uint end = first + bvhLeafCount(ref);
            for (uint i = first; i < end; ++i) {
                Prim p = BVH_PRIM(i);
                float t = 0.0f;
                vec2 bary = vec2(0.0f);
                uint rank = tieRank(p);
                if (intersectPrim(p, origin, dir, 0.0f, tieLimit(hit, hitRank, rank, tMax), t, bary)) {
                    takeHit(hit, hitRank, t, i, bary, rank);
                    if (anyHit) return true;
                }
            }
        } else {
            // Inner node: the four boxes from one node's load, sorted by entry (a sorting network)
            BvhNode node = BVH_NODE(ref);
            float reach = walkReach(hit, hitRank, tMax);
            float t0 = childEntry(node, 0u, origin, invDir, reach);
            float t1 = childEntry(node, 1u, origin, invDir, reach);
            float t2 = childEntry(node, 2u, origin, invDir, reach);
            float t3 = childEntry(node, 3u, origin, invDir, reach);
            uint r0 = node.child.x, r1 = node.child.y, r2 = node.child.z, r3 = node.child.w;
            orderPair(t0, r0, t1, r1);
            orderPair(t2, r2, t3, r3);
            orderPair(t0, r0, t2, r2);
            orderPair(t1, r1, t3, r3);
            orderPair(t1, r1, t2, r2);
            if (t0 < kBoxMiss) {
                // collapseBvh keeps the entries a walk can leave below kBvhStackSize
                if (t3 < kBoxMiss) {
                    BVH_STACK_WRITE(sp, r3, t3);
                    ++sp;
                }
                if (t2 < kBoxMiss) {
                    BVH_STACK_WRITE(sp, r2, t2);
                    ++sp;
                }
                if (t1 < kBoxMiss) {
                    BVH_STACK_WRITE(sp, r1, t1);
                    ++sp;
                }
                ref = r0;
                continue;
            }
        }
        // Pop the next entry that can still hold a closer hit
        bool popped = false;
        while (sp > 0u && !popped) {
            --sp;
            uint entry;
            float entryT;
            BVH_STACK_READ(sp, entry, entryT);
            if (entryT <= walkReach(hit, hitRank, tMax)) {
                ref = entry;
                popped = true;
            }
        }
        if (!popped) break;
    }
    return hit.prim != kNoPrim;
}

TRACE_FN bool traceClosest(vec3 origin, vec3 dir, float tMax, OUT(Hit) hit) {
    return traceRay(origin, dir, tMax, false, hit);
}

// Whether anything is hit with t in (0, tMax).
TRACE_FN bool traceAny(vec3 origin, vec3 dir, float tMax) {
    Hit hit;
    return traceRay(origin, dir, tMax, true, hit);
}

// The point where a ray hit prim at t and the prim's geometric normal there (for triangles and
// disks the stored normal). Sphere points are projected back onto the sphere, so that the
// rounding of origin + t dir does not leave them inside or outside.
TRACE_FN void hitPoint(Prim pr, vec3 origin, vec3 dir, float t, OUT(vec3) p, OUT(vec3) ng) {
    p = origin + dir * t;
    ng = pr.n;
    if (kHasSpheres && primShape(pr) == kPrimSphere) {
        ng = normalize(p - pr.p0);
        p = pr.p0 + ng * pr.p1.x;
    }
}

SHADER_NAMESPACE_END

#undef TRACE_FN

#endif  // TELESCOPE_INTERSECT_TRACE_H
