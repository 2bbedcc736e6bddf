// The environment buffer of an infinite_sphere with an image (binding kBindingEnvironment; layout
// in shaders/shared/environment_map.h): texels, rotation and the sampling tables.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "scene/scene.h"

namespace telescope {

// The sampling weight of texel (x, y) as Tungsten's BitmapTexture::makeSamplable builds it: the
// largest of its three channels (in magnitude: a negative texel is sampled too) times sin(y pi / h) (the Jacobian of the sphere map, taken at the
// row's upper edge), then the largest over each texel's 3 x 3 neighbourhood (wrapped unless
// clamped), so that a bilinear lookup is never non-zero where the density is 0.
std::vector<double> environmentSamplingWeights(const EnvironmentImage& image);

// Tests only (a positive control of the render tests): light sampling claims its pdf this many
// times too large. 1 everywhere else.
inline float environmentTestPdfScale = 1.0f;

// The buffer: header, texels (times the image's scale), the rows' cdf and each row's column cdf.
std::vector<float> buildEnvironmentBuffer(const EnvironmentImage& image, const glm::mat3& rotation);

// Radiance averaged over the sphere of directions (midpoint of each texel; for light selection).
glm::vec3 environmentMeanRadiance(const EnvironmentImage& image);

}  // namespace telescope
