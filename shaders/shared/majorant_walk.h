// The walk through a majorant grid (GLSL and C++): a 3-D DDA (Amanatides and Woo) over the cells of
// a res.x x res.y x res.z grid that a segment x(t) = xo + t xd, t in [0, len], crosses, in grid
// units (cell c covers [c, c + 1)). Trackers run each piece at its own cell's majorant
// (medium.glsl trTrackGrid); tests/unit/majorant_walk_test.cpp checks the cells and pieces on the
// CPU against points sampled along segments.
//
//   MajorantWalk w = majorantWalkStart(xo, xd, res, len);
//   do { piece [t, majorantWalkCellEnd(w)) lies in w.cell; t = that end } while (majorantWalkNext(w));
//
// The start cell is the one holding xo, clamped into the grid (segments start inside the medium's
// bounds; rounding may put xo a hair outside). A walk ends at len or where it leaves the grid.
#ifndef TELESCOPE_MAJORANT_WALK_H
#define TELESCOPE_MAJORANT_WALK_H

#include "shared/intersect.h"  // safeInverse
#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

struct MajorantWalk {
    ivec3 cell;     // the current cell
    ivec3 stepDir;  // -1, 0 or 1 per axis
    vec3 tNext;     // parameter of the next face crossing per axis (kInfinity along a zero direction)
    vec3 tDelta;    // parameter across one cell per axis
    ivec3 res;
    float len;
};

FN MajorantWalk majorantWalkStart(vec3 xo, vec3 xd, ivec3 res, float len) {
    MajorantWalk w;
    w.res = res;
    w.len = len;
    w.cell = clamp(ivec3(floor(xo)), ivec3(0), res - 1);
    w.stepDir = ivec3(sign(xd));
    vec3 inv = safeInverse(xd);
    w.tDelta = abs(inv);
    w.tNext = (vec3(w.cell) + vec3(greaterThan(xd, vec3(0.0f))) - xo) * inv;
    w.tNext = mix(w.tNext, vec3(kInfinity), equal(xd, vec3(0.0f)));
    return w;
}

// Where the current cell's piece of the segment ends (len for the last one).
FN float majorantWalkCellEnd(MajorantWalk w) { return min(min(w.tNext.x, w.tNext.y), min(w.tNext.z, w.len)); }

// Steps into the next cell; false when the segment ends in this cell or leaves the grid.
FN bool majorantWalkNext(INOUT(MajorantWalk) w) {
    if (majorantWalkCellEnd(w) >= w.len) return false;
    if (w.tNext.x <= w.tNext.y && w.tNext.x <= w.tNext.z) {
        w.cell.x += w.stepDir.x;
        w.tNext.x += w.tDelta.x;
    } else if (w.tNext.y <= w.tNext.z) {
        w.cell.y += w.stepDir.y;
        w.tNext.y += w.tDelta.y;
    } else {
        w.cell.z += w.stepDir.z;
        w.tNext.z += w.tDelta.z;
    }
    return !(any(lessThan(w.cell, ivec3(0))) || any(greaterThanEqual(w.cell, w.res)));
}

SHADER_NAMESPACE_END

#endif
