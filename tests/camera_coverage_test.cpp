// Film coverage of a thin emitter against a closed form (issue "nothing silent").
//
// An emitter-only render (max_bounces 1: I(0), the emitters the camera sees) of a one-sided quad
// of radiance 1 has, per pixel, the filter-weighted fraction of the pixel the quad covers. The box
// and tent filters are partitions of unity, so where the quad's image lies inside the film (with a
// margin of one filter radius) the pixel values sum to the area of the quad's image: the image
// mean equals the area of the projected polygon over the film's area, both in pixels. The pinhole
// maps the quad's four corners to a quadrilateral (computed here from the loaded geometry and the
// camera basis, independently of the shader), whose area is the shoelace formula.
//
// Grazing views make the polygon a thin sliver whose coverage is decided at its edges: the case
// where Tungsten's tent filter measured 0.3-0.5% high and 1.9% low (docs/TESTING.md). Each case
// is a Z-test of the image mean with the film's own variance (independent samples: binomial per
// pixel); the control, the same quad 1% larger (2% more area), is rejected by the same test.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "region_stats.h"
#include "render_harness.h"
#include "shared/camera.h"

using namespace telescope;
using namespace telescope::test;

namespace {

class CameraCoverage : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

// A horizontal quad of side `side` facing down, `height` above a camera at the origin looking
// along +z; pitch tilts it about x (degrees). Black, emission 1.
Scene coverageScene(uint32_t width, uint32_t height, const std::string& filter, double quadHeight, double side,
                    double pitch) {
    const nlohmann::json j = {
        {"bsdfs", {{{"name", "black"}, {"type", "lambert"}, {"albedo", 0.0}}}},
        {"primitives",
         {{{"name", "light"},
           {"type", "quad"},
           {"bsdf", "black"},
           {"emission", 1.0},
           {"transform", {{"position", {0.0, quadHeight, 2.0}}, {"scale", {side, 1.0, side}}, {"rotation", {pitch, 0.0, 180.0}}}}}}},
        {"camera",
         {{"type", "pinhole"},
          {"fov", 60.0},
          {"resolution", {width, height}},
          {"reconstruction_filter", filter},
          {"transform", {{"position", {0.0, 0.0, 0.0}}, {"look_at", {0.0, 0.0, 1.0}}, {"up", {0.0, 1.0, 0.0}}}}}},
        {"integrator", {{"type", "path_tracer"}, {"max_bounces", 1}}},
        {"renderer", {{"spp", 1}}}};
    return loadSceneFromString(j.dump(), "camera coverage", sourcePath("scenes"));
}

// Film point (pixels, y down) of world point p: the inverse of shared/camera.h cameraRayDirection.
glm::dvec2 project(const Camera& cam, glm::dvec3 p) {
    const glm::dvec3 d = p - glm::dvec3(cam.position);
    const double a = glm::dot(d, glm::dvec3(cam.right)), b = glm::dot(d, glm::dvec3(cam.up)),
                 c = glm::dot(d, glm::dvec3(cam.forward));
    const double pd = 1.0 / std::tan(0.5 * glm::radians(double(cam.fovDegrees)));
    const double w = cam.width, h = cam.height;
    return {0.5 * w * (1.0 + pd * a / c), 0.5 * h - 0.5 * w * pd * b / c};
}

// The area (pixels^2) of the quad's image, and whether it keeps a one-pixel margin in the film.
double projectedArea(const Scene& scene, bool& inside) {
    EXPECT_EQ(scene.geometry.size(), 1u);
    const Geometry& g = scene.geometry.at(0);
    EXPECT_EQ(g.type, GeometryType::Quad);
    const Camera& cam = scene.camera;
    // One-sided emission: the camera must see the emitting side.
    EXPECT_GT(glm::dot(glm::dvec3(g.normal), glm::dvec3(cam.position) - glm::dvec3(g.p0)), 0.0);
    const std::array<glm::dvec3, 4> corners = {glm::dvec3(g.p0), glm::dvec3(g.p1),
                                                glm::dvec3(g.p1) + glm::dvec3(g.p2) - glm::dvec3(g.p0), glm::dvec3(g.p2)};
    double twice = 0.0;
    inside = true;
    for (size_t i = 0; i < 4; ++i) {
        const glm::dvec2 a = project(cam, corners[i]), b = project(cam, corners[(i + 1) % 4]);
        twice += a.x * b.y - b.x * a.y;
        inside = inside && a.x > 1.0 && a.y > 1.0 && a.x < cam.width - 1.0 && a.y < cam.height - 1.0;
    }
    return 0.5 * std::abs(twice);
}

struct Coverage {
    double z = 0.0, relative = 0.0;
};

// Z of the rendered image mean against projected area / film area.
Coverage coverageZ(const Film& film, double expected) {
    double mean = 0.0, variance = 0.0;
    const double n = double(film.pixelCount());
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        mean += film.mean(shader::kChannelEstimate, i).x / n;
        variance += film.varianceOfMean(i).x / (n * n);
    }
    return {(mean - expected) / std::sqrt(variance), mean / expected - 1.0};
}

TEST_F(CameraCoverage, EmitterImageMeanIsItsProjectedAreaOverTheFilm) {
    struct Case {
        uint32_t width, height;
        const char* filter;
        double quadHeight, pitch;
        uint64_t spp;
    };
    // Heights 0.05, 0.10 and 0.15 under a quad at distance 2: views 1.4, 2.9 and 4.3 degrees off
    // its plane (the polygon a few pixels high); a tilted one; non-square films. The thinnest
    // image gets the largest film, so that the control's 2% stays > 6 standard errors.
    const Case cases[] = {{192, 192, "box", 0.05, 0.0, 2048},  {192, 192, "tent", 0.05, 0.0, 2048},
                          {96, 96, "tent", 0.15, 0.0, 1024},   {96, 96, "box", 0.15, 0.0, 1024},
                          {128, 72, "tent", 0.10, 0.0, 1024},  {128, 72, "box", 0.10, 0.0, 1024},
                          {72, 128, "tent", 0.25, 20.0, 1024}};
    const double threshold = sidakThreshold(1e-3, 2 * std::size(cases));
    uint32_t seed = 71;
    for (const Case& c : cases) {
        const std::string what = fmt::format("{}x{} {} height {} pitch {}", c.width, c.height, c.filter, c.quadHeight, c.pitch);
        const Scene scene = coverageScene(c.width, c.height, c.filter, c.quadHeight, 0.5, c.pitch);
        bool inside = false;
        const double expected = projectedArea(scene, inside) / (double(c.width) * c.height);
        ASSERT_TRUE(inside) << what << ": the quad's image must stay inside the film";
        const Film film = renderFilm(scene, c.spp, seed++);
        const Coverage z = coverageZ(film, expected);
        // The control: the same render against the area of a quad 1% larger.
        const Scene larger = coverageScene(c.width, c.height, c.filter, c.quadHeight, 0.505, c.pitch);
        const double largerExpected = projectedArea(larger, inside) / (double(c.width) * c.height);
        const Coverage control = coverageZ(film, largerExpected);
        std::printf("%s: expected mean %.7f, rendered %+.3f%% (Z %+.2f); quad 1%% larger: Z %+.2f\n", what.c_str(),
                    expected, 100.0 * z.relative, z.z, control.z);
        EXPECT_LT(std::abs(z.z), threshold) << what << ": image mean off the projected area by " << 100.0 * z.relative << "%";
        EXPECT_GT(std::abs(control.z), threshold) << what << ": the test cannot tell a quad 1% larger";
    }
}

}  // namespace
