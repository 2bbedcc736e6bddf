// Points on emitters, shared by next-event estimation (path tracer, gather) and photon emission.
// One source for GLSL and C++ (tests/unit/emitter_test.cpp).
#ifndef TELESCOPE_EMITTER_H
#define TELESCOPE_EMITTER_H

#include "shared/gpu_types.h"
#include "shared/sampling.h"

SHADER_NAMESPACE_BEGIN

// A uniformly distributed point q on the emissive prim and its emitting normal nq (outward for
// spheres). `spheres` and `disks` say whether the scene has those prim types (specialisation
// constants in GLSL), so absent types cost nothing.
FN void sampleEmitterPoint(Prim pr, bool spheres, bool disks, float u1, float u2, OUT(vec3) q, OUT(vec3) nq) {
    if (spheres && primShape(pr) == kPrimSphere) {
        nq = sampleUniformSphere(u1, u2);
        q = pr.p0 + nq * pr.p1.x;
    } else if (disks && primShape(pr) == kPrimDisk) {
        q = sampleDisk(pr.p0, pr.n, pr.p1.x, u1, u2);
        nq = pr.n;
    } else if (primShape(pr) == kPrimQuad) {
        q = sampleParallelogram(pr.p0, pr.p1, pr.p2, u1, u2);
        nq = pr.n;
    } else {
        q = sampleTriangle(pr.p0, pr.p1, pr.p2, u1, u2);
        nq = pr.n;
    }
}

SHADER_NAMESPACE_END

#endif
