// Voxel density grids for grid media: a procedural cloud generator for our own scenes and a
// constant grid (the test that a grid renders like the homogeneous medium). Densities are
// relative (the medium's sigma_a and sigma_s scale them); a grid fills an axis-aligned box.
#pragma once

#include <cstdint>

#include "scene/scene.h"

namespace telescope {

struct ProceduralCloudSettings {
    glm::uvec3 resolution{64};
    uint32_t seed = 1;
    float frequency = 3.0f;  // noise cells across the box
    float coverage = 0.45f;  // noise threshold: larger = sparser cloud
    uint32_t octaves = 4;
};

// fBm value noise carved by a soft ellipsoid, scaled to a maximum density of 1.
// All grids of a scene go to one storage buffer of floats; lavapipe binds at most 128 MiB.
inline constexpr uint64_t kMaxGridFloats = uint64_t(32) << 20;

// Majorant grid cells along each axis (1 x 1 x 1 for majorantCell 0: one global majorant).
glm::uvec3 majorantResolution(const DensityGrid& grid);

// Floats the grid takes on the device: voxels, emission (3 per voxel) and majorant cells (2 each).
uint64_t gridFloats(const DensityGrid& grid);

// The majorant grid: per cell the (min, max) density over every voxel a lookup inside the cell
// reads (its own voxels and, for trilinear lookups, one more on each side), x fastest.
std::vector<glm::vec2> majorantGrid(const DensityGrid& grid);

DensityGrid proceduralCloud(const ProceduralCloudSettings& settings);

DensityGrid constantGrid(glm::uvec3 resolution, float value);

// Density varying linearly along the grid's z: voxel layer k holds from + (to - from) k / (n - 1),
// so the trilinear lookup is exactly linear between the first and the last layer's centres.
DensityGrid linearGrid(glm::uvec3 resolution, float from, float to);

// Trilinear lookup at a point of the unit box [0,1]^3 (voxel centres at (i + 1/2) / res, clamped
// at the faces), as medium.glsl does it; 0 outside.
float sampleGrid(const DensityGrid& grid, glm::vec3 unit);

}  // namespace telescope
