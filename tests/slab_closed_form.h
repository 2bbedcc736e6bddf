// The closed form of scenes/absorbing-slab.json (an emitter Le = 1 seen through two absorbing
// slabs, dirac filter): per pixel L = g(tau / cos) with tau = 1.2 x density scale through the
// constant slab (top half of the frame) and 3 (1 - exp(-3)) / 3 x density scale through the
// exponential-falloff slab (bottom half), g the transmittance model's surface-to-surface form.
#pragma once

#include <vector>

#include "region_stats.h"
#include "scene/scene.h"
#include "shared/transmittance.h"

namespace telescope::test {

// Optical depths along the slab normal (thickness 1) at the shipped densities: constant 1.2;
// falloff 3 exp(-3 (z + 1/2)) integrated over z in [-1/2, 1/2].
constexpr double kSlabTauConstant = 1.2;
double slabTauFalloff();

// Block means of the per-pixel closed form (noiseless), for `scene`'s camera. The densities of
// the two slabs are the shipped ones times constantScale and falloffScale.
std::vector<RegionMean> slabClosedForm(const Scene& scene, const shader::TrModel& model, uint32_t block,
                                       double constantScale = 1.0, double falloffScale = 1.0);

// The closed form gets a standard deviation of 2e-5 of its value: ray offsets at the slab faces
// (1e-5 of the scene size) shorten every segment, which zero-variance estimators on constant
// density resolve.
std::vector<RegionMean> withOffsetAllowance(std::vector<RegionMean> exact);

}  // namespace telescope::test
