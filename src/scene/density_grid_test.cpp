// Density grids: the procedural cloud is deterministic, non-negative with maximum 1 and carved to
// zero at the box faces; the trilinear lookup reproduces voxel values at voxel centres, is
// constant for a constant grid and zero outside the box.
#include <gtest/gtest.h>

#include <algorithm>

#include "scene/density_grid.h"

namespace telescope {
namespace {

TEST(DensityGrid, ProceduralCloudIsDeterministicAndNormalised) {
    ProceduralCloudSettings s;
    s.resolution = glm::uvec3(24, 20, 16);
    s.seed = 3;
    DensityGrid a = proceduralCloud(s), b = proceduralCloud(s);
    ASSERT_EQ(a.density.size(), size_t(24) * 20 * 16);
    EXPECT_EQ(a.density, b.density);
    EXPECT_FLOAT_EQ(*std::max_element(a.density.begin(), a.density.end()), 1.0f);
    EXPECT_GE(*std::min_element(a.density.begin(), a.density.end()), 0.0f);
    size_t empty = std::count(a.density.begin(), a.density.end(), 0.0f);
    EXPECT_GT(empty, a.density.size() / 10) << "a cloud, not a fog";
    EXPECT_LT(empty, a.density.size() * 9 / 10) << "a cloud, not nothing";
    // Corners of the box are outside the ellipsoid.
    EXPECT_EQ(a.density.front(), 0.0f);
    EXPECT_EQ(a.density.back(), 0.0f);
    s.seed = 4;
    EXPECT_NE(proceduralCloud(s).density, a.density);
}

TEST(DensityGrid, TrilinearLookup) {
    DensityGrid c = constantGrid(glm::uvec3(4, 3, 2), 0.7f);
    for (glm::vec3 p : {glm::vec3(0.0f), glm::vec3(0.5f), glm::vec3(1.0f), glm::vec3(0.1f, 0.9f, 0.33f)})
        EXPECT_FLOAT_EQ(sampleGrid(c, p), 0.7f);
    EXPECT_EQ(sampleGrid(c, glm::vec3(1.01f, 0.5f, 0.5f)), 0.0f);
    EXPECT_EQ(sampleGrid(c, glm::vec3(0.5f, -0.01f, 0.5f)), 0.0f);

    ProceduralCloudSettings s;
    s.resolution = glm::uvec3(8);
    DensityGrid g = proceduralCloud(s);
    for (uint32_t z : {2u, 4u})
        for (uint32_t y : {3u, 5u})
            for (uint32_t x : {1u, 4u}) {
                glm::vec3 centre = (glm::vec3(x, y, z) + 0.5f) / 8.0f;
                EXPECT_NEAR(sampleGrid(g, centre), g.density[(size_t(z) * 8 + y) * 8 + x], 1e-6f);
            }
    // Halfway between two centres along x: the average.
    glm::vec3 mid = (glm::vec3(4.0f, 5.5f, 4.5f)) / 8.0f;
    float expected = 0.5f * (g.density[(4 * 8 + 5) * 8 + 3] + g.density[(4 * 8 + 5) * 8 + 4]);
    EXPECT_NEAR(sampleGrid(g, mid), expected, 1e-6f);
}

}  // namespace
}  // namespace telescope

namespace telescope {
namespace {
TEST(DensityGrid, LinearGridIsLinearBetweenLayerCentres) {
    DensityGrid g = linearGrid(glm::uvec3(2, 2, 3), 0.4f, 2.0f);
    // Layer centres at unit z = 1/6, 1/2, 5/6.
    for (float z = 1.0f / 6.0f; z <= 5.0f / 6.0f; z += 0.05f)
        EXPECT_NEAR(sampleGrid(g, glm::vec3(0.3f, 0.7f, z)), 0.4f + 1.6f * (z - 1.0f / 6.0f) / (2.0f / 3.0f), 1e-5f);
}
}  // namespace
}  // namespace telescope
