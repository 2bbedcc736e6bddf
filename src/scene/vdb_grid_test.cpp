// OpenVDB grids through the loader (src/scene/medium_reader.cpp, src/vdb_plugin/): files written
// by tests/vdb/write_vdb.cpp with OpenVDB itself. Tungsten's placement (normalize_size: the active
// box [min, max + 1] scaled to a largest side of 1, centred on x and z, bottom at y = 0; then the
// grid transform) and OpenVDB's lookups (BoxSampler: trilinear, voxel centres at integer index
// coordinates; exact_nearest: the voxel's cube) at world points computed by hand; density_scale,
// emission_scale; and a density field that differs from the file fails the same checks (control).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>

#include "scene/density_grid.h"
#include "scene/scene_loader.h"

namespace telescope {
namespace {

namespace fs = std::filesystem;

class VdbGrid : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / fmt::format("telescope-vdbgrid-{}", getpid());
        fs::create_directories(dir_);
        // Active voxels x 0..3, y 0..1, z 0..7 (voxel size 0.5), density 1 + 2 k / 7 on layer z = k
        const std::string cmd = fmt::format("{} {} --voxel-size 0.5 --float density 0 0 0 3 1 7 1 3 "
                                            "--vec3 Cd 0 0 0 3 1 7 0.5 1 2",
                                            TELESCOPE_WRITE_VDB, (dir_ / "g.vdb").string());
        ASSERT_EQ(std::system(cmd.c_str()), 0);
    }
    void TearDown() override { fs::remove_all(dir_); }

    DensityGrid load(const std::string& gridKeys) {
        const std::string text = fmt::format(R"({{"media": [{{"name": "m", "type": "voxel", "sigma_a": 1,
            "grid": {{"type": "vdb", "file": "g.vdb"{}}}}}]}})", gridKeys);
        std::ofstream((dir_ / "s.json").string()) << text;
        return loadScene((dir_ / "s.json").string()).media.at(0).grid;
    }

    // Lookup at a world point through the grid's placement.
    static float at(const DensityGrid& g, glm::vec3 world) {
        return sampleGrid(g, glm::vec3(glm::inverse(g.unitToWorld) * glm::vec4(world, 1.0f)));
    }

    fs::path dir_;
};

// Index point -> world with normalize_size: diag = (4, 2, 8), scale 1/8, centre (0.25, 0, 0.5).
glm::vec3 normalized(glm::vec3 index) { return index / 8.0f - glm::vec3(0.25f, 0.0f, 0.5f); }
// The file's density (BoxSampler) at an index point inside the active box, linear along z.
float fileDensity(glm::vec3 index) { return 1.0f + 2.0f * index.z / 7.0f; }

TEST_F(VdbGrid, TungstenPlacementAndTrilinearLookups) {
    const DensityGrid g = load(R"(, "density_scale": 2, "integration_method": "exact_linear", "sampling_method": "exact_linear")");
    EXPECT_EQ(g.resolution, glm::uvec3(6, 4, 10));  // the active box and one layer of zeros around it
    for (glm::vec3 index : {glm::vec3(0, 0, 0), glm::vec3(3, 1, 7), glm::vec3(1.5f, 0.5f, 3.25f), glm::vec3(2, 1, 6.9f)})
        EXPECT_NEAR(at(g, normalized(index)), 2.0f * fileDensity(index), 1e-4f) << index.x << " " << index.y << " " << index.z;
    // Half a voxel outside the active box the trilinear field is half the face value; outside the
    // padded box it is 0.
    EXPECT_NEAR(at(g, normalized({-0.5f, 0.5f, 0.0f})), 0.5f * 2.0f * fileDensity({0, 0, 0}), 1e-4f);
    EXPECT_EQ(at(g, normalized({-2.0f, 0.5f, 3.0f})), 0.0f);
    // Emission: Cd x emission_scale, 3 floats a voxel, scaled by the density by default
    const DensityGrid e = load(R"(, "emission_scale": 4, "integration_method": "exact_linear", "sampling_method": "exact_linear")");
    ASSERT_EQ(e.emission.size(), 3 * e.density.size());
    EXPECT_TRUE(e.emissionByDensity);
    const size_t inside = (size_t(1 + 1) * e.resolution.y + 1) * e.resolution.x + 1;  // index (0, 0, 1)
    EXPECT_FLOAT_EQ(e.emission[3 * inside + 0], 2.0f);
    EXPECT_FLOAT_EQ(e.emission[3 * inside + 2], 8.0f);
    EXPECT_FLOAT_EQ(e.emission[0], 0.0f);  // a padding voxel
}

TEST_F(VdbGrid, NearestLookupsFileTransformAndRotation) {
    // exact_nearest (Tungsten's default): the value of the voxel whose cube holds the point
    const DensityGrid g = load("");
    EXPECT_TRUE(g.nearest);
    EXPECT_EQ(g.resolution, glm::uvec3(4, 2, 8));
    EXPECT_NEAR(at(g, normalized({1.2f, 0.3f, 3.4f})), fileDensity({0, 0, 3}), 1e-5f);
    EXPECT_NEAR(at(g, normalized({1.2f, 0.3f, 3.6f})), fileDensity({0, 0, 4}), 1e-5f);
    // normalize_size false: the file's own placement (index i at 0.5 i), then the grid transform:
    // a half turn about y and a lift by 1.
    const DensityGrid r = load(R"(, "normalize_size": false, "transform": {"position": [0, 1, 0], "rotation": [0, 180, 0]}, "integration_method": "exact_linear", "sampling_method": "exact_linear")");
    for (glm::vec3 index : {glm::vec3(1, 0, 2), glm::vec3(2.5f, 0.5f, 5.5f)}) {
        const glm::vec3 file = 0.5f * index, world(-file.x, file.y + 1.0f, -file.z);
        EXPECT_NEAR(at(r, world), fileDensity(index), 1e-4f);
        // Control: the unrotated point reads another density
        EXPECT_GT(std::abs(at(r, file + glm::vec3(0, 1, 0)) - fileDensity(index)), 0.1f);
    }
}

}  // namespace
}  // namespace telescope
