// Hard-case stability suite: scenes and settings at the edges of what the estimators handle.
// Every case renders a small image and checks that every sample was finite (the renderer counts
// non-finite samples in its stats; the suite requires 0) and every output pixel is finite; where
// the answer is known, the estimate must also lie within its statistical bound.
//
// Each case is one test so a failure names the case. The scenes are built here from the shipped
// ones by scaling or editing the JSON, so the cases stay readable next to their expectations.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "region_stats.h"
#include "render_harness.h"

using namespace telescope;
using namespace telescope::test;
using nlohmann::json;

namespace {

json readJson(const std::string& relative) {
    std::ifstream in(sourcePath(relative));
    return json::parse(in);
}

Scene sceneFromJson(const json& j, const std::string& name, const std::vector<SceneOverride>& overrides = {}) {
    return loadSceneFromString(j.dump(), name, sourcePath("scenes"), overrides);
}

// Multiplies every position and scale of the scene (primitives and camera) by s.
json scaled(json j, double s) {
    auto scaleVec = [s](json& v) {
        for (auto& x : v) x = x.get<double>() * s;
    };
    for (auto& p : j["primitives"]) {
        auto& t = p["transform"];
        if (t.contains("position")) scaleVec(t["position"]);
        if (t.contains("scale")) {
            if (t["scale"].is_array()) scaleVec(t["scale"]);
            else t["scale"] = t["scale"].get<double>() * s;
        } else if (p["type"] != "point") {
            t["scale"] = s;
        }
    }
    auto& c = j["camera"]["transform"];
    scaleVec(c["position"]);
    scaleVec(c["look_at"]);
    return j;
}

// Every pixel of every channel finite, and no sample dropped as non-finite.
void expectFinite(const Film& film, const std::string& what) {
    EXPECT_EQ(film.nonFiniteSamples(), 0u) << what;
    size_t bad = 0;
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        const glm::dvec3 m = film.mean(shader::kChannelEstimate, i);
        const glm::dvec3 v = film.varianceOfMean(i);
        for (int c = 0; c < 3; ++c)
            if (!std::isfinite(m[c]) || !std::isfinite(v[c])) ++bad;
    }
    EXPECT_EQ(bad, 0u) << what << ": non-finite output pixels";
}

void expectValue(const Film& film, double value, uint32_t block, const std::string& what) {
    auto regions = blockMeans(film, block);
    const double t = sidakThreshold(1e-3, regions.size() * 3);
    ZSummary z = compareToValue(regions, glm::dvec3(value), t);
    EXPECT_EQ(z.failing, 0u) << what << ": " << z.worst << " (threshold " << t << ")";
}

// The mean over the whole image against a known value (a Z-test at 1e-3 per channel).
void expectImageMean(const Film& film, double value, const std::string& what) {
    glm::dvec3 mean(0.0), variance(0.0);
    const double n = double(film.pixelCount());
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        mean += film.mean(shader::kChannelEstimate, i) / n;
        variance += film.varianceOfMean(i) / (n * n);
    }
    const double t = sidakThreshold(1e-3, 3);
    for (int c = 0; c < 3; ++c) {
        const double z = (mean[c] - value) / std::sqrt(variance[c]);
        EXPECT_LT(std::abs(z), t) << what << ": image mean " << mean[c] << " vs " << value << ", Z = " << z;
    }
}

constexpr const char* kSingleTerm = R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.5}})";
constexpr const char* kSum = R"({"estimator":"sum","pmf":{"type":"geometric","r":0.5}})";

class Stability : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

// ---- Scene scale: the furnace's answer, Le / (1 - a) = 2, does not depend on its size ----

void furnaceAtScale(double s) {
    json j = scaled(readJson("scenes/furnace.json"), s);
    Scene scene = sceneFromJson(j, "furnace x" + std::to_string(s),
                                {{"camera.resolution", "[16,16]"}, {"integrator.max_bounces", "1"},
                                 {"integrator.debias", kSingleTerm}});
    Film film = renderFilm(scene, 96, 101);
    const std::string what = "furnace scaled by " + std::to_string(s);
    expectFinite(film, what);
    expectValue(film, 2.0, 4, what);
}

TEST_F(Stability, TinySceneScale) { furnaceAtScale(1e-4); }
TEST_F(Stability, HugeSceneScale) { furnaceAtScale(1e4); }

// ---- A point light over a plane at extreme distances: E = I / d^2 straight below ----
// Radiance of the Lambertian plane (albedo 0.5) under the light: 0.5 / pi * I / d^2, I = 1.

void pointPlaneAtScale(double s) {
    json j = scaled(readJson("scenes/point-plane.json"), s);
    Scene scene = sceneFromJson(j, "point-plane x" + std::to_string(s),
                                {{"camera.resolution", "[16,16]"}, {"camera.fov", "2"},
                                 {"integrator.max_bounces", "1"}});
    Film film = renderFilm(scene, 4, 7);
    const std::string what = "point-plane scaled by " + std::to_string(s);
    expectFinite(film, what);
    // The 2-degree view sees the plane straight below: cos = 1 within 1e-3.
    const double expected = 0.5 / M_PI / (s * s);
    const glm::dvec3 centre = film.mean(shader::kChannelEstimate, 8 * 16 + 8);
    EXPECT_NEAR(centre.x / expected, 1.0, 2e-3) << what;
}

TEST_F(Stability, PointLightAtMicroDistance) { pointPlaneAtScale(1e-3); }
TEST_F(Stability, PointLightAtKiloDistance) { pointPlaneAtScale(1e3); }

// ---- Very bright, tiny light: a sphere of radius 1e-4 with emission 1e8 ----

TEST_F(Stability, VeryBrightTinyLight) {
    json j = readJson("scenes/cornell-box.json");
    for (auto& p : j["primitives"]) {
        if (p.contains("emission")) p["emission"] = 0.0;
    }
    j["primitives"].push_back({{"name", "speck"},
                               {"type", "sphere"},
                               {"bsdf", j["primitives"][0]["bsdf"]},
                               {"emission", 1e8},
                               {"transform", {{"position", {0.0, 1.5, 0.0}}, {"scale", 1e-4}}}});
    Scene scene = sceneFromJson(j, "bright speck", {{"camera.resolution", "[16,16]"}, {"integrator.max_bounces", "2"},
                                                     {"integrator.debias", kSingleTerm}});
    expectFinite(renderFilm(scene, 16, 3), "bright tiny light");
}

// ---- Grazing angles: the camera a hair above the plane looking along it ----

TEST_F(Stability, GrazingCamera) {
    json j = readJson("scenes/point-plane.json");
    j["camera"]["transform"] = {{"position", {0.0, 1e-5, 5.0}}, {"look_at", {0.0, 1e-5, 0.0}}, {"up", {0.0, 1.0, 0.0}}};
    Scene scene = sceneFromJson(j, "grazing", {{"camera.resolution", "[16,16]"}, {"integrator.debias", kSum},
                                               {"integrator.max_bounces", "1"}});
    expectFinite(renderFilm(scene, 16, 5), "grazing camera");
}

TEST_F(Stability, GrazingLight) {
    json j = readJson("scenes/point-plane.json");
    for (auto& p : j["primitives"])
        if (p["type"] == "point") p["transform"]["position"] = {0.0, 1e-6, 0.0};
    Scene scene = sceneFromJson(j, "grazing light", {{"camera.resolution", "[16,16]"}, {"integrator.max_bounces", "1"}});
    expectFinite(renderFilm(scene, 8, 5), "light grazing the plane");
}

// ---- Degenerate triangles: zero-area, repeated vertices, a needle ----

TEST_F(Stability, DegenerateTriangles) {
    const auto dir = std::filesystem::temp_directory_path() / "telescope-stability";
    std::filesystem::create_directories(dir);
    const auto obj = dir / "degenerate.obj";
    {
        std::ofstream out(obj);
        out << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"  // a good quad
               "v 0 0 0.1\nv 0.5 0.5 0.1\nv 1 1 0.1\n"        // colinear
               "v 0.2 0.2 0.2\n"                             // one point
               "v 0 0 0.3\nv 1e-12 0 0.3\nv 0 1 0.3\n"       // needle
               "f 1 2 3\nf 1 3 4\nf 5 6 7\nf 8 8 8\nf 9 10 11\n";
    }
    json j = readJson("scenes/point-plane.json");
    j["primitives"][0] = {{"name", "mesh"}, {"type", "mesh"}, {"file", obj.string()}, {"bsdf", "grey"},
                          {"transform", {{"rotation", {-90.0, 0.0, 0.0}}, {"scale", 2.0}}}};
    Scene scene = sceneFromJson(j, "degenerate", {{"camera.resolution", "[16,16]"}, {"integrator.debias", kSingleTerm},
                                                  {"integrator.max_bounces", "1"}});
    expectFinite(renderFilm(scene, 16, 9), "degenerate triangles");
}

// ---- Level distributions with extreme tails (levels far beyond the trace depth) ----

void furnaceWithDebias(const std::string& debias, double albedo, double expected, uint64_t spp) {
    Scene scene = loadTestScene("scenes/furnace.json", {{"camera.resolution", "[16,16]"},
                                                        {"integrator.max_bounces", "1"},
                                                        {"bsdfs[0].albedo", std::to_string(albedo)},
                                                        {"integrator.debias", debias}});
    Film film = renderFilm(scene, spp, 17);
    expectFinite(film, debias);
    if (expected > 0.0) expectValue(film, expected, 8, debias);
}

TEST_F(Stability, GeometricPmfWithTinyR) {
    // r = 1e-6: levels up to ~1.7e7, far past the trace depth; corrections there are exactly 0.
    furnaceWithDebias(R"({"estimator":"single_term","pmf":{"type":"geometric","r":1e-6}})", 0.5, 0.0, 8);
}
TEST_F(Stability, GeometricPmfWithRNearOne) {
    // r = 0.999: p(j) underflows float after a dozen levels, which u in [0,1) never reaches.
    furnaceWithDebias(R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.999}})", 0.5, 0.0, 32);
}
TEST_F(Stability, PowerLawPmfHeavyTail) {
    // alpha = 0.999: P(M >= m) = (m+1)^-0.001, levels clamp at 2^31 - 1.
    furnaceWithDebias(R"({"estimator":"sum","pmf":{"type":"power_law","alpha":0.999}})", 0.5, 0.0, 8);
}
TEST_F(Stability, PowerLawPmfLightTail) {
    // alpha = 0.01: 1 / P(M >= m) grows like m; the sum estimator stays unbiased.
    furnaceWithDebias(R"({"estimator":"sum","pmf":{"type":"power_law","alpha":0.01}})", 0.5, 2.0, 256);
}
TEST_F(Stability, AlbedoNearOne) {
    // a = 0.99: L = 100, reached only through hundreds of bounces.
    furnaceWithDebias(R"({"estimator":"sum","pmf":{"type":"geometric","r":0.01}})", 0.99, 0.0, 16);
}

// ---- Specular traps: a mirror box never ends a path before the trace-depth cap ----

TEST_F(Stability, MirrorFurnace) {
    Scene scene = loadTestScene("scenes/furnace.json",
                                {{"camera.resolution", "[16,16]"}, {"integrator.max_bounces", "2"},
                                 {"bsdfs[0]", R"({"name":"grey","type":"mirror","albedo":0.999})"},
                                 {"integrator.debias", kSingleTerm}});
    expectFinite(renderFilm(scene, 8, 19), "mirror furnace");
}

TEST_F(Stability, ExtremeIndexOfRefraction) {
    for (const char* ior : {"1.0", "1.0001", "20"}) {
        json j = readJson("scenes/cornell-box.json");
        j["bsdfs"].push_back({{"name", "glass"}, {"type", "dielectric"}, {"ior", std::stod(ior)}});
        j["primitives"].push_back({{"name", "ball"}, {"type", "sphere"}, {"bsdf", "glass"},
                                   {"transform", {{"position", {0.0, 0.5, 0.0}}, {"scale", 0.4}}}});
        Scene scene = sceneFromJson(j, std::string("ior ") + ior,
                                    {{"camera.resolution", "[16,16]"}, {"integrator.debias", kSingleTerm},
                                     {"integrator.max_bounces", "2"}});
        expectFinite(renderFilm(scene, 8, 23), std::string("dielectric ior ") + ior);
    }
}

// ---- Odd image sizes and a camera sitting on a surface ----

TEST_F(Stability, OddImageSizes) {
    for (const char* res : {"[1,1]", "[7,3]", "[3,17]"}) {
        Scene scene = loadTestScene("scenes/furnace.json", {{"camera.resolution", res}, {"integrator.max_bounces", "1"},
                                                            {"integrator.debias", kSingleTerm}});
        Film film = renderFilm(scene, 64, 29);
        expectFinite(film, res);
        expectImageMean(film, 2.0, res);
    }
}

TEST_F(Stability, CameraOnASurface) {
    Scene scene = loadTestScene("scenes/furnace.json", {{"camera.resolution", "[16,16]"},
                                                        {"camera.transform.position", "[0,0,-1]"},
                                                        {"camera.transform.look_at", "[0,0,1]"},
                                                        {"integrator.debias", kSum}, {"integrator.max_bounces", "1"}});
    expectFinite(renderFilm(scene, 16, 31), "camera on the back wall");
}

TEST_F(Stability, NoEmissionAnywhere) {
    json j = readJson("scenes/furnace.json");
    for (auto& p : j["primitives"]) p["emission"] = 0.0;
    Scene scene = sceneFromJson(j, "dark furnace", {{"camera.resolution", "[16,16]"}, {"integrator.max_bounces", "1"},
                                                    {"integrator.debias", kSingleTerm}});
    Film film = renderFilm(scene, 8, 37);
    expectFinite(film, "no emission");
    for (size_t i = 0; i < film.pixelCount(); ++i) ASSERT_EQ(film.mean(shader::kChannelEstimate, i), glm::dvec3(0.0));
}

// ---- Photon mapping: gather radii at the edges, empty photon maps ----
// The plane scene is 20 units wide; the light (I = 1) is 1 unit above it.

Film renderPhotons(const std::vector<SceneOverride>& extra, uint64_t spp, uint32_t seed, json* edit = nullptr) {
    json j = readJson("scenes/point-plane-photon.json");
    if (edit) j = *edit;
    std::vector<SceneOverride> o = {{"camera.resolution", "[16,16]"}, {"integrator.photon_count", "20000"}};
    o.insert(o.end(), extra.begin(), extra.end());
    return renderFilm(sceneFromJson(j, "point-plane-photon", o), spp, seed);
}

TEST_F(Stability, PhotonGatherRadiusTiny) {
    // 1e-7 of the scene: almost every gather is empty, the rare photon weighs 1 / (pi r^2) ~ 1e11.
    expectFinite(renderPhotons({{"integrator.gather_radius", "2e-6"}}, 4, 41), "unbiased PM, r_1 = 2e-6");
    expectFinite(renderPhotons({{"integrator.gather_radius", "2e-6"}, {"integrator.debias", "null"}}, 4, 42),
                 "biased PM, r = 2e-6");
}

TEST_F(Stability, PhotonGatherRadiusHuge) {
    // 1e3 of the scene: every photon lands in every gather; one hash cell holds the whole map.
    Film film = renderPhotons({{"integrator.gather_radius", "2e4"}, {"integrator.debias", "null"}}, 2, 43);
    expectFinite(film, "biased PM, r = 2e4");
    // Every photon on the plane is in every gather, at distance << r where the cone kernel is
    // 3 / (pi r^2): L = albedo / pi * Phi_plane * 3 / (pi r^2), with Phi_plane = I * Omega and the
    // solid angle of the 20 x 20 square seen from 1 above its centre Omega = 4 asin(100 / 101).
    const double omega = 4.0 * std::asin(100.0 / 101.0), r = 2e4;
    const double expected = 0.5 / M_PI * omega * 3.0 / (M_PI * r * r);
    for (size_t i = 0; i < film.pixelCount(); ++i)
        ASSERT_NEAR(film.mean(shader::kChannelEstimate, i).x / expected, 1.0, 0.05) << "pixel " << i;
    expectFinite(renderPhotons({{"integrator.gather_radius", "2e4"}}, 2, 44), "unbiased PM, r_1 = 2e4");
}

TEST_F(Stability, EmptyPhotonMap) {
    // A light with no power stores no photon: every gather is empty, the image is black.
    json j = readJson("scenes/point-plane-photon.json");
    for (auto& p : j["primitives"])
        if (p["type"] == "point") p["power"] = 0.0;
    Film film = renderPhotons({}, 2, 45, &j);
    expectFinite(film, "no photons");
    for (size_t i = 0; i < film.pixelCount(); ++i) ASSERT_EQ(film.mean(shader::kChannelEstimate, i), glm::dvec3(0.0));
}

TEST_F(Stability, PhotonsOnlyBehindTheSurface) {
    // The light below the plane: every photon arrives from the back side and is rejected.
    json j = readJson("scenes/point-plane-photon.json");
    for (auto& p : j["primitives"])
        if (p["type"] == "point") p["transform"]["position"] = {0.0, -1.0, 0.0};
    Film film = renderPhotons({{"integrator.enable_two_sided_shading", "false"}}, 2, 46, &j);
    expectFinite(film, "photons behind the plane");
}

// ---- Participating media: optical depths from 1e-6 to 1e4, Davis near its limits, empty media ----
// scenes/absorbing-slab.json: the top half of the frame sees an emitter (Le = 1) through a slab
// of constant density, thickness 1; the bottom half through an exponential-falloff slab.

const char* const kAllTransmittanceEstimators[] = {
    R"({"type":"ray_march","level":2})", R"({"type":"debiased_ray_march","level":1})",
    R"({"type":"delta_tracking"})",       R"({"type":"ratio_tracking"})",
    R"({"type":"residual_ratio_tracking"})", R"({"type":"unbiased_ray_march","level":2})"};

Film renderSlab(const std::string& estimator, double constantDensity, double falloffDensity,
                const std::string& model = R"({"type":"exponential"})", uint64_t spp = 4) {
    Scene scene = loadTestScene("scenes/absorbing-slab.json",
                                {{"camera.resolution", "[16,16]"},
                                 {"media[0].density", fmt::format("{}", constantDensity)},
                                 {"media[1].density", fmt::format("{}", falloffDensity)},
                                 {"media[0].transmittance", model},
                                 {"media[1].transmittance", model},
                                 {"integrator.transmittance_estimator", estimator}});
    return renderFilm(scene, spp, 51);
}

// Mean of the estimate over the top half (the constant slab) and over the bottom half.
std::pair<double, double> halfMeans(const Film& film) {
    double top = 0.0, bottom = 0.0;
    const size_t half = film.pixelCount() / 2;
    for (size_t i = 0; i < film.pixelCount(); ++i) (i < half ? top : bottom) += film.mean(shader::kChannelEstimate, i).x;
    return {top / double(half), bottom / double(film.pixelCount() - half)};
}

TEST_F(Stability, OpticalDepthTiny) {
    // tau = 1e-6: every estimator returns Le (1 - tau / cos) to within 1e-4.
    for (const char* estimator : kAllTransmittanceEstimators) {
        Film film = renderSlab(estimator, 1e-6, 1e-6);
        expectFinite(film, estimator);
        auto [top, bottom] = halfMeans(film);
        EXPECT_NEAR(top, 1.0, 1e-4) << estimator;
        EXPECT_NEAR(bottom, 1.0, 1e-4) << estimator;
    }
}

TEST_F(Stability, OpticalDepthHuge) {
    // tau = 1e4: exp(-1e4) underflows; every estimator returns 0 (or a finite, tiny value).
    for (const char* estimator : kAllTransmittanceEstimators) {
        Film film = renderSlab(estimator, 1e4, 1e4);
        expectFinite(film, estimator);
        auto [top, bottom] = halfMeans(film);
        EXPECT_LT(std::abs(top), 1e-6) << estimator;
        EXPECT_LT(std::abs(bottom), 1e-6) << estimator;
    }
}

TEST_F(Stability, ZeroDensityMedium) {
    // A medium of density 0 is vacuum: exactly Le.
    for (const char* estimator : kAllTransmittanceEstimators) {
        Film film = renderSlab(estimator, 0.0, 0.0);
        expectFinite(film, estimator);
        auto [top, bottom] = halfMeans(film);
        EXPECT_NEAR(top, 1.0, 1e-6) << estimator;
        EXPECT_NEAR(bottom, 1.0, 1e-6) << estimator;
    }
}

TEST_F(Stability, DavisNearItsLimits) {
    // T(tau) = (1 + tau / alpha)^-alpha: alpha = 1e-3 is nearly transparent far out (heavy tail),
    // alpha = 1e6 is the exponential. Debiased marching and biased marching stay finite, and the
    // debiased estimate on the constant slab matches the closed form within 5%.
    for (double alpha : {1e-3, 1e6}) {
        const std::string model = fmt::format(R"({{"type":"davis","alpha":{}}})", alpha);
        for (const char* estimator : {kAllTransmittanceEstimators[0], kAllTransmittanceEstimators[1]}) {
            Film film = renderSlab(estimator, 1.2, 3.0, model, 16);
            expectFinite(film, model + " " + estimator);
        }
        Film film = renderSlab(kAllTransmittanceEstimators[1], 1.2, 3.0, model, 64);
        // The centre rows look along the normal (tau = 1.2 / cos, cos > 0.98 near the centre).
        const double t = std::pow(1.0 + 1.2 / alpha, -alpha);
        const glm::dvec3 centre = film.mean(shader::kChannelEstimate, 7 * 16 + 8);
        EXPECT_NEAR(centre.x / t, 1.0, 0.05) << model;
    }
}

TEST_F(Stability, MediaListedButUnused) {
    // Media nobody references: the plan folds the volume code out; the image is Le everywhere.
    Scene scene = loadTestScene("scenes/absorbing-slab.json",
                                {{"camera.resolution", "[16,16]"},
                                 {"primitives[0].int_medium", "null"},
                                 {"primitives[1].int_medium", "null"}});
    Film film = renderFilm(scene, 4, 53);
    expectFinite(film, "unused media");
    auto [top, bottom] = halfMeans(film);
    EXPECT_NEAR(top, 1.0, 1e-6);
    EXPECT_NEAR(bottom, 1.0, 1e-6);
}

}  // namespace
