// Glossy materials in the path tracer against known answers (docs/TESTING.md).
//
// scenes/rough-conductor.json: an infinite plate under a constant sky of radiance 1, seen through
// pixel centres (dirac filter). A plate cannot see itself, so every pixel is exactly the plate's
// directional albedo for the view direction, E(wi) = integral of eval(wi, wo) dwo over the upper
// hemisphere, which the test integrates by quadrature from the shared BSDF code (the renderer
// estimates it with next-event estimation, BSDF sampling and MIS). Z-tests per 8x8 block and of the
// image mean, one Sidak family at 1e-3; the control renders a wrong roughness against the same
// answer and must be rejected. The estimator is bounded (weights below 1 per lobe), so its
// variance is finite.
//
// The smooth conductor (the same scene with type "conductor") is deterministic per pixel:
// albedo F(cos theta), compared exactly.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>

#include "region_stats.h"
#include "render/gpu_scene.h"
#include "render_harness.h"
#include "shared/bsdf.h"
#include "shared/camera.h"

using namespace telescope;
using namespace telescope::test;

namespace {

class GlossyRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

// Unit view direction (towards the camera) of every pixel centre, in the plate's frame (normal +y
// becomes local z).
std::vector<glm::vec3> pixelViewDirections(const Scene& s) {
    const Camera& c = s.camera;
    const float d = shader::cameraPlaneDistance(c.fovDegrees);
    std::vector<glm::vec3> out;
    for (uint32_t y = 0; y < c.height; ++y)
        for (uint32_t x = 0; x < c.width; ++x) {
            const glm::vec3 dir = shader::cameraRayDirection(glm::vec2(x + 0.5f, y + 0.5f), c.width, c.height, d, c.right,
                                                              c.up, c.forward);
            const glm::vec3 wi = -glm::normalize(dir);
            out.push_back(glm::vec3(wi.x, -wi.z, wi.y));  // (t, b, n) with n = +y; isotropic, any t works
        }
    return out;
}

// A function of the view angle theta, tabulated and interpolated linearly.
struct AlbedoTable {
    std::vector<double> theta, value;
    double operator()(double t) const {
        const double step = theta[1] - theta[0];
        const double f = std::clamp((t - theta[0]) / step, 0.0, double(theta.size() - 1) - 1e-9);
        const size_t i = size_t(f);
        return value[i] + (value[i + 1] - value[i]) * (f - double(i));
    }
};

// Directional albedo of material m (the Dirac lobe of a plastic plus the quadrature of eval over
// the sphere: light from below reaches a refracting plate too), tabulated over the view angle (it
// depends on theta only) and interpolated linearly. Radiance refracted out of the plate is scaled
// by (n_wi / n_wo)^2 = 1 / ior^2 (shared/bsdf.h roughRefractionRadianceScale; Tungsten 0.2.2
// renders the plate so); radianceScaling false leaves it out, the control's wrong answer.
std::array<AlbedoTable, 3> albedoTables(const shader::MaterialGpu& m, double maxTheta, bool radianceScaling = true) {
    std::array<AlbedoTable, 3> t;
    const int nodes = 64;
    for (int i = 0; i < nodes; ++i) {
        const double th = maxTheta * i / (nodes - 1);
        const glm::vec3 wi(float(std::sin(th)), 0.0f, float(std::cos(th)));
        const double dirac = m.type == shader::kBsdfPlastic ? shader::fresnelDielectricSigned(wi.z, m.ior) : 0.0;
        for (int c = 0; c < 3; ++c) {
            t[c].theta.push_back(th);
            t[c].value.push_back(0.0);
        }
        // Midpoint rule in (theta, phi), dw = sin theta dtheta dphi, all three channels at once.
        const double pi = 3.14159265358979323846;
        const int nt = 1024, np = 128;
        glm::dvec3 acc(0.0);
        for (int a = 0; a < nt; ++a) {
            const double tt = pi * (a + 0.5) / nt;
            glm::dvec3 ring(0.0);
            for (int b = 0; b < np; ++b) {
                const double ph = 2.0 * pi * (b + 0.5) / np;
                const glm::vec3 wo(float(std::sin(tt) * std::cos(ph)), float(std::sin(tt) * std::sin(ph)), float(std::cos(tt)));
                const float scale = radianceScaling && m.type == shader::kBsdfRoughDielectric
                                        ? shader::roughRefractionRadianceScale(m.ior, wi, wo)
                                        : 1.0f;
                ring += glm::dvec3(shader::glossyEval(m, wi, wo) * scale);
            }
            acc += ring * std::sin(tt);
        }
        acc *= (pi / nt) * (2.0 * pi / np);
        for (int c = 0; c < 3; ++c) t[c].value.back() = dirac + acc[c];
    }
    return t;
}

// The material as the renderer uploads it.
shader::MaterialGpu gpuMaterial(const Scene& s) { return telescope::gpuMaterial(s.materials.at(0)); }

// Block means (8x8) and the image mean of the closed form, per pixel from the albedo tables.
std::pair<std::vector<RegionMean>, RegionMean> expectedRegions(const Scene& s, bool radianceScaling = true) {
    const shader::MaterialGpu g = gpuMaterial(s);
    const std::vector<glm::vec3> wi = pixelViewDirections(s);
    double maxTheta = 0.0;
    for (const glm::vec3& w : wi) maxTheta = std::max(maxTheta, std::acos(double(std::clamp(w.z, -1.0f, 1.0f))));
    const std::array<AlbedoTable, 3> tables = albedoTables(g, maxTheta + 0.01, radianceScaling);
    const uint32_t w = s.camera.width, h = s.camera.height, b = 8;
    std::vector<RegionMean> blocks((w / b) * (h / b));
    RegionMean image;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const double th = std::acos(double(std::clamp(wi[y * w + x].z, -1.0f, 1.0f)));
            const glm::dvec3 v(tables[0](th), tables[1](th), tables[2](th));
            blocks[(y / b) * (w / b) + x / b].mean += v / double(b * b);
            image.mean += v / double(w * h);
        }
    return {blocks, image};
}

}  // namespace

namespace {

using ExpectedRegions = std::pair<std::vector<RegionMean>, RegionMean>;

// `scene` with overrides against `expected` (computed from the scene as loaded), and the control:
// the same scene with wrongOverrides against the same answer, which must be rejected.
void checkAgainst(const std::string& scene, const std::vector<SceneOverride>& overrides,
                  const std::vector<SceneOverride>& wrongOverrides, uint32_t seed,
                  const std::function<ExpectedRegions(const Scene&)>& expected) {
    const Scene s = loadTestScene(scene, overrides);
    const auto [blocks, image] = expected(s);
    const Film film = renderFilm(s, 256, seed);
    EXPECT_EQ(film.nonFiniteSamples(), 0u);
    const ZSummary z = compareBlocksAndImage(film, blocks, image, 8);
    EXPECT_EQ(z.failing, 0u) << scene << ": " << z.worst << " (threshold " << z.threshold << ")";
    const RegionMean got = imageMean(film);
    std::printf("%s: image mean %.5f %.5f %.5f, expected %.5f %.5f %.5f, max |Z| %.2f\n", scene.c_str(), got.mean.x,
                got.mean.y, got.mean.z, image.mean.x, image.mean.y, image.mean.z, z.maxAbsZ);

    std::vector<SceneOverride> wrong = overrides;
    wrong.insert(wrong.end(), wrongOverrides.begin(), wrongOverrides.end());
    const ZSummary c = compareBlocksAndImage(renderFilm(loadTestScene(scene, wrong), 256, seed + 1), blocks, image, 8);
    std::printf("control %s %s=%s: %zu of %zu tests fail, worst %s\n", scene.c_str(), wrongOverrides[0].key.c_str(),
                wrongOverrides[0].value.c_str(), c.failing, c.tests, c.worst.c_str());
    EXPECT_GT(c.failing, 0u) << scene << ": the test cannot see " << wrongOverrides[0].key << " = " << wrongOverrides[0].value;
}

// The plate of `scene` (with overrides) against its directional albedo.
void checkPlate(const std::string& scene, const std::vector<SceneOverride>& overrides,
                const std::vector<SceneOverride>& wrongOverrides, uint32_t seed) {
    checkAgainst(scene, overrides, wrongOverrides, seed, [](const Scene& s) { return expectedRegions(s); });
}

}  // namespace

TEST_F(GlossyRender, RoughConductorPlateMatchesItsDirectionalAlbedo) {
    checkPlate("scenes/rough-conductor.json", {}, {{"bsdfs[0].roughness", "0.2"}}, 5);
    checkPlate("scenes/rough-conductor.json", {{"bsdfs[0].distribution", "beckmann"}}, {{"bsdfs[0].roughness", "0.2"}}, 7);
}

TEST_F(GlossyRender, PlasticPlateMatchesItsDirectionalAlbedo) {
    checkPlate("scenes/plastic.json", {}, {{"bsdfs[0].ior", "1.7"}}, 11);
}

TEST_F(GlossyRender, RoughPlasticPlateMatchesItsDirectionalAlbedo) {
    checkPlate("scenes/rough-plastic.json", {}, {{"bsdfs[0].roughness", "0.4"}}, 13);
}

TEST_F(GlossyRender, OrenNayarPlateMatchesItsDirectionalAlbedo) {
    checkPlate("scenes/oren-nayar.json", {}, {{"bsdfs[0].roughness", "0.4"}}, 17);
}

// Light reaches the frosted plate from both sides (the sky is below it too): the sky seen through
// the plate is refracted out of the glass and scaled by 1 / ior^2 (image mean 0.4756; Tungsten
// 0.2.2 renders 0.4757, docs/TESTING.md). Controls: a wrong roughness, and the render against the
// unscaled answer (0.985, what the path tracer rendered before it scaled refracted radiance).
TEST_F(GlossyRender, RoughDielectricPlateMatchesItsDirectionalAlbedo) {
    checkPlate("scenes/rough-dielectric.json", {}, {{"bsdfs[0].roughness", "0.8"}}, 19);
    const Scene s = loadTestScene("scenes/rough-dielectric.json");
    const auto [blocks, image] = expectedRegions(s, false);
    const ZSummary c = compareBlocksAndImage(renderFilm(s, 256, 23), blocks, image, 8);
    std::printf("control: the unscaled answer, %zu of %zu tests fail, worst %s\n", c.failing, c.tests, c.worst.c_str());
    EXPECT_GE(c.failing, c.tests / 2) << "the unscaled answer must be rejected almost everywhere";
}

// The smooth dielectric plate under the same sky: a camera sample reflects (weight 1, the sky) with
// probability F(cos theta) or refracts and sees the sky below scaled by 1 / ior^2, so the pixel's
// expectation is F + (1 - F) / ior^2 (Tungsten 0.2.2: image mean 0.4908). Z-tests per 8x8 block
// and of the image mean; the control is the unscaled answer, 1 everywhere.
TEST_F(GlossyRender, SmoothDielectricPlateSeesTheSkyBelowScaledByOneOverEtaSquared) {
    const Scene s = loadTestScene("scenes/rough-dielectric.json", {{"bsdfs[0].type", "dielectric"}});
    ASSERT_EQ(s.materials.at(0).type, BsdfType::Dielectric);
    const double ior = s.materials[0].ior;
    const std::vector<glm::vec3> wi = pixelViewDirections(s);
    const uint32_t w = s.camera.width, h = s.camera.height, b = 8;
    const auto expected = [&](bool scaled) {
        std::vector<RegionMean> blocks((w / b) * (h / b));
        RegionMean image;
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x) {
                float cosT;
                const double F = shader::fresnelDielectric(wi[y * w + x].z, float(ior), cosT);
                const double v = F + (1.0 - F) / (scaled ? ior * ior : 1.0);
                blocks[(y / b) * (w / b) + x / b].mean += glm::dvec3(v / double(b * b));
                image.mean += glm::dvec3(v / double(w * h));
            }
        return std::pair{blocks, image};
    };
    const Film film = renderFilm(s, 256, 29);
    const auto [blocks, image] = expected(true);
    const ZSummary z = compareBlocksAndImage(film, blocks, image, 8);
    const RegionMean got = imageMean(film);
    std::printf("smooth plate: image mean %.5f, expected %.5f, max |Z| %.2f\n", got.mean.x, image.mean.x, z.maxAbsZ);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (threshold " << z.threshold << ")";
    const auto [unscaledBlocks, unscaledImage] = expected(false);
    const ZSummary c = compareBlocksAndImage(film, unscaledBlocks, unscaledImage, 8);
    EXPECT_GE(c.failing, c.tests / 2) << "the unscaled answer must be rejected almost everywhere";
}

TEST_F(GlossyRender, SmoothConductorPlateIsItsFresnelTerm) {
    const Scene s = loadTestScene("scenes/rough-conductor.json",
                                  {{"bsdfs[0].type", "conductor"}, {"bsdfs[0].material", "Au"},
                                   {"bsdfs[0].albedo", "0.5"}});
    ASSERT_EQ(s.materials.at(0).type, BsdfType::Conductor);
    const Film film = renderFilm(s, 4, 3);
    const std::vector<glm::vec3> wi = pixelViewDirections(s);
    // Gold at normal incidence, from its tabulated index: ((n-1)^2 + k^2) / ((n+1)^2 + k^2) per channel.
    const glm::vec3 eta = s.materials[0].eta, k = s.materials[0].k;
    EXPECT_NEAR(eta.x, 0.1431189557f, 1e-6f);
    EXPECT_NEAR(k.z, 1.6032152899f, 1e-6f);
    size_t checked = 0;
    for (uint32_t i = 0; i < wi.size(); ++i) {
        const glm::dvec3 v = film.mean(0, i);
        const glm::vec3 f = 0.5f * shader::fresnelConductor(eta, k, wi[i].z);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(v[c], f[c], 1e-4 * f[c]) << "pixel " << i << " channel " << c;
        ++checked;
    }
    EXPECT_EQ(checked, 32u * 32u);
}

// The glossy path tracer with media: a rough dielectric of index 1.0001 and roughness 0.001 around
// the absorbing slabs (its crossings are bounces, as the forward boundary's are, and it refracts
// all but ~1e-9 of the light straight on) renders the forward-boundary image: independent renders,
// 8x8 blocks and the image mean, one Sidak family. Control: a glass boundary (ior 1.5, roughness
// 0.3) against the same image.
TEST_F(GlossyRender, IndexMatchedRoughDielectricAroundMediaIsTheForwardBoundary) {
    const std::vector<SceneOverride> small = {{"camera.resolution", "[32,32]"}};
    const Film forward = renderFilm(loadTestScene("scenes/absorbing-slab.json", small), 256, 31);
    auto withBoundary = [&](const char* bsdf) {
        std::vector<SceneOverride> o = small;
        o.push_back({"bsdfs[0]", bsdf});
        return loadTestScene("scenes/absorbing-slab.json", o);
    };
    const Scene matched = withBoundary(R"({"name":"boundary","type":"rough_dielectric","ior":1.0001,"roughness":0.001})");
    ASSERT_EQ(matched.materials.at(0).type, BsdfType::RoughDielectric);
    const Film glossy = renderFilm(matched, 256, 32);
    EXPECT_EQ(glossy.nonFiniteSamples(), 0u);
    const ZSummary z = compareBlocksAndImage(glossy, blockMeans(forward, 8), imageMean(forward), 8);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (threshold " << z.threshold << ")";
    std::printf("matched rough dielectric: image mean %.5f, forward %.5f, max |Z| %.2f\n", imageMean(glossy).mean.x,
                imageMean(forward).mean.x, z.maxAbsZ);

    const Film glass =
        renderFilm(withBoundary(R"({"name":"boundary","type":"rough_dielectric","ior":1.5,"roughness":0.3})"), 256, 33);
    const ZSummary c = compareBlocksAndImage(glass, blockMeans(forward, 8), imageMean(forward), 8);
    std::printf("control glass boundary: %zu of %zu tests fail, worst %s\n", c.failing, c.tests, c.worst.c_str());
    EXPECT_GT(c.failing, 0u);
}

// A roughness texture (docs/SCENE-FORMAT.md, "Textures"): the Oren-Nayar plate with a checker of
// roughness 0.1 and 1 (cells of one unit: res 40 on the 40 x 40 plate). Each pixel is the
// directional albedo of the roughness of the cell its centre ray hits (Tungsten's quad uv:
// u = (x + 20) / 40, v = 1 - (z + 20) / 40), tabulated for both values as above. Control: the
// same render against the cells swapped.
TEST_F(GlossyRender, CheckerRoughnessPlateMatchesItsCells) {
    const Scene s = loadTestScene(
        "scenes/oren-nayar.json",
        {{"bsdfs[0].roughness", R"({"type": "checker", "on_color": 0.1, "off_color": 1.0, "res_u": 40, "res_v": 40})"}});
    ASSERT_EQ(s.materials.at(0).roughnessTexture, 0);
    const std::vector<glm::vec3> wi = pixelViewDirections(s);
    double maxTheta = 0.0;
    for (const glm::vec3& w : wi) maxTheta = std::max(maxTheta, std::acos(double(std::clamp(w.z, -1.0f, 1.0f))));
    Material rough = s.materials[0];
    rough.roughnessTexture = -1;
    rough.roughness = 0.1f;
    const std::array<AlbedoTable, 3> on = albedoTables(telescope::gpuMaterial(rough), maxTheta + 0.01);
    rough.roughness = 1.0f;
    const std::array<AlbedoTable, 3> off = albedoTables(telescope::gpuMaterial(rough), maxTheta + 0.01);

    const Camera& c = s.camera;
    const float d = shader::cameraPlaneDistance(c.fovDegrees);
    auto expected = [&](bool swapped) {
        const uint32_t w = c.width, h = c.height, b = 8;
        std::vector<RegionMean> blocks((w / b) * (h / b));
        RegionMean image;
        for (uint32_t y = 0; y < h; ++y)
            for (uint32_t x = 0; x < w; ++x) {
                const glm::dvec3 dir(shader::cameraRayDirection(glm::vec2(x + 0.5f, y + 0.5f), w, h, d, c.right, c.up, c.forward));
                const glm::dvec3 o(c.position);
                const glm::dvec3 p = o + dir * (-o.y / dir.y);
                const double u = (p.x + 20.0) / 40.0, v = 1.0 - (p.z + 20.0) / 40.0;
                const bool isOn = (int(std::floor(u * 40.0)) + int(std::floor(v * 40.0))) % 2 == 1;
                const std::array<AlbedoTable, 3>& t = isOn != swapped ? on : off;
                const double th = std::acos(double(std::clamp(wi[y * w + x].z, -1.0f, 1.0f)));
                const glm::dvec3 val(t[0](th), t[1](th), t[2](th));
                blocks[(y / b) * (w / b) + x / b].mean += val / double(b * b);
                image.mean += val / double(w * h);
            }
        return std::pair{blocks, image};
    };
    const Film film = renderFilm(s, 256, 41);
    EXPECT_EQ(film.nonFiniteSamples(), 0u);
    const auto [blocks, image] = expected(false);
    const ZSummary z = compareBlocksAndImage(film, blocks, image, 8);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (threshold " << z.threshold << ")";
    const auto [wrongBlocks, wrongImage] = expected(true);
    const ZSummary ctl = compareBlocksAndImage(film, wrongBlocks, wrongImage, 8);
    std::printf("checker roughness: max |Z| %.2f; control with the cells swapped: %zu of %zu tests fail\n", z.maxAbsZ,
                ctl.failing, ctl.tests);
    EXPECT_GT(ctl.failing, 0u) << "the test cannot see the roughness cells swapped";
}

// ---- Thin sheets, transparency and mixed materials (shared/bsdf.h, shaders/path_tracer.glsl) ----
namespace {

// Block means (8x8) and the image mean of a closed form given per pixel by its view direction.
std::pair<std::vector<RegionMean>, RegionMean> regionsOf(const Scene& s,
                                                         const std::function<glm::dvec3(glm::vec3 wi)>& value) {
    const std::vector<glm::vec3> wi = pixelViewDirections(s);
    const uint32_t w = s.camera.width, h = s.camera.height, b = 8;
    std::vector<RegionMean> blocks((w / b) * (h / b));
    RegionMean image;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const glm::dvec3 v = value(wi[y * w + x]);
            blocks[(y / b) * (w / b) + x / b].mean += v / double(b * b);
            image.mean += v / double(w * h);
        }
    return {blocks, image};
}

// `scene` with overrides against the closed form `answer` (a function of the scene as loaded).
void checkClosedForm(const std::string& scene, const std::vector<SceneOverride>& overrides,
                     const std::vector<SceneOverride>& wrongOverrides, uint32_t seed,
                     const std::function<std::function<glm::dvec3(glm::vec3)>(const Scene&)>& answer) {
    checkAgainst(scene, overrides, wrongOverrides, seed, [&](const Scene& s) { return regionsOf(s, answer(s)); });
}

// Cosine-weighted hemispherical mean 2 int_0^1 g(mu) mu dmu (midpoint rule).
glm::dvec3 hemisphericalMean(const std::function<glm::dvec3(float mu)>& g) {
    const int n = 20000;
    glm::dvec3 sum(0.0);
    for (int i = 0; i < n; ++i) {
        const double mu = (i + 0.5) / n;
        sum += g(float(mu)) * (2.0 * mu / n);
    }
    return sum;
}

}  // namespace

// scenes/thinsheet.json: a thin sheet at y = 0 over a Lambert ground of albedo rho at y = -1, under
// a sky of radiance 1 (both plates 400 x 400, wide enough to be infinite here). The sheet reflects
// R(mu) of the sky and passes T(mu) of what the ground sends up; the ground is uniformly lit and
// Lambertian, so its radiance is L = rho (Tbar + Rbar L), Tbar and Rbar the cosine-weighted means
// over the hemisphere: a pixel at view cosine mu is R(mu) + T(mu) rho Tbar / (1 - rho Rbar). Light
// reaches the ground through the sheet by next-event estimation, whose shadow rays the sheet
// attenuates by T (Tungsten's forward lobe), and by BSDF sampling through the sheet, with MIS: a
// blocked or unattenuated shadow ray fails this test. Weights are bounded (at most 1 / mean(T)),
// so the variance is finite. Control: ior 1.8 against the same answer.
TEST_F(GlossyRender, ThinSheetOverAGroundMatchesItsClosedForm) {
    auto answer = [](const Scene& s) {
        const shader::MaterialGpu sheet = telescope::gpuMaterial(s.materials.at(s.geometry.at(0).material));
        const glm::dvec3 rho(s.materials.at(s.geometry.at(1).material).albedo);
        auto rt = [sheet](float mu, bool reflect) {
            glm::vec3 T;
            const glm::vec3 R = shader::thinSheetReflectance(sheet, mu, T);
            return glm::dvec3(reflect ? R : T);
        };
        const glm::dvec3 rBar = hemisphericalMean([&](float mu) { return rt(mu, true); });
        const glm::dvec3 tBar = hemisphericalMean([&](float mu) { return rt(mu, false); });
        const glm::dvec3 ground = rho * tBar / (1.0 - rho * rBar);
        return std::function<glm::dvec3(glm::vec3)>([=](glm::vec3 wi) { return rt(wi.z, true) + rt(wi.z, false) * ground; });
    };
    checkClosedForm("scenes/thinsheet.json", {}, {{"bsdfs[0].ior", "1.8"}}, 41, answer);
    // Thin-film interference: coloured R and T in the same closed form.
    checkClosedForm("scenes/thinsheet.json", {{"bsdfs[0].enable_interference", "true"}}, {{"bsdfs[0].thickness", "0.6"}}, 43,
                    answer);
}

// A non-absorbing thin sheet over nothing but the sky (the ground shrunk to a speck no pixel's
// ray meets) is a white furnace: R + T = 1, and every
// weight is 1, so every pixel is exactly 1.
TEST_F(GlossyRender, NonAbsorbingThinSheetIsAWhiteFurnace) {
    const Scene s = loadTestScene("scenes/thinsheet.json", {{"bsdfs[0].sigma_a", "0"}, {"primitives[1].transform.scale", "[0.001,1,0.001]"}});
    const Film film = renderFilm(s, 16, 45);
    for (uint32_t i = 0; i < s.camera.width * s.camera.height; ++i) {
        const glm::dvec3 v = film.mean(0, i);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(v[c], 1.0, 1e-5) << "pixel " << i;
    }
}

// scenes/transparency.json: a transparency sheet (opacity alpha over a Lambert base of albedo a)
// over a Lambert ground (rho) under a sky of radiance 1. Everything is uniform and diffuse or
// straight-through, so the sheet's radiance is the same everywhere: with s = alpha a and t =
// 1 - alpha, the ground sends up L = rho (t + s L), and a pixel is s + t^2 rho / (1 - rho s) (the
// base is two-sided). Shadow rays from the ground pass the sheet with weight 1 - alpha. Weights
// are at most 1. Control: alpha 0.5.
TEST_F(GlossyRender, TransparencyOverAGroundMatchesItsClosedForm) {
    auto answer = [](const Scene& s) {
        const Material& leaf = s.materials.at(s.geometry.at(0).material);
        const glm::dvec3 sRef = double(leaf.alpha) * glm::dvec3(s.materials.at(leaf.component[0]).albedo);
        const glm::dvec3 rho(s.materials.at(s.geometry.at(1).material).albedo);
        const double t = 1.0 - leaf.alpha;
        const glm::dvec3 v = sRef + t * t * rho / (1.0 - rho * sRef);
        return std::function<glm::dvec3(glm::vec3)>([=](glm::vec3) { return v; });
    };
    checkClosedForm("scenes/transparency.json", {}, {{"bsdfs[0].alpha", "0.5"}}, 47, answer);
}

// The white furnace of transparency: a white base over a white ground under the sky of radiance
// 1 reflects everything, so every pixel is 1 (the closed form above with a = rho = 1: alpha +
// (1 - alpha)^2 / (1 - alpha)), whatever alpha; the passes and the base's scattering together lose
// nothing. Light bounces between the ground and the sheet's base (each pass and each scattering
// is a bounce): the scene's max_bounces 16 cuts off 1.0% (measured 0.9896), so the furnace runs at
// 64 (cut-off about 0.4 x 0.6^31 < 1e-7). Control: a base of albedo 0.9, against the same answer 1.
TEST_F(GlossyRender, WhiteTransparencyIsAWhiteFurnace) {
    checkClosedForm("scenes/transparency.json",
                    {{"bsdfs[0].base.albedo", "1"}, {"bsdfs[1].albedo", "1"}, {"integrator.max_bounces", "64"}},
                    {{"bsdfs[0].base.albedo", "0.9"}}, 49, [](const Scene&) {
                        return std::function<glm::dvec3(glm::vec3)>([](glm::vec3) { return glm::dvec3(1.0); });
                    });
}

// scenes/mixed.json: a plate of ratio x rough copper + (1 - ratio) x Lambert under the sky: a pixel
// is ratio E_copper(mu) + (1 - ratio) albedo, E_copper the copper's directional albedo by
// quadrature. Also with a mirror (a Dirac component) for the copper: ratio + (1 - ratio) albedo.
// Control: ratio 0.6 against the same answer.
TEST_F(GlossyRender, MixedPlateMatchesTheMixtureOfItsComponents) {
    checkClosedForm("scenes/mixed.json", {}, {{"bsdfs[1].ratio", "0.6"}}, 51, [](const Scene& s) {
        const Material& mix = s.materials.at(s.geometry.at(0).material);
        const shader::MaterialGpu copper = telescope::gpuMaterial(s.materials.at(mix.component[0]));
        const glm::dvec3 lambert(s.materials.at(mix.component[1]).albedo);
        double maxTheta = 0.0;
        for (const glm::vec3& w : pixelViewDirections(s)) maxTheta = std::max(maxTheta, std::acos(double(std::clamp(w.z, -1.0f, 1.0f))));
        const std::array<AlbedoTable, 3> e = albedoTables(copper, maxTheta + 0.01);
        const double r = mix.ratio;
        return std::function<glm::dvec3(glm::vec3)>([=](glm::vec3 wi) {
            const double th = std::acos(double(std::clamp(wi.z, -1.0f, 1.0f)));
            return r * glm::dvec3(e[0](th), e[1](th), e[2](th)) + (1.0 - r) * lambert;
        });
    });
    checkClosedForm("scenes/mixed.json", {{"bsdfs[0].type", "mirror"}}, {{"bsdfs[1].ratio", "0.6"}}, 53, [](const Scene& s) {
        const Material& mix = s.materials.at(s.geometry.at(0).material);
        EXPECT_EQ(s.materials.at(mix.component[0]).type, BsdfType::Mirror);
        const glm::dvec3 v = double(mix.ratio) + (1.0 - mix.ratio) * glm::dvec3(s.materials.at(mix.component[1]).albedo);
        return std::function<glm::dvec3(glm::vec3)>([=](glm::vec3) { return v; });
    });
}
