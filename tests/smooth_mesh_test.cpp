// Tungsten's mesh keys "smooth", "recompute_normals" and "backface_culling" against a known answer:
// a Lambertian sphere lit head-on by a point light (direct light only), rendered as the analytic
// sphere and as triangulated spheres (24 x 48 and 48 x 96 segments: 7.5 and 3.75 degree facets)
// shaded with the file's exact vertex normals or Tungsten's recomputed ones, against flat shading
// (the same meshes without "smooth") as the control.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "region_stats.h"
#include "render_harness.h"
#include "core/error.h"
#include "scene/scene_loader.h"

using namespace telescope;
using namespace telescope::test;

namespace {

constexpr uint32_t kRes = 32;

// A UV sphere of radius 1 at the origin as .obj with exact normals ("vn" = position).
std::string sphereObj(int rings, int segments) {
    std::string out;
    for (int i = 0; i <= rings; ++i) {
        const double theta = M_PI * i / rings;
        for (int j = 0; j < segments; ++j) {
            const double phi = 2.0 * M_PI * j / segments;
            const double x = std::sin(theta) * std::cos(phi), y = std::cos(theta), z = std::sin(theta) * std::sin(phi);
            out += fmt::format("v {:.9f} {:.9f} {:.9f}\nvn {:.9f} {:.9f} {:.9f}\n", x, y, z, x, y, z);
        }
    }
    auto index = [&](int i, int j) { return i * segments + (j % segments) + 1; };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1), d = index(i, j + 1);
            // outward winding: cross(p1 - p0, p2 - p0) points away from the centre
            if (i > 0) out += fmt::format("f {0}//{0} {1}//{1} {2}//{2}\n", a, d, b);
            if (i + 1 < rings) out += fmt::format("f {0}//{0} {1}//{1} {2}//{2}\n", d, c, b);
        }
    return out;
}

// The scene around one sphere primitive: the camera at z = 4 looking at the sphere, the point
// light next to it, so the central pixels see the lit cap far from the terminator.
std::string sceneText(const std::string& sphere) {
    return fmt::format(R"({{
        "bsdfs": [{{"name": "white", "type": "lambert", "albedo": 0.8}}],
        "primitives": [{},
            {{"type": "point", "transform": {{"position": [0.5, 0.5, 4]}}, "power": [400, 400, 400]}}],
        "camera": {{"resolution": [{}, {}], "reconstruction_filter": "box", "type": "pinhole", "fov": 30,
            "transform": {{"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0]}}}},
        "integrator": {{"type": "path_tracer", "max_bounces": 2}}}})",
                       sphere, kRes, kRes);
}

Film renderSphere(const std::filesystem::path& dir, const std::string& name, const std::string& sphere) {
    const std::filesystem::path file = dir / (name + ".json");
    std::ofstream(file) << sceneText(sphere);
    return renderFilm(loadScene(file.string()), 64, 7);
}

// The largest relative difference of the central pixels (red).
double maxRelative(const Film& a, const Film& b) {
    auto pa = blockMeans(a, 1), pb = blockMeans(b, 1);
    double worst = 0.0;
    for (uint32_t y = 8; y < 24; ++y)
        for (uint32_t x = 8; x < 24; ++x)
            worst = std::max(worst, std::abs(pa[y * kRes + x].mean.x / pb[y * kRes + x].mean.x - 1.0));
    return worst;
}

class SmoothMesh : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

}  // namespace

TEST_F(SmoothMesh, SmoothShadedSphereMeshConvergesToTheAnalyticSphereAtSecondOrder) {
    // The central pixels' largest relative error against the analytic sphere, for two meshes
    // whose facets halve: smooth shading (the file's normals, or recomputed) is second order in
    // the facet angle (an interpolated normal misses by O(h^2), the facets sit O(h^2) inside), flat
    // shading first order (the facet normal misses by up to half the facet angle). Measured: 0.58%,
    // 0.65% and 5.3% at 7.5 degrees; 0.15%, 0.17% and 0.9% at 3.75 degrees. Noise: about
    // 0.07% per pixel at 64 spp (a point light: only the pixel footprint varies).
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "telescope-smooth-mesh-test";
    std::filesystem::create_directories(dir);
    const Film analytic = renderSphere(dir, "analytic", R"({"type": "sphere", "bsdf": "white"})");
    struct Errors {
        double file = 0.0, recomputed = 0.0, flat = 0.0;
    };
    std::vector<Errors> errors;
    for (int rings : {24, 48}) {
        std::ofstream(dir / "sphere.obj") << sphereObj(rings, 2 * rings);
        Errors e;
        e.file = maxRelative(
            renderSphere(dir, "file", R"({"type": "mesh", "file": "sphere.obj", "bsdf": "white", "smooth": true})"),
            analytic);
        e.recomputed = maxRelative(renderSphere(dir, "recomputed",
                                                R"({"type": "mesh", "file": "sphere.obj", "bsdf": "white",
                                                    "smooth": true, "recompute_normals": true})"),
                                   analytic);
        const Film flat = renderSphere(dir, "flat", R"({"type": "mesh", "file": "sphere.obj", "bsdf": "white"})");
        e.flat = maxRelative(flat, analytic);
        // recompute_normals without smooth changes nothing (Tungsten recomputes only smooth meshes)
        const Film flatRecomputed = renderSphere(
            dir, "flat-recomputed", R"({"type": "mesh", "file": "sphere.obj", "bsdf": "white", "recompute_normals": true})");
        EXPECT_EQ(maxRelative(flatRecomputed, flat), 0.0);
        std::printf("%d x %d facets: largest relative error: smooth (file normals) %.4f, smooth (recomputed) %.4f, "
                    "flat %.4f\n", rings, 2 * rings, e.file, e.recomputed, e.flat);
        errors.push_back(e);
    }
    EXPECT_LT(errors[0].file, 0.012);
    EXPECT_LT(errors[0].recomputed, 0.012);
    EXPECT_GT(errors[0].flat, 0.03) << "the control: flat shading must be visibly off";
    // Halving the facets divides the smooth error by about 4 (measured 3.9 and 3.8). Flat shading's
    // error falls faster than its first order here (5.3% to 0.9%): at 3.75 degrees a facet spans
    // about 2 pixels, which average it out; it stays several times the smooth error.
    EXPECT_LT(errors[1].file, errors[0].file / 2.5);
    EXPECT_LT(errors[1].recomputed, errors[0].recomputed / 2.5);
    EXPECT_GT(errors[1].flat, 3.0 * errors[1].file);
    std::filesystem::remove_all(dir);
}

TEST_F(SmoothMesh, BackfaceCullingTrueIsRefusedNamingTheKey) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "telescope-smooth-mesh-cull";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "sphere.obj") << sphereObj(4, 8);
    const std::filesystem::path file = dir / "cull.json";
    std::ofstream(file) << sceneText(
        R"({"type": "mesh", "file": "sphere.obj", "bsdf": "white", "backface_culling": true})");
    try {
        loadScene(file.string());
        FAIL() << "backface_culling true must be refused";
    } catch (const InputError& e) {
        EXPECT_EQ(e.key(), "primitives[0].backface_culling");
    }
    std::ofstream(file) << sceneText(
        R"({"type": "mesh", "file": "sphere.obj", "bsdf": "white", "backface_culling": false})");
    EXPECT_TRUE(loadScene(file.string()).ignoredKeys.empty());
    std::filesystem::remove_all(dir);
}
