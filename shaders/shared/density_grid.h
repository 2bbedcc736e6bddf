// Trilinear lookup in a voxel density grid (x fastest, then y, then z), one source for medium.glsl
// and the host (src/scene/density_grid.cpp, tested in density_grid_test.cpp). Voxel centres sit at
// (i + 1/2) / res of the unit box; lookups are clamped to the outermost centres, 0 outside the box.
#ifndef TELESCOPE_DENSITY_GRID_H
#define TELESCOPE_DENSITY_GRID_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

// The eight voxels around a point: the lower corner's index, the index steps to its x, y and z
// neighbours (0 where the corner is on the last layer) and the interpolation weights.
struct GridStencil {
    uint corner;
    uvec3 step;
    vec3 t;
};

// False outside the unit box [0, 1]^3.
FN bool gridStencil(uvec3 res, vec3 unit, OUT(GridStencil) s) {
    if (any(lessThan(unit, vec3(0.0f))) || any(greaterThan(unit, vec3(1.0f)))) return false;
    vec3 c = clamp(unit * vec3(res) - 0.5f, vec3(0.0f), vec3(res) - 1.0f);
    uvec3 i0 = uvec3(floor(c));
    uvec3 i1 = min(i0 + 1u, res - 1u);
    s.t = c - vec3(i0);
    s.corner = (i0.z * res.y + i0.y) * res.x + i0.x;
    s.step = uvec3(i1.x - i0.x, (i1.y - i0.y) * res.x, (i1.z - i0.z) * res.x * res.y);
    return true;
}

// Nearest-voxel lookups (Tungsten's exact_nearest): the weights of the stencil's closest corner.
FN vec3 gridNearestWeights(vec3 t) { return vec3(t.x >= 0.5f ? 1.0f : 0.0f, t.y >= 0.5f ? 1.0f : 0.0f, t.z >= 0.5f ? 1.0f : 0.0f); }

// vXYZ: the voxel at corner + X step.x + Y step.y + Z step.z.
FN float gridTrilinear(vec3 t, float v000, float v100, float v010, float v110, float v001, float v101, float v011,
                       float v111) {
    float y0 = mix(mix(v000, v100, t.x), mix(v010, v110, t.x), t.y);
    float y1 = mix(mix(v001, v101, t.x), mix(v011, v111, t.x), t.y);
    return mix(y0, y1, t.z);
}

SHADER_NAMESPACE_END

#endif
