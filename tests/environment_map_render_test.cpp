// Renders under Tungsten's infinite_sphere with an image (shaders/shared/environment_map.h):
// a Lambertian plate (albedo 1/2) seen from above with the dirac filter, lit only by the sky, so
// every pixel is albedo / pi times the irradiance E = int L(w) max(w . n, 0) dw, which the host
// integrates from the image as loaded with the shared lookup (a quadrature far finer than the
// render's noise). The path tracer combines light sampling (envSample) and BSDF sampling that
// escapes (envPdf) by MIS, so a wrong pdf on either side biases the image.
//
// Z-tests: the estimator has finite variance (its light-sampling weight L / p is bounded: the
// sampling weight of a texel is at least the largest radiance a bilinear lookup takes in it, times
// sin theta at the row's edge nearer the equator, Tungsten's dilated table; the BSDF-sampled part
// is bounded by the largest texel), 8 x 8 blocks and the image, one Sidak family.
#include <gtest/gtest.h>

#include <regex>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <vector>

#include <ImfRgbaFile.h>
#include <fmt/format.h>

#include "cli_process.h"
#include "region_stats.h"
#include "render/environment_map.h"
#include "render/image_output.h"
#include "render_harness.h"

namespace envmap_render_test {
std::vector<float> data;  // the environment buffer the shared code reads on the host
}
#define ENV_DATA(i) (::envmap_render_test::data[i])
#include "shared/environment_map.h"

namespace telescope::test {
namespace {

constexpr uint32_t kBlock = 8;
constexpr double kAlpha = 1e-3;
constexpr double kAlbedo = 0.5;
constexpr double kPi = 3.14159265358979323846;

// albedo / pi times the irradiance of the plate (normal +y) under the scene's environment image.
glm::dvec3 plateAnswer(const Scene& scene) {
    const PointLikeLight* env = nullptr;
    for (const PointLikeLight& l : scene.lights)
        if (l.image) env = &l;
    if (!env) throw std::runtime_error("the scene has no environment image");
    envmap_render_test::data = buildEnvironmentBuffer(*env->image, env->rotation);
    const double pi = kPi;
    const int thetaSteps = 4096, phiSteps = 2048;
    glm::dvec3 sum(0.0);
    for (int i = 0; i < thetaSteps / 2; ++i) {  // the upper hemisphere around +y
        const double th = (i + 0.5) * pi / thetaSteps;
        const double c = std::cos(th), s = std::sin(th);
        glm::dvec3 ring(0.0);
        for (int j = 0; j < phiSteps; ++j) {
            const double phi = (j + 0.5) * 2.0 * pi / phiSteps;
            const glm::vec3 w(float(s * std::cos(phi)), float(c), float(s * std::sin(phi)));
            ring += glm::dvec3(shader::envRadiance(w));
        }
        sum += ring * (c * s);
    }
    return kAlbedo / pi * sum * (pi / thetaSteps) * (2.0 * pi / phiSteps);
}

ZSummary againstValue(const Film& film, glm::dvec3 value) {
    std::vector<RegionMean> regions = blockMeans(film, kBlock);
    regions.push_back(imageMean(film));
    return compareToValue(regions, value, sidakThreshold(kAlpha, regions.size() * 3));
}

// scenes/environment-map/scene.json (a peaky 64 x 32 sky with a sun, turned 40 degrees about y),
// and the same sky tilted 20 degrees about x (the sun's elevation changes, ground rises on one side): each matches its own
// quadrature. Control: the tilted render against the untilted answer.
TEST(EnvironmentMapRender, PlateUnderTheSkyMatchesQuadratureAndFollowsTheRotation) {
    const Scene sky = loadTestScene("scenes/environment-map/scene.json");
    const Scene tilted =
        loadTestScene("scenes/environment-map/scene.json", {{"primitives[1].transform.rotation", "[20, 40, 0]"}});
    const glm::dvec3 skyAnswer = plateAnswer(sky), tiltedAnswer = plateAnswer(tilted);
    std::printf("plate radiance: sky %.5f %.5f %.5f, tilted %.5f %.5f %.5f\n", skyAnswer.x, skyAnswer.y, skyAnswer.z,
                tiltedAnswer.x, tiltedAnswer.y, tiltedAnswer.z);
    const Film a = renderFilm(sky, 256, 91), b = renderFilm(tilted, 256, 92);
    const ZSummary za = againstValue(a, skyAnswer), zb = againstValue(b, tiltedAnswer);
    EXPECT_EQ(za.failing, 0u) << za.worst;
    EXPECT_EQ(zb.failing, 0u) << zb.worst;
    std::printf("sky: max |Z| %.2f, tilted: max |Z| %.2f (%zu tests each)\n", za.maxAbsZ, zb.maxAbsZ, za.tests);
    const ZSummary control = againstValue(b, skyAnswer);
    std::printf("control, tilted render against the untilted answer: %zu of %zu tests fail (worst %s)\n",
                control.failing, control.tests, control.worst.c_str());
    EXPECT_GT(control.failing, 0u) << control.worst;
    expectNoValidationMessages();
}

// A constant image (an EXR the test writes) is the constant infinite_sphere: albedo L on the plate,
// for both. Control: the image upside down (a sky bright above, dark below) against the answer of
// the image the right way up.
class EnvironmentMapFiles : public testing::Test {
protected:
    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               fmt::format("telescope-envmap-{}-{}", ::getpid(),
                           testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }

    // A width x height half-float EXR of value(x, y).
    std::string writeExr(const std::string& name, int width, int height,
                         const std::function<glm::vec3(int, int)>& value) {
        std::vector<Imf::Rgba> pixels(size_t(width) * height);
        for (int y = 0; y < height; ++y)
            for (int x = 0; x < width; ++x) {
                const glm::vec3 v = value(x, y);
                pixels[size_t(y) * width + x] = Imf::Rgba(v.x, v.y, v.z, 1.0f);
            }
        const std::string path = (dir_ / name).string();
        Imf::RgbaOutputFile file(path.c_str(), width, height, Imf::WRITE_RGBA);
        file.setFrameBuffer(pixels.data(), 1, size_t(width));
        file.writePixels(height);
        return path;
    }

    Scene plateScene(const std::string& emission) {
        std::string text = loadFileText(sourcePath("scenes/environment-map/scene.json"));
        nlohmann::json doc = nlohmann::json::parse(text);
        doc["primitives"][1]["emission"] = nlohmann::json::parse(emission);
        doc["primitives"][1].erase("transform");
        return loadSceneFromString(doc.dump(), (dir_ / "plate.json").string(), dir_.string());
    }

    static std::string loadFileText(const std::string& path) {
        std::ifstream in(path);
        return std::string(std::istreambuf_iterator<char>(in), {});
    }

    std::filesystem::path dir_;
};

TEST_F(EnvironmentMapFiles, ConstantImageEqualsTheConstantInfiniteSphere) {
    writeExr("constant.exr", 16, 8, [](int, int) { return glm::vec3(0.75f, 0.5f, 0.25f); });
    const Scene image = plateScene(R"({"type": "bitmap", "file": "constant.exr"})");
    const Scene constant = plateScene("[0.75, 0.5, 0.25]");
    const glm::dvec3 answer = kAlbedo * glm::dvec3(0.75, 0.5, 0.25);
    const Film a = renderFilm(image, 64, 93), b = renderFilm(constant, 64, 94);
    const ZSummary za = againstValue(a, answer), zb = againstValue(b, answer);
    EXPECT_EQ(za.failing, 0u) << za.worst;
    EXPECT_EQ(zb.failing, 0u) << zb.worst;
    const RegionMean ma = imageMean(a), mb = imageMean(b);
    std::printf("constant image %.5f, constant infinite_sphere %.5f, closed form %.5f\n", ma.mean.x, mb.mean.x,
                answer.x);
    // Control: light sampling claims a pdf 1.2 times the true one (the NEE weight and its MIS
    // weight mis-weighted; escaped rays keep the true pdf).
    environmentTestPdfScale = 1.2f;
    const Film w = renderFilm(image, 64, 97);
    environmentTestPdfScale = 1.0f;
    const ZSummary zw = againstValue(w, answer);
    std::printf("control, NEE pdf x 1.2: image %.5f, %zu of %zu tests fail (worst %s)\n", imageMean(w).mean.x,
                zw.failing, zw.tests, zw.worst.c_str());
    EXPECT_GT(zw.failing, 0u) << zw.worst;

    // A sky of 4 at the zenith falling to 0 at the horizon and below (only elevation matters),
    // and the same image upside down.
    auto sky = [](bool flipped) {
        return [flipped](int, int y) {
            const int row = flipped ? 31 - y : y;
            return glm::vec3(std::max(0.0f, 4.0f * (1.0f - (row + 0.5f) / 16.0f)));
        };
    };
    writeExr("sky.exr", 64, 32, sky(false));
    writeExr("flipped.exr", 64, 32, sky(true));
    const Scene up = plateScene(R"("sky.exr")"), down = plateScene(R"("flipped.exr")");
    const glm::dvec3 upAnswer = plateAnswer(up), downAnswer = plateAnswer(down);
    const Film c = renderFilm(up, 64, 95), d = renderFilm(down, 64, 96);
    const ZSummary zc = againstValue(c, upAnswer), zd = againstValue(d, downAnswer);
    EXPECT_EQ(zc.failing, 0u) << zc.worst;
    EXPECT_EQ(zd.failing, 0u) << zd.worst;
    const ZSummary control = againstValue(d, upAnswer);
    std::printf("elevation sky %.5f (flipped %.5f); control, flipped render against it: %zu of %zu tests fail\n",
                upAnswer.x, downAnswer.x, control.failing, control.tests);
    EXPECT_GT(control.failing, 0u) << control.worst;
    expectNoValidationMessages();
}

// Bad input: one clear message naming the scene file and the key; exit code 2.
TEST_F(EnvironmentMapFiles, BadImagesAreAClearErrorWithExitCode2) {
    writeExr("sky.exr", 8, 4, [](int, int) { return glm::vec3(1.0f); });
    writeExr("big.exr", 4096, 2048, [](int, int) { return glm::vec3(1.0f); });  // 2 KiB over one binding
    writeSrgbPng((dir_ / "ldr.png").string(), 4, 2, std::vector<float>(4 * 2 * 3, 0.5f));
    std::ofstream(dir_ / "not-an-image.exr") << "plain text";
    struct Case {
        const char* name;
        const char* emission;
        const char* key;
        const char* says;
    };
    const Case cases[] = {
        {"missing", R"("nowhere.exr")", "primitives[1].emission", "nowhere.exr"},
        {"unreadable", R"("not-an-image.exr")", "primitives[1].emission", "not-an-image.exr"},
        {"missing-file-key", R"({"type": "bitmap"})", "primitives[1].emission", "missing 'file'"},
        {"wrong-texture", R"({"type": "checker"})", "primitives[1].emission.type", "unsupported texture type 'checker'"},
        {"too-large", R"("big.exr")", "primitives[1].emission", "must fit one 128 MiB storage-buffer binding"},
        {"not-hdr", R"({"type": "bitmap", "file": "ldr.png"})", "primitives[1].emission.file", "not a high-dynamic-range image"},
        {"wrong-interpolate", R"({"type": "bitmap", "file": "sky.exr", "interpolate": 3})",
         "primitives[1].emission.interpolate", "expected"},
    };
    for (const Case& c : cases) {
        nlohmann::json doc = nlohmann::json::parse(loadFileText(sourcePath("scenes/environment-map/scene.json")));
        doc["primitives"][1]["emission"] = nlohmann::json::parse(c.emission);
        const std::string scene = (dir_ / (std::string(c.name) + ".json")).string();
        std::ofstream(scene) << doc.dump(2);
        const CommandResult r = runTelescope("plan " + scene, dir_);
        EXPECT_EQ(r.exitCode, 2) << c.name << ": " << r.stderrText;
        EXPECT_NE(r.stderrText.find(scene), std::string::npos) << c.name << ": " << r.stderrText;
        EXPECT_NE(r.stderrText.find(c.key), std::string::npos) << c.name << ": " << r.stderrText;
        EXPECT_NE(r.stderrText.find(c.says), std::string::npos) << c.name << ": " << r.stderrText;
    }
    // Photon mapping emits photons from the environment (tests/photon_sky_test.cpp): its plan says so.
    const std::string scene = sourcePath("scenes/environment-map/scene.json");
    const CommandResult r = runShell("{ " + std::string(TELESCOPE_BINARY) + " plan " + scene +
                                         R"( --set 'integrator={"type":"progressive_photon_map","gather_radius":0.1}' 1>&2; })",
                                     dir_);
    EXPECT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_TRUE(std::regex_search(r.stderrText, std::regex("lights at infinity +on"))) << r.stderrText;
    // The plan lists the feature.
    const CommandResult plan = runShell("{ " + std::string(TELESCOPE_BINARY) + " plan " + scene + " 1>&2; }", dir_);
    EXPECT_EQ(plan.exitCode, 0) << plan.stderrText;
    EXPECT_NE(plan.stderrText.find("infinite_sphere with an image"), std::string::npos) << plan.stderrText;
}

}  // namespace
}  // namespace telescope::test
