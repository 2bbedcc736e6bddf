// Textured albedo in the path tracer against known answers (docs/TESTING.md).
//
// scenes/checker-plate.json: a lambert quad plate (2 x 2, normal +y) under a constant sky of
// radiance 1, seen from above through pixel centres (dirac filter). The plate cannot see itself,
// so every pixel is exactly the albedo at the point its centre ray hits. The test finds that point
// and its uv by hand (Tungsten's quad uv: u = (x + 1) / 2, v = 1 - (z + 1) / 2 on this plate) and
// the albedo from the texture's definition, then Z-tests 8x8 block means and the image mean, one
// Sidak family at 1e-3 (compareBlocksAndImage). The estimator (next-event estimation and cosine
// sampling with MIS, radiance 1) is bounded, so its variance is finite.
//
// Controls, each rendered and compared with the same test: a wrong mapping (u and v swapped;
// the checker offset by half a cell) and, for the 8-bit image, texels taken without the sRGB
// decoding. Each must be rejected.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>
#include <functional>

#include <fmt/format.h>

#include "region_stats.h"
#include "render_harness.h"
#include "shared/camera.h"

using namespace telescope;
using namespace telescope::test;

namespace {

class TextureRender : public ::testing::Test {
protected:
    void TearDown() override { expectNoValidationMessages(); }
};

using AlbedoAt = std::function<glm::dvec3(glm::dvec2 uv)>;

// Per 8x8 block and for the image: the mean of albedo(uv of the pixel centre's hit).
std::pair<std::vector<RegionMean>, RegionMean> expectedRegions(const Scene& s, const AlbedoAt& albedo) {
    const Camera& c = s.camera;
    const float d = shader::cameraPlaneDistance(c.fovDegrees);
    const uint32_t w = c.width, h = c.height, b = 8;
    std::vector<RegionMean> blocks((w / b) * (h / b));
    RegionMean image;
    for (uint32_t y = 0; y < h; ++y)
        for (uint32_t x = 0; x < w; ++x) {
            const glm::dvec3 dir(shader::cameraRayDirection(glm::vec2(x + 0.5f, y + 0.5f), w, h, d, c.right, c.up, c.forward));
            const glm::dvec3 o(c.position);
            const glm::dvec3 p = o + dir * (-o.y / dir.y);  // the plate y = 0
            const glm::dvec2 uv((p.x + 1.0) / 2.0, 1.0 - (p.z + 1.0) / 2.0);
            const glm::dvec3 a = albedo(uv);
            blocks[(y / b) * (w / b) + x / b].mean += a / double(b * b);
            image.mean += a / double(w * h);
        }
    return {blocks, image};
}

// Renders `s` and Z-tests it against albedo; returns the summary.
ZSummary renderAgainst(const Scene& s, const AlbedoAt& albedo, uint32_t seed, const Film* film = nullptr) {
    const auto [blocks, image] = expectedRegions(s, albedo);
    const Film rendered = film ? *film : renderFilm(s, 256, seed);
    EXPECT_EQ(rendered.nonFiniteSamples(), 0u);
    return compareBlocksAndImage(rendered, blocks, image, 8);
}

// Tungsten's checker from its definition: cell (floor(u res_u), floor(v res_v)) is on when the
// indices' sum is odd (uv in (0, 1) here).
AlbedoAt checker(glm::dvec3 on, glm::dvec3 off, int resU, int resV) {
    return [=](glm::dvec2 uv) {
        const int iu = int(std::floor(uv.x * resU)), iv = int(std::floor(uv.y * resV));
        return (iu + iv) % 2 == 1 ? on : off;
    };
}

double srgbDecode(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

}  // namespace

TEST_F(TextureRender, CheckerAlbedoPlateMatchesItsCells) {
    const Scene s = loadTestScene("scenes/checker-plate.json");
    const AlbedoAt right = checker({0.8, 0.5, 0.2}, {0.1, 0.3, 0.6}, 4, 2);
    const Film film = renderFilm(s, 256, 11);
    const ZSummary z = renderAgainst(s, right, 11, &film);
    EXPECT_EQ(z.failing, 0u) << z.worst << " (threshold " << z.threshold << ")";
    std::printf("checker plate: max |Z| %.2f over %zu tests\n", z.maxAbsZ, z.tests);

    // Controls: the same render against wrong mappings.
    const ZSummary swapped = renderAgainst(s, [&](glm::dvec2 uv) { return right({uv.y, uv.x}); }, 0, &film);
    const ZSummary shifted = renderAgainst(s, [&](glm::dvec2 uv) { return right({uv.x + 0.125, uv.y}); }, 0, &film);
    std::printf("control u, v swapped: %zu of %zu tests fail; half a cell along u: %zu fail\n", swapped.failing,
                swapped.tests, shifted.failing);
    EXPECT_GT(swapped.failing, 0u) << "the test cannot see u and v swapped";
    EXPECT_GT(shifted.failing, 0u) << "the test cannot see a checker offset by half a cell";
}

namespace {

// A w x h image written with OpenImageIO (row 0 at the top), channel values from value(i, j, k).
void writeImage(const std::filesystem::path& path, int w, int h, OIIO::TypeDesc format,
                const std::function<float(int, int, int)>& value) {
    std::vector<float> px(size_t(w) * h * 3);
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i)
            for (int k = 0; k < 3; ++k) px[(size_t(j) * w + i) * 3 + k] = value(i, j, k);
    auto out = OIIO::ImageOutput::create(path.string());
    ASSERT_TRUE(out) << OIIO::geterror();
    OIIO::ImageSpec spec(w, h, 3, format);
    ASSERT_TRUE(out->open(path.string(), spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << out->geterror();
    out->close();
}

// Nearest lookups of a w x h image: texel (floor(u w), floor((1 - v) h)).
AlbedoAt nearest(int w, int h, const std::function<glm::dvec3(int, int)>& texel) {
    return [=](glm::dvec2 uv) { return texel(int(std::floor(uv.x * w)), int(std::floor((1.0 - uv.y) * h))); };
}

}  // namespace

// An 8-bit sRGB PNG (decoded to linear, Tungsten's gamma_correct default) and a float EXR (linear
// as stored), 4 x 4 texels, nearest lookups.
TEST_F(TextureRender, BitmapAlbedoPlateMatchesItsTexels) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "telescope-texture-render";
    std::filesystem::create_directories(dir);
    auto byte = [](int i, int j, int k) { return k == 0 ? 40 + 60 * i : k == 1 ? 30 + 70 * j : 220 - 25 * (i + j); };
    writeImage(dir / "albedo.png", 4, 4, OIIO::TypeDesc::UINT8, [&](int i, int j, int k) { return byte(i, j, k) / 255.0f; });
    auto linear = [](int i, int j, int k) { return 0.05f + 0.2f * float(k == 0 ? i : k == 1 ? j : 3 - i) + 0.01f * float(j); };
    writeImage(dir / "albedo.exr", 4, 4, OIIO::TypeDesc::FLOAT, linear);

    auto bitmap = [&](const char* file) {
        return std::vector<SceneOverride>{
            {"bsdfs[0].albedo", fmt::format(R"({{"type": "bitmap", "file": "{}", "interpolate": false}})", (dir / file).string())}};
    };
    const Scene png = loadTestScene("scenes/checker-plate.json", bitmap("albedo.png"));
    const AlbedoAt decoded = nearest(4, 4, [&](int i, int j) {
        return glm::dvec3(srgbDecode(byte(i, j, 0) / 255.0), srgbDecode(byte(i, j, 1) / 255.0), srgbDecode(byte(i, j, 2) / 255.0));
    });
    const Film film = renderFilm(png, 256, 21);
    const ZSummary z = renderAgainst(png, decoded, 0, &film);
    EXPECT_EQ(z.failing, 0u) << "png: " << z.worst << " (threshold " << z.threshold << ")";
    // Control: the texels without the sRGB decoding.
    const ZSummary raw = renderAgainst(png, nearest(4, 4, [&](int i, int j) {
        return glm::dvec3(byte(i, j, 0), byte(i, j, 1), byte(i, j, 2)) / 255.0;
    }), 0, &film);
    std::printf("png: max |Z| %.2f; control without sRGB decoding: %zu of %zu tests fail\n", z.maxAbsZ, raw.failing, raw.tests);
    EXPECT_GT(raw.failing, 0u) << "the test cannot see a missing sRGB decoding";

    const Scene exr = loadTestScene("scenes/checker-plate.json", bitmap("albedo.exr"));
    const AlbedoAt stored = nearest(4, 4, [&](int i, int j) { return glm::dvec3(linear(i, j, 0), linear(i, j, 1), linear(i, j, 2)); });
    const Film exrFilm = renderFilm(exr, 256, 23);
    const ZSummary e = renderAgainst(exr, stored, 0, &exrFilm);
    EXPECT_EQ(e.failing, 0u) << "exr: " << e.worst << " (threshold " << e.threshold << ")";
    // Control: rows read bottom-up (v not flipped).
    const ZSummary flipped = renderAgainst(exr, [&](glm::dvec2 uv) { return stored({uv.x, 1.0 - uv.y}); }, 0, &exrFilm);
    std::printf("exr: max |Z| %.2f; control with v not flipped: %zu of %zu tests fail\n", e.maxAbsZ, flipped.failing,
                flipped.tests);
    EXPECT_GT(flipped.failing, 0u) << "the test cannot see rows read bottom-up";
    std::filesystem::remove_all(dir);
}
