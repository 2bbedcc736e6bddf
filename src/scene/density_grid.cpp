#include "scene/density_grid.h"

#include "shared/density_grid.h"

#include <algorithm>
#include <cmath>

namespace telescope {

namespace {

uint32_t hash3(int32_t x, int32_t y, int32_t z, uint32_t seed) {
    uint32_t h = seed * 0x9E3779B9u;
    for (uint32_t v : {uint32_t(x), uint32_t(y), uint32_t(z)}) {
        h ^= v + 0x7F4A7C15u + (h << 6) + (h >> 2);
        h *= 0x85EBCA6Bu;
        h ^= h >> 13;
    }
    return h;
}

float lattice(int32_t x, int32_t y, int32_t z, uint32_t seed) { return float(hash3(x, y, z, seed) >> 8) / 16777216.0f; }

float smooth(float t) { return t * t * (3.0f - 2.0f * t); }

// Value noise in [0, 1): smoothed trilinear interpolation of lattice values.
float valueNoise(glm::vec3 p, uint32_t seed) {
    glm::vec3 f = glm::floor(p);
    glm::ivec3 i(f);
    glm::vec3 t = p - f;
    glm::vec3 s(smooth(t.x), smooth(t.y), smooth(t.z));
    float v = 0.0f;
    for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                float w = (dx ? s.x : 1 - s.x) * (dy ? s.y : 1 - s.y) * (dz ? s.z : 1 - s.z);
                v += w * lattice(i.x + dx, i.y + dy, i.z + dz, seed);
            }
    return v;
}

}  // namespace

DensityGrid proceduralCloud(const ProceduralCloudSettings& c) {
    DensityGrid g;
    g.resolution = c.resolution;
    g.source = "procedural_cloud";
    g.density.assign(size_t(c.resolution.x) * c.resolution.y * c.resolution.z, 0.0f);
    float maxValue = 0.0f;
    for (uint32_t z = 0; z < c.resolution.z; ++z)
        for (uint32_t y = 0; y < c.resolution.y; ++y)
            for (uint32_t x = 0; x < c.resolution.x; ++x) {
                // p in [-1, 1]^3
                glm::vec3 p = (glm::vec3(x, y, z) + 0.5f) / glm::vec3(c.resolution) * 2.0f - 1.0f;
                float n = 0.0f, amplitude = 0.5f, norm = 0.0f;
                glm::vec3 q = p * c.frequency;
                for (uint32_t o = 0; o < c.octaves; ++o) {
                    n += amplitude * valueNoise(q, c.seed + o);
                    norm += amplitude;
                    amplitude *= 0.5f;
                    q *= 2.03f;
                }
                n /= norm;
                // Soft ellipsoid, flatter at the bottom like a cumulus.
                glm::vec3 e = p * glm::vec3(1.0f, p.y < 0.0f ? 1.6f : 1.15f, 1.0f);
                float r = glm::length(e);
                float shape = std::clamp((1.0f - r) / 0.45f, 0.0f, 1.0f);
                float d = std::max(0.0f, n * shape + 0.35f * shape - c.coverage);
                g.density[(size_t(z) * c.resolution.y + y) * c.resolution.x + x] = d;
                maxValue = std::max(maxValue, d);
            }
    if (maxValue > 0.0f)
        for (float& d : g.density) d /= maxValue;
    return g;
}

DensityGrid constantGrid(glm::uvec3 resolution, float value) {
    DensityGrid g;
    g.resolution = resolution;
    g.source = "constant";
    g.density.assign(size_t(resolution.x) * resolution.y * resolution.z, value);
    return g;
}

DensityGrid linearGrid(glm::uvec3 resolution, float from, float to) {
    DensityGrid g = constantGrid(resolution, from);
    g.source = "linear";
    for (uint32_t z = 0; z < resolution.z; ++z) {
        const float v = resolution.z > 1 ? from + (to - from) * float(z) / float(resolution.z - 1) : from;
        for (size_t i = 0; i < size_t(resolution.x) * resolution.y; ++i) g.density[z * size_t(resolution.x) * resolution.y + i] = v;
    }
    return g;
}

float sampleGrid(const DensityGrid& grid, glm::vec3 unit) {
    shader::GridStencil g;
    if (!shader::gridStencil(grid.resolution, unit, g)) return 0.0f;
    if (grid.nearest) g.t = shader::gridNearestWeights(g.t);
    const float* v = grid.density.data() + g.corner;
    const uint32_t x = g.step.x, y = g.step.y, z = g.step.z;
    return shader::gridTrilinear(g.t, v[0], v[x], v[y], v[x + y], v[z], v[x + z], v[y + z], v[x + y + z]);
}

glm::uvec3 majorantResolution(const DensityGrid& grid) {
    if (grid.majorantCell == 0) return glm::uvec3(1u);
    return (grid.resolution + grid.majorantCell - 1u) / grid.majorantCell;
}

uint64_t gridFloats(const DensityGrid& grid) {
    const glm::uvec3 m = majorantResolution(grid);
    return grid.density.size() + grid.emission.size() + 2ull * m.x * m.y * m.z;
}

std::vector<glm::vec2> majorantGrid(const DensityGrid& grid) {
    const glm::uvec3 res = grid.resolution, cells = majorantResolution(grid);
    const uint32_t cell = grid.majorantCell;
    // Voxels a lookup inside a cell may read: the cell's own and one more on each side (trilinear
    // stencils; for nearest lookups this covers a point that rounding puts across a cell face).
    const int32_t reach = grid.majorantCoversStencil ? 1 : 0;
    std::vector<glm::vec2> out(size_t(cells.x) * cells.y * cells.z, glm::vec2(INFINITY, 0.0f));
    for (uint32_t cz = 0; cz < cells.z; ++cz)
        for (uint32_t cy = 0; cy < cells.y; ++cy)
            for (uint32_t cx = 0; cx < cells.x; ++cx) {
                const glm::uvec3 c(cx, cy, cz);
                glm::ivec3 lo(0), hi(glm::ivec3(res) - 1);
                if (cell > 0) {
                    lo = glm::max(glm::ivec3(c * cell) - reach, glm::ivec3(0));
                    hi = glm::min(glm::ivec3((c + 1u) * cell) - 1 + reach, glm::ivec3(res) - 1);
                }
                glm::vec2& mm = out[(size_t(cz) * cells.y + cy) * cells.x + cx];
                for (int32_t z = lo.z; z <= hi.z; ++z)
                    for (int32_t y = lo.y; y <= hi.y; ++y)
                        for (int32_t x = lo.x; x <= hi.x; ++x) {
                            const float d = grid.density[(size_t(z) * res.y + y) * res.x + x];
                            mm.x = std::min(mm.x, d);
                            mm.y = std::max(mm.y, d);
                        }
                if (!std::isfinite(mm.x)) mm.x = 0.0f;
            }
    return out;
}

}  // namespace telescope
