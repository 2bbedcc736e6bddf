// Textures (shared/texture.h): the uv of a hit on each primitive type, through the loader, the
// GPU scene's uv records and primUv, against Tungsten's parameterisations written out by hand at
// known points; and the texture lookups (checker, nearest, bilinear, wrap, clamp, sRGB) against
// values computed by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "render/gpu_scene.h"
#include "scene/scene_loader.h"
#include "shared/intersect.h"
#include "shared/texture.h"

using namespace telescope;

namespace {

constexpr float kPiF = 3.14159265358979f;

// One primitive with a checker-textured lambert material, as the GPU sees it.
GpuScene textured(const std::string& primitive, const std::string& baseDir = ".") {
    const std::string text = R"({"bsdfs": [{"name": "t", "type": "lambert", "albedo": {"type": "checker"}}],
                                 "primitives": [)" + primitive + "]}";
    return buildGpuScene(loadSceneFromString(text, "texture-test.json", baseDir));
}

// The uv primUv gives where the ray from `origin` along `dir` hits slot `slot` of the scene.
glm::vec2 uvAlongRay(const GpuScene& g, uint32_t slot, glm::vec3 origin, glm::vec3 dir) {
    const shader::Prim& p = g.prims.at(slot);
    float t = 0.0f;
    glm::vec2 bary(0.0f);
    bool hit = false;
    if (p.type == shader::kPrimSphere) hit = shader::intersectSphere(origin, dir, p.p0, p.p1.x, 0.0f, 1e30f, t);
    else if (p.type == shader::kPrimDisk) hit = shader::intersectDisk(origin, dir, p.p0, p.p1.x, p.n, 0.0f, 1e30f, t);
    else hit = shader::intersectPlanar(origin, dir, p.p0, p.p1, p.p2, p.type == shader::kPrimQuad, 0.0f, 1e30f, t, bary);
    EXPECT_TRUE(hit);
    return shader::primUv(g.textureData.data(), slot, p.type, bary, origin + t * dir, p.p0);
}

// Slot of the prim whose geometric normal is n (cube faces).
uint32_t slotWithNormal(const GpuScene& g, glm::vec3 n) {
    for (uint32_t i = 0; i < g.prims.size(); ++i)
        if (glm::length(g.prims[i].n - n) < 1e-5f) return i;
    ADD_FAILURE() << "no face with that normal";
    return 0;
}

void expectUv(glm::vec2 got, glm::vec2 want) {
    EXPECT_NEAR(got.x, want.x, 1e-5f);
    EXPECT_NEAR(got.y, want.y, 1e-5f);
}

}  // namespace

// Tungsten's quad: uv at base + l0 e0 + l1 e1 is (l0, 1 - l1), e0 = M (1, 0, 0), e1 = M (0, 0, 1).
TEST(TextureUv, QuadIsItsEdgeCoordinates) {
    const GpuScene g = textured(R"({"type": "quad", "bsdf": "t", "transform": {"scale": [2, 1, 4]}})");
    // base (-1, 0, -2), e0 = (2, 0, 0), e1 = (0, 0, 4): (0.5, 0, -1) is l0 = 0.75, l1 = 0.25
    expectUv(uvAlongRay(g, 0, {0.5f, 1.0f, -1.0f}, {0, -1, 0}), {0.75f, 0.75f});
    expectUv(uvAlongRay(g, 0, {-0.9f, -1.0f, 1.8f}, {0, 1, 0}), {0.05f, 0.05f});  // from below: same uv
    // Rotated 90 degrees about y: the edges turn but the uv stays tied to them.
    const GpuScene r = textured(R"({"type": "quad", "bsdf": "t", "transform": {"scale": [2, 1, 4], "rotation": [0, 90, 0]}})");
    const shader::Prim& p = r.prims[0];
    // Recover e0, e1 from the corners: p0 is the base, the other two are base + e0 and base + e1 in some order;
    // the point base + 0.25 e0 + 0.6 e1 must have uv (0.25, 0.4) whichever order the prim stores.
    const glm::vec3 a = p.p1 - p.p0, b = p.p2 - p.p0;
    const glm::vec3 e0 = glm::length(a) < 3.0f ? a : b;  // |e0| = 2, |e1| = 4
    const glm::vec3 e1 = glm::length(a) < 3.0f ? b : a;
    const glm::vec3 q = p.p0 + 0.25f * e0 + 0.6f * e1;
    expectUv(uvAlongRay(r, 0, q + p.n, -p.n), {0.25f, 0.4f});
}

// Tungsten's cube: uvw = local point / size + 1/2, uv = (uvw[(d + 1) % 3], uvw[(d + 2) % 3]) on the
// faces normal to axis d.
TEST(TextureUv, CubeFacesAreTheirLocalCoordinates) {
    const GpuScene g = textured(R"({"type": "cube", "bsdf": "t", "transform": {"scale": [2, 2, 2]}})");
    // (1, 0.5, -0.25) on +x: uvw = (1, 0.75, 0.375), uv = (0.75, 0.375)
    expectUv(uvAlongRay(g, slotWithNormal(g, {1, 0, 0}), {3.0f, 0.5f, -0.25f}, {-1, 0, 0}), {0.75f, 0.375f});
    expectUv(uvAlongRay(g, slotWithNormal(g, {-1, 0, 0}), {-3.0f, 0.5f, -0.25f}, {1, 0, 0}), {0.75f, 0.375f});
    // (0.5, 1, -0.25) on +y: uvw = (0.75, 1, 0.375), uv = (uvw.z, uvw.x) = (0.375, 0.75)
    expectUv(uvAlongRay(g, slotWithNormal(g, {0, 1, 0}), {0.5f, 3.0f, -0.25f}, {0, -1, 0}), {0.375f, 0.75f});
    // (0.5, -0.8, -1) on -z: uvw = (0.75, 0.1, 0), uv = (uvw.x, uvw.y) = (0.75, 0.1)
    expectUv(uvAlongRay(g, slotWithNormal(g, {0, 0, -1}), {0.5f, -0.8f, -3.0f}, {0, 0, 1}), {0.75f, 0.1f});
}

// Tungsten's sphere: uv = (atan2(n.y, n.x) / 2 pi + 1/2, acos(n.z) / pi) of the local normal.
TEST(TextureUv, SphereIsAzimuthAndPolarAngle) {
    const GpuScene g = textured(R"({"type": "sphere", "bsdf": "t", "transform": {"position": [1, 2, 3], "scale": [2, 2, 2]}})");
    const glm::vec3 c(1, 2, 3);
    expectUv(uvAlongRay(g, 0, c + glm::vec3(5, 0, 0), {-1, 0, 0}), {0.5f, 0.5f});
    expectUv(uvAlongRay(g, 0, c + glm::vec3(0, 5, 0), {0, -1, 0}), {0.75f, 0.5f});
    expectUv(uvAlongRay(g, 0, c + glm::vec3(0, -5, 0), {0, 1, 0}), {0.25f, 0.5f});
    // n = (-1, -1, sqrt 2) / 2: azimuth -135 degrees, polar 45 degrees
    const glm::vec3 n = glm::vec3(-1.0f, -1.0f, std::sqrt(2.0f)) * 0.5f;
    expectUv(uvAlongRay(g, 0, c + 5.0f * n, -n), {-0.375f + 0.5f, 0.25f});
}

// Tungsten's disk: uv = (atan2(d . tangent, d . bitangent) / 2 pi + 1/2, |d| / r) in TangentFrame(n);
// for n = +y that frame has tangent +x and bitangent -z.
TEST(TextureUv, DiskIsAzimuthAndRadius) {
    const GpuScene g = textured(R"({"type": "disk", "bsdf": "t", "transform": {"scale": [2, 1, 2]}})");
    expectUv(uvAlongRay(g, 0, {1.0f, 1.0f, 0.0f}, {0, -1, 0}), {0.75f, 0.5f});   // d = (1, 0, 0): x 0, y 1
    expectUv(uvAlongRay(g, 0, {0.0f, 1.0f, 1.5f}, {0, -1, 0}), {1.0f, 0.75f});   // x = -1.5, y = +0: atan2 = pi
}

// Meshes: the vertices' "vt" coordinates interpolated with the barycentrics; without them, 0.
TEST(TextureUv, MeshInterpolatesVertexUvs) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / "telescope-texture-test";
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "tri.obj") << "v 0 0 0\nv 1 0 0\nv 0 0 -1\nvt 0.1 0.2\nvt 0.9 0.2\nvt 0.1 0.7\nf 1/1 2/2 3/3\n";
    std::ofstream(dir / "bare.obj") << "v 0 0 0\nv 1 0 0\nv 0 0 -1\nf 1 2 3\n";
    const GpuScene g = textured(R"({"type": "mesh", "bsdf": "t", "file": "tri.obj"})", dir.string());
    // (0.25, 0, -0.5): barycentrics (0.25, 0.25, 0.5) of v1 v2 v3
    expectUv(uvAlongRay(g, 0, {0.25f, 1.0f, -0.5f}, {0, -1, 0}),
             0.25f * glm::vec2(0.1f, 0.2f) + 0.25f * glm::vec2(0.9f, 0.2f) + 0.5f * glm::vec2(0.1f, 0.7f));
    const GpuScene bare = textured(R"({"type": "mesh", "bsdf": "t", "file": "bare.obj"})", dir.string());
    expectUv(uvAlongRay(bare, 0, {0.25f, 1.0f, -0.5f}, {0, -1, 0}), {0.0f, 0.0f});
    std::filesystem::remove_all(dir);
}

// ---- Lookups ----

namespace {

// A buffer with one bitmap texture of w x h texels (shared/texture.h's layout; no uv records).
std::vector<glm::vec4> bitmapBuffer(uint32_t w, uint32_t h, const std::vector<glm::vec4>& texels, uint32_t flags,
                                    float scale = 1.0f) {
    std::vector<glm::vec4> d;
    d.push_back({glm::uintBitsToFloat(4u), 0.0f, 0.0f, 0.0f});
    d.push_back({glm::vec3(scale), glm::uintBitsToFloat(shader::kTextureBitmap)});
    d.push_back({glm::vec3(0.0f), glm::uintBitsToFloat(flags)});
    d.push_back({glm::uintBitsToFloat(w), glm::uintBitsToFloat(h), glm::uintBitsToFloat(4u), 0.0f});
    d.insert(d.end(), texels.begin(), texels.end());
    return d;
}

float at(const std::vector<glm::vec4>& d, float u, float v) { return shader::textureValue(d.data(), 0, {u, v}).x; }

}  // namespace

// Texel (i, j) (column i, row j from the top) covers u in [i, i + 1) / w, v in (1 - (j + 1) / h, 1 - j / h].
TEST(TextureLookup, NearestTakesTheTexelUnderTheUv) {
    // 2 x 2: top row 1, 2; bottom row 3, 4
    const auto d = bitmapBuffer(2, 2, {glm::vec4(1), glm::vec4(2), glm::vec4(3), glm::vec4(4)}, 0u, 0.5f);
    EXPECT_FLOAT_EQ(at(d, 0.2f, 0.9f), 0.5f);  // top left, times the scale
    EXPECT_FLOAT_EQ(at(d, 0.7f, 0.9f), 1.0f);
    EXPECT_FLOAT_EQ(at(d, 0.2f, 0.1f), 1.5f);
    EXPECT_FLOAT_EQ(at(d, 0.7f, 0.1f), 2.0f);
    EXPECT_FLOAT_EQ(at(d, 1.2f, 1.9f), 0.5f);   // wraps
    EXPECT_FLOAT_EQ(at(d, -0.3f, -0.1f), 1.0f);  // wraps below zero: as (0.7, 0.9), the top right
}

TEST(TextureLookup, BilinearBetweenTexelCentres) {
    const auto d = bitmapBuffer(2, 2, {glm::vec4(1), glm::vec4(2), glm::vec4(3), glm::vec4(4)}, shader::kTextureInterpolate);
    EXPECT_FLOAT_EQ(at(d, 0.25f, 0.75f), 1.0f);  // texel centres
    EXPECT_FLOAT_EQ(at(d, 0.75f, 0.25f), 4.0f);
    EXPECT_FLOAT_EQ(at(d, 0.5f, 0.5f), 2.5f);    // the middle: the mean of the four
    EXPECT_FLOAT_EQ(at(d, 0.5f, 0.75f), 1.5f);   // between 1 and 2
    // (x, y) = (0.25, 0.25) texels past the top-left centre: (1 * 0.75 + 2 * 0.25) 0.75 + (3 * 0.75 + 4 * 0.25) 0.25
    EXPECT_NEAR(at(d, 0.375f, 0.625f), 1.75f, 1e-5f);
    // At u = 0 the lookup straddles the left and right columns: wrap mixes them, clamp does not.
    EXPECT_FLOAT_EQ(at(d, 0.0f, 0.75f), 1.5f);
    const auto c = bitmapBuffer(2, 2, {glm::vec4(1), glm::vec4(2), glm::vec4(3), glm::vec4(4)},
                                shader::kTextureInterpolate | shader::kTextureClamp);
    EXPECT_FLOAT_EQ(at(c, 0.0f, 0.75f), 1.0f);
    EXPECT_FLOAT_EQ(at(c, 1.0f, 0.0f), 4.0f);
}

// Tungsten's checker: cell (int(u res_u), int(v res_v)) is "on" when exactly one index is odd.
TEST(TextureLookup, CheckerCells) {
    const glm::vec3 on(1, 0, 0), off(0, 0, 1);
    const glm::uvec2 res(4, 2);
    EXPECT_EQ(shader::checkerValue(on, off, res, {0.1f, 0.1f}), off);   // (0, 0)
    EXPECT_EQ(shader::checkerValue(on, off, res, {0.3f, 0.1f}), on);    // (1, 0)
    EXPECT_EQ(shader::checkerValue(on, off, res, {0.3f, 0.6f}), off);   // (1, 1)
    EXPECT_EQ(shader::checkerValue(on, off, res, {0.6f, 0.6f}), on);    // (2, 1)
}

TEST(TextureLookup, SrgbToLinear) {
    EXPECT_FLOAT_EQ(shader::srgbToLinear(0.0f), 0.0f);
    EXPECT_FLOAT_EQ(shader::srgbToLinear(1.0f), 1.0f);
    EXPECT_NEAR(shader::srgbToLinear(0.04f), 0.04f / 12.92f, 1e-7f);
    EXPECT_NEAR(shader::srgbToLinear(0.5f), 0.2140411f, 1e-6f);  // ((0.5 + 0.055) / 1.055)^2.4
    EXPECT_NEAR(shader::srgbToLinear(128.0f / 255.0f), 0.2158605f, 1e-6f);
}
