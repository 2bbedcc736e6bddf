// OpenVDB grids, medium emission and the majorant grid on the device (docs/MEDIA.md,
// docs/TESTING.md), on the absorbing slab (scenes/absorbing-slab.json): the camera looks along +z
// through a slab z in [-0.5, 0.5] (top half of the frame: y > 0) at an emitter, dirac filter, so
// every pixel has one direction and a closed form.
//
// - A VDB written by the test (tests/vdb/write_vdb.cpp, OpenVDB itself) with the linear slab's
//   density renders image for image like the procedural linear grid (same seed: equal to float
//   rounding); a VDB with another value does not (control). The same for a constant VDB read
//   with nearest-voxel lookups against a constant grid.
// - Emission: an absorbing, emitting VDB slab against L = Le exp(-tau) + e (1 - exp(-tau)) /
//   (sigma_t rho), e = emission_scale Cd rho (Tungsten's scale_emission_by_density); the same
//   render without the density factor fails the same test (control).
// - The majorant grid: delta and ratio tracking through one-voxel majorant cells match the
//   linear slab's closed form; delta tracking with majorant cells that ignore the trilinear
//   stencil's neighbours (too small a majorant) fails it (control).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <fmt/format.h>

#include "region_stats.h"
#include "render_harness.h"
#include "shared/transmittance.h"
#include "slab_closed_form.h"

using namespace telescope;
using namespace telescope::test;
namespace fs = std::filesystem;

namespace {

const char* kSlab = "scenes/absorbing-slab.json";
constexpr uint32_t kBlock = 8;
constexpr double kAlpha = 1e-3;

// The linear slab of media_render_test.cpp: density 0.4 at z = -0.5 to 2.0 at z = 0.5, layer
// centres at z = -0.5, 0, 0.5, optical depth 1.2 along the normal.
const char* kLinearGrid = R"({"type":"linear","resolution":[1,1,3],"from":0.4,"to":2.0,
                               "transform":{"position":[0,1,0],"scale":[4,2,1.5]}})";

class VdbRender : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / fmt::format("telescope-vdb-{}-{}", getpid(),
                                                       ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        fs::remove_all(dir_);
        expectNoValidationMessages();
    }

    // Writes DIR/name with telescope_write_vdb; voxel size 0.5, index 0 at the world origin.
    std::string writeVdb(const std::string& name, const std::string& grids) {
        const std::string path = (dir_ / name).string();
        const std::string cmd = fmt::format("{} {} --voxel-size 0.5 {}", TELESCOPE_WRITE_VDB, path, grids);
        EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
        return path;
    }

    // A voxel medium over the top slab from a VDB file (file's world space, placed by the grid
    // transform at y + 1): voxels x in [-8, 8], y in [-4, 4], z in [-1, 1] of size 0.5 cover
    // x in [-4, 4], y in [-1, 3] and the slab's z in [-0.5, 0.5] exactly with voxel centres, so
    // inside the slab the trilinear field has no contribution from the zero voxels around it.
    static std::string vdbMedium(const std::string& path, const std::string& extra) {
        return fmt::format(R"({{"name":"constant","type":"voxel","sigma_a":1.0,"sigma_s":0.0,
                               "grid":{{"type":"vdb","file":"{}","normalize_size":false,
                                       "transform":{{"position":[0,1,0]}}{}}}}})",
                           path, extra);
    }

    fs::path dir_;
};

// Largest relative per-pixel difference of the estimate (red channel) between two films.
double maxRelativeDifference(const Film& a, const Film& b) {
    double worst = 0.0;
    for (size_t i = 0; i < a.pixelCount(); ++i) {
        const double x = a.mean(shader::kChannelEstimate, i).x, y = b.mean(shader::kChannelEstimate, i).x;
        worst = std::max(worst, std::abs(x - y) / std::max(std::abs(y), 1e-3));
    }
    return worst;
}

}  // namespace

TEST_F(VdbRender, VdbFileRendersLikeTheProceduralGridImageForImage) {
    const std::string estimator = R"({"type":"debiased_ray_march","level":1})";
    Scene procedural = loadTestScene(
        kSlab, {{"media[0]", fmt::format(R"({{"name":"constant","type":"voxel","sigma_a":1.0,"sigma_s":0.0,"grid":{}}})",
                                         kLinearGrid)},
                {"integrator.transmittance_estimator", estimator}});
    // 0.4, 1.2, 2.0 on the layers z = -1, 0, 1 (world z -0.5, 0, 0.5)
    const std::string same = writeVdb("linear.vdb", "--float density -8 -4 -1 8 4 1 0.4 2.0");
    const std::string other = writeVdb("other.vdb", "--float density -8 -4 -1 8 4 1 0.4 2.4");
    const std::string linear = R"(,"integration_method":"exact_linear","sampling_method":"exact_linear")";
    Scene fromVdb = loadTestScene(kSlab, {{"media[0]", vdbMedium(same, linear)},
                                          {"integrator.transmittance_estimator", estimator}});
    Scene control = loadTestScene(kSlab, {{"media[0]", vdbMedium(other, linear)},
                                          {"integrator.transmittance_estimator", estimator}});
    const Film a = renderFilm(procedural, 16, 41), b = renderFilm(fromVdb, 16, 41), c = renderFilm(control, 16, 41);
    const double equal = maxRelativeDifference(b, a), differs = maxRelativeDifference(c, a);
    std::printf("VDB vs procedural linear grid: max relative pixel difference %.3g (control VDB: %.3g)\n", equal, differs);
    EXPECT_LT(equal, 1e-4);
    EXPECT_GT(differs, 1e-2);

    // Nearest-voxel lookups (Tungsten's default exact_nearest): a constant VDB is a constant box.
    Scene constant = loadTestScene(
        kSlab, {{"media[0]", R"({"name":"constant","type":"voxel","sigma_a":1.0,"sigma_s":0.0,"density":1.2,
                                  "grid":{"type":"constant","resolution":[4,4,3],"value":1.0,
                                          "transform":{"position":[0,1,0],"scale":[8,4,1]}}})"},
                {"integrator.transmittance_estimator", estimator}});
    // Voxels z = -1, 0, 1 of size 0.5 with nearest lookups fill z in [-0.75, 0.75]; the slab is inside.
    const std::string box = writeVdb("box.vdb", "--float density -7 -3 -1 8 4 1 1.2 1.2");
    const std::string boxOther = writeVdb("box-other.vdb", "--float density -7 -3 -1 8 4 1 1.0 1.0");
    Scene nearest = loadTestScene(kSlab, {{"media[0]", vdbMedium(box, "")}, {"integrator.transmittance_estimator", estimator}});
    Scene nearestControl =
        loadTestScene(kSlab, {{"media[0]", vdbMedium(boxOther, "")}, {"integrator.transmittance_estimator", estimator}});
    const Film d = renderFilm(constant, 16, 42), e = renderFilm(nearest, 16, 42), f = renderFilm(nearestControl, 16, 42);
    const double equalNearest = maxRelativeDifference(e, d), differsNearest = maxRelativeDifference(f, d);
    std::printf("nearest-voxel VDB vs constant grid: %.3g (control VDB: %.3g)\n", equalNearest, differsNearest);
    EXPECT_LT(equalNearest, 1e-4);
    EXPECT_GT(differsNearest, 1e-2);
}

TEST_F(VdbRender, EmissiveSlabMatchesTheClosedForm) {
    // rho = 1.0 x density_scale 1.2, sigma_a = 1: tau = 1.2 / cos as the constant slab.
    const std::string path = writeVdb("fire.vdb", "--float density -8 -4 -1 8 4 1 1.0 1.0 "
                                                  "--vec3 Cd -8 -4 -1 8 4 1 0.5 1.0 2.0");
    const glm::dvec3 cd(0.5, 1.0, 2.0);
    const double emissionScale = 0.8, rho = 1.2, sigmaT = 1.0;
    const std::string keys = R"(,"density_scale":1.2,"emission_name":"Cd","emission_scale":0.8,
                                 "integration_method":"exact_linear","sampling_method":"exact_linear")";
    Scene scene = loadTestScene(kSlab, {{"media[0]", vdbMedium(path, keys)},
                                        {"integrator.transmittance_estimator", R"({"type":"ratio_tracking"})"}});
    Scene wrong = loadTestScene(kSlab, {{"media[0]", vdbMedium(path, std::string(keys) + R"(,"scale_emission_by_density":false)")},
                                        {"integrator.transmittance_estimator", R"({"type":"ratio_tracking"})"}});

    // Closed form per pixel (the camera of slab_closed_form.cpp): the emitter behind (Le = 1)
    // through the slab plus the emission integrated along the path in it.
    const Camera& cam = scene.camera;
    const double plane = 1.0 / std::tan(0.5 * cam.fovDegrees * 3.14159265358979323846 / 180.0);
    Film exact(cam.width, cam.height);
    exact.setSamplesPerPixel(1);
    for (uint32_t y = 0; y < cam.height; ++y)
        for (uint32_t x = 0; x < cam.width; ++x) {
            const double lx = -1.0 + 2.0 * (x + 0.5) / cam.width, ly = double(cam.height) / cam.width - 2.0 * (y + 0.5) / cam.width;
            const double cosZ = plane / std::sqrt(lx * lx + ly * ly + plane * plane);
            glm::dvec3 value;
            if (ly > 0) {
                const double tau = sigmaT * rho / cosZ;
                value = glm::dvec3(std::exp(-tau)) + emissionScale * cd * rho * (1.0 - std::exp(-tau)) / (sigmaT * rho);
            } else {
                value = glm::dvec3(std::exp(-slabTauFalloff() / cosZ));
            }
            exact.sums(shader::kChannelEstimate)[size_t(y) * cam.width + x] = glm::dvec4(value, 0.0);
            exact.sums(shader::kChannelEstimateSq)[size_t(y) * cam.width + x] = glm::dvec4(value * value, 0.0);
        }
    const std::vector<RegionMean> reference = withOffsetAllowance(blockMeans(exact, kBlock));
    const double threshold = sidakThreshold(kAlpha, reference.size() * 3);
    const Film film = renderFilm(scene, 256, 51);
    const ZSummary z = compareRegions(blockMeans(film, kBlock), reference, threshold);
    EXPECT_EQ(z.failing, 0u) << z.worst;
    EXPECT_EQ(film.nonFiniteSamples(), 0u);
    const Film w = renderFilm(wrong, 256, 52);
    const ZSummary zw = compareRegions(blockMeans(w, kBlock), reference, threshold);
    std::printf("emission without the density factor: %zu of %zu tests fail (worst %s)\n", zw.failing, zw.tests, zw.worst.c_str());
    EXPECT_GT(zw.failing, 0u) << zw.worst;
}

TEST_F(VdbRender, TrackingThroughTheMajorantGridMatchesTheLinearSlab) {
    auto linearSlab = [&](const std::string& estimator) {
        std::string grid = kLinearGrid;
        grid.insert(grid.rfind('}'), R"(,"majorant_cell":1)");
        return loadTestScene(kSlab, {{"media[0]", fmt::format(R"({{"name":"constant","type":"voxel","sigma_a":1.0,"sigma_s":0.0,"grid":{}}})", grid)},
                                     {"integrator.transmittance_estimator", estimator}});
    };
    const shader::TrModel exponential = shader::trSimple(shader::kTrExponential, glm::vec4(0));
    uint32_t seed = 60;
    for (const char* estimator : {R"({"type":"delta_tracking"})", R"({"type":"ratio_tracking"})",
                                  R"({"type":"residual_ratio_tracking"})"}) {
        Scene scene = linearSlab(estimator);
        const Film film = renderFilm(scene, 256, ++seed);
        const std::vector<RegionMean> exact = withOffsetAllowance(slabClosedForm(scene, exponential, kBlock));
        const ZSummary z = compareRegions(blockMeans(film, kBlock), exact, sidakThreshold(kAlpha, exact.size() * 3));
        EXPECT_EQ(z.failing, 0u) << estimator << ": " << z.worst;
    }
    // Control: majorant cells from their own voxel only, so the trilinear density between layers
    // exceeds the cell's majorant; delta tracking then clips its collision probability (biased).
    Scene wrong = linearSlab(R"({"type":"delta_tracking"})");
    wrong.media[0].grid.majorantCoversStencil = false;
    const Film film = renderFilm(wrong, 256, 70);
    const std::vector<RegionMean> exact = withOffsetAllowance(slabClosedForm(wrong, exponential, kBlock));
    const ZSummary z = compareRegions(blockMeans(film, kBlock), exact, sidakThreshold(kAlpha, exact.size() * 3));
    std::printf("delta tracking under too small a majorant: %zu of %zu tests fail (worst %s)\n", z.failing, z.tests, z.worst.c_str());
    EXPECT_GT(z.failing, 0u) << z.worst;
}
