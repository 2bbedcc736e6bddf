// The routines every pass shares (shaders/shared): the camera (camera.h), specular scattering
// (bsdf.h), points on emitters (emitter.h), the photons' stratified emission (sampling.h), the film's sample sums (sample_sums.h) and the level
// pmf truncated to a cap (level_pmf.h), run on the CPU exactly as the shaders run them. The
// statistical checks use fixed seeds and binomial or chi-square bounds, and each has a control
// that the same bound rejects.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "shared/bsdf.h"
#include "shared/camera.h"
#include "shared/density_grid.h"
#include "shared/emitter.h"
#include "shared/level_pmf.h"
#include "shared/rng.h"
#include "shared/sample_sums.h"
#include "shared/sampling.h"

using namespace telescope::shader;

namespace {

double angleBetween(vec3 a, vec3 b) { return std::acos(std::clamp(double(dot(normalize(a), normalize(b))), -1.0, 1.0)); }

// Upper quantile of chi-square with k degrees of freedom (Wilson-Hilferty), z = normal quantile.
double chiSquareQuantile(double k, double z) {
    const double h = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - h + z * std::sqrt(h), 3.0);
}

}  // namespace

// ---- Camera ----

TEST(SharedCamera, PinholeGeometryFollowsTungsten) {
    EXPECT_NEAR(cameraPlaneDistance(90.0f), 1.0f, 1e-6f);
    const vec3 right(1, 0, 0), up(0, 1, 0), forward(0, 0, 1);
    const uint w = 200, h = 100;
    const float fov = 60.0f, d = cameraPlaneDistance(fov);
    // The film centre looks forward; the left and right edges are fov/2 off it, horizontally.
    const vec3 centre = cameraRayDirection(vec2(100.0f, 50.0f), w, h, d, right, up, forward);
    EXPECT_NEAR(angleBetween(centre, forward), 0.0, 1e-3);
    const vec3 left = cameraRayDirection(vec2(0.0f, 50.0f), w, h, d, right, up, forward);
    EXPECT_NEAR(angleBetween(left, forward), glm::radians(30.0), 1e-4);
    EXPECT_LT(left.x, 0.0f);
    EXPECT_NEAR(left.y, 0.0f, 1e-6f);
    // Pixel (0, 0) is the top-left one: y down on the film is -up in the world; square pixels,
    // so the top edge is (h / w) fov/2 away in tangent.
    const vec3 top = cameraRayDirection(vec2(100.0f, 0.0f), w, h, d, right, up, forward);
    EXPECT_GT(top.y, 0.0f);
    EXPECT_NEAR(top.y / top.z, 0.5 * std::tan(glm::radians(30.0)), 1e-5);
    EXPECT_NEAR(length(top), 1.0f, 1e-6f);
}

TEST(SharedCamera, FilmPointsFollowTheFilter) {
    const uvec2 pixel(7, 3);
    float weight = -1.0f;
    EXPECT_EQ(cameraFilmPoint(kFilterBox, pixel, vec2(0.25f, 0.75f), weight), vec2(7.25f, 3.75f));
    EXPECT_EQ(weight, 1.0f);
    EXPECT_EQ(cameraFilmPoint(kFilterDirac, pixel, vec2(0.1f, 0.9f), weight), vec2(7.5f, 3.5f));
    // Tent: offsets in [-1, 1] around the centre, mean 0, variance 1/6 (midpoint rule over u).
    double mean = 0.0, var = 0.0;
    const int n = 4096;
    for (int i = 0; i < n; ++i) {
        const float u = (float(i) + 0.5f) / float(n);
        const vec2 f = cameraFilmPoint(kFilterTent, pixel, vec2(u, 0.5f), weight);
        EXPECT_EQ(weight, 1.0f);
        ASSERT_GE(f.x, 6.5f);
        ASSERT_LE(f.x, 8.5f);
        mean += (f.x - 7.5) / n;
        var += (f.x - 7.5) * (f.x - 7.5) / n;
    }
    EXPECT_NEAR(mean, 0.0, 1e-4);
    EXPECT_NEAR(var, 1.0 / 6.0, 1e-4);
    // Wide filters: the weight is the product of the per-axis weights of shared/pixel_filter.h.
    float wx, wy;
    const vec2 u(0.3f, 0.8f);
    const vec2 f = cameraFilmPoint(kFilterMitchellNetravali, pixel, u, weight);
    const float ox = sampleWideFilter(kFilterMitchellNetravali, u.x, wx);
    const float oy = sampleWideFilter(kFilterMitchellNetravali, u.y, wy);
    EXPECT_EQ(f, vec2(pixel) + vec2(ox, oy) + 0.5f);
    EXPECT_EQ(weight, wx * wy);
}

// ---- Specular scattering ----

namespace {

MaterialGpu material(uint type, float ior, bool refracts) {
    MaterialGpu m{};
    m.albedo = vec3(0.9f, 0.5f, 0.25f);
    m.type = type;
    m.ior = ior;
    m.flags = refracts ? kMaterialRefraction : 0u;
    return m;
}

}  // namespace

TEST(SharedBsdf, MirrorReflectsWithoutRandomNumbers) {
    Rng rng = rngCreate(1, 2, 3);
    const Rng before = rng;
    vec3 dir = normalize(vec3(1.0f, -2.0f, 0.5f));
    const vec3 n(0, 1, 0);
    const vec3 f = scatterSpecular(material(kBsdfMirror, 1.5f, false), true, n, dir, rng);
    EXPECT_EQ(f, vec3(0.9f, 0.5f, 0.25f));
    EXPECT_NEAR(length(dir - normalize(vec3(1.0f, 2.0f, 0.5f))), 0.0f, 1e-6f);
    EXPECT_EQ(rng.state, before.state);
}

// Reflection happens with probability F and refraction obeys Snell's law, from both sides; the
// binomial bound (5 sigma at 10^5 draws) rejects the reflectance of the wrong side (the control).
TEST(SharedBsdf, DielectricReflectsWithFresnelProbabilityAndRefractsBySnell) {
    const MaterialGpu glass = material(kBsdfDielectric, 1.5f, true);
    const vec3 n(0, 0, 1);
    for (bool front : {true, false}) {
        const float cosI = 0.8f, sinI = std::sqrt(1.0f - cosI * cosI);
        const vec3 in(sinI, 0.0f, -cosI);  // towards -n: n faces the incoming ray
        const float eta = front ? 1.5f : 1.0f / 1.5f;
        float cosT;
        const double F = fresnelDielectric(cosI, eta, cosT);
        ASSERT_LT(F, 1.0) << "not total internal reflection at this angle";
        Rng rng = rngCreate(5, 6, front ? 7u : 8u);
        const int draws = 100000;
        int reflected = 0;
        for (int i = 0; i < draws; ++i) {
            vec3 dir = in;
            const vec3 f = scatterSpecular(glass, front, n, dir, rng);
            ASSERT_EQ(f, glass.albedo) << "both branches carry the albedo: F is the probability";
            ASSERT_NEAR(length(dir), 1.0f, 1e-5f);
            if (dir.z > 0.0f) {
                ++reflected;
            } else {
                // Snell: sin(theta_t) = sin(theta_i) / eta, in the plane of incidence.
                ASSERT_NEAR(std::sqrt(dir.x * dir.x + dir.y * dir.y), sinI / eta, 1e-5f);
                ASSERT_NEAR(dir.y, 0.0f, 1e-6f);
                ASSERT_GT(dir.x, 0.0f);
            }
        }
        const double sigma = std::sqrt(draws * F * (1.0 - F));
        EXPECT_LT(std::abs(reflected - draws * F), 5.0 * sigma) << "front " << front;
        float cosOther;
        const double wrong = fresnelDielectric(cosI, front ? 1.0f / 1.5f : 1.5f, cosOther);  // the other side's F
        EXPECT_GT(std::abs(reflected - draws * wrong), 5.0 * sigma) << "control, front " << front;
    }
}

TEST(SharedBsdf, TotalInternalReflectionAndNonRefractingDielectric) {
    Rng rng = rngCreate(9, 9, 9);
    const vec3 n(0, 0, 1);
    const vec3 grazing = normalize(vec3(0.9f, 0.0f, -0.2f));
    for (int i = 0; i < 1000; ++i) {  // from inside at a grazing angle: always reflects
        vec3 dir = grazing;
        scatterSpecular(material(kBsdfDielectric, 1.5f, true), false, n, dir, rng);
        ASSERT_GT(dir.z, 0.0f);
    }
    const Rng before = rng;
    vec3 dir = normalize(vec3(0.6f, 0.0f, -0.8f));
    const vec3 f = scatterSpecular(material(kBsdfDielectric, 1.5f, false), true, n, dir, rng);
    float cosT;
    const float F = fresnelDielectric(0.8f, 1.5f, cosT);
    EXPECT_NEAR(f.x, 0.9f * F, 1e-6f);  // reflection weighted by F, no random number
    EXPECT_GT(dir.z, 0.0f);
    EXPECT_EQ(rng.state, before.state);
}

// ---- Emitters ----

TEST(SharedEmitter, PointsAreUniformOnEachPrimType) {
    Prim tri{};
    tri.type = kPrimTriangle;
    tri.p0 = vec3(0, 0, 0);
    tri.p1 = vec3(2, 0, 0);
    tri.p2 = vec3(0, 3, 0);
    tri.n = vec3(0, 0, 1);
    Prim sphere{};
    sphere.type = kPrimSphere;
    sphere.p0 = vec3(1, 2, 3);
    sphere.p1 = vec3(0.5f, 0, 0);
    Prim disk{};
    disk.type = kPrimDisk;
    disk.p0 = vec3(-1, 0, 4);
    disk.p1 = vec3(2.0f, 0, 0);
    disk.n = normalize(vec3(0, 1, 1));

    Prim quad{};
    quad.type = kPrimQuad;
    quad.p0 = vec3(1, 1, 1);
    quad.p1 = vec3(3, 1, 1);  // edges (2, 0, 0) and (1, 4, 0): a sheared parallelogram
    quad.p2 = vec3(2, 5, 1);
    quad.n = vec3(0, 0, 1);

    Rng rng = rngCreate(3, 1, 4);
    const int n = 200000;
    vec3 sumTri(0.0f), sumSphere(0.0f);
    double sumQuadY = 0.0, sumQuadYY = 0.0, sumHalfY = 0.0;
    double sumR2 = 0.0;
    for (int i = 0; i < n; ++i) {
        vec3 q, nq;
        sampleEmitterPoint(tri, true, true, rngNext(rng), rngNext(rng), q, nq);
        ASSERT_EQ(nq, tri.n);
        ASSERT_NEAR(q.z, 0.0f, 1e-6f);
        ASSERT_GE(q.x, -1e-6f);
        ASSERT_GE(q.y, -1e-6f);
        ASSERT_LE(q.x / 2.0f + q.y / 3.0f, 1.0f + 1e-5f);
        sumTri += q;
        sampleEmitterPoint(sphere, true, true, rngNext(rng), rngNext(rng), q, nq);
        ASSERT_NEAR(length(q - sphere.p0), 0.5f, 1e-5f);
        ASSERT_NEAR(length(nq - (q - sphere.p0) / 0.5f), 0.0f, 1e-5f);
        sumSphere += q;
        sampleEmitterPoint(disk, true, true, rngNext(rng), rngNext(rng), q, nq);
        ASSERT_EQ(nq, disk.n);
        ASSERT_NEAR(dot(q - disk.p0, disk.n), 0.0f, 1e-5f);
        const float r2 = dot(q - disk.p0, q - disk.p0);
        ASSERT_LE(r2, 4.0f + 1e-4f);
        sumR2 += r2;
        sampleEmitterPoint(quad, true, true, rngNext(rng), rngNext(rng), q, nq);
        ASSERT_EQ(nq, quad.n);
        ASSERT_NEAR(q.z, 1.0f, 1e-6f);
        const float v = (q.y - 1.0f) / 4.0f, u = (q.x - 1.0f - v) / 2.0f;  // edge coordinates
        ASSERT_GE(u, -1e-5f);
        ASSERT_LE(u, 1.0f + 1e-5f);
        ASSERT_GE(v, -1e-5f);
        ASSERT_LE(v, 1.0f + 1e-5f);
        sumQuadY += q.y;
        sumQuadYY += double(q.y) * q.y;
        sumHalfY += sampleTriangle(quad.p0, quad.p1, quad.p2, rngNext(rng), rngNext(rng)).y;
    }
    // Means: the centroid (2/3, 1) with per-axis sd <= 0.71, the centre, and E[r^2] = R^2 / 2
    // (uniform in area; sd of r^2 = R^2 / sqrt(12)); bounds 5 sigma / sqrt(n).
    const double k = 5.0 / std::sqrt(double(n));
    EXPECT_NEAR(sumTri.x / n, 2.0 / 3.0, 0.48 * k);
    EXPECT_NEAR(sumTri.y / n, 1.0, 0.71 * k);
    EXPECT_NEAR(length(sumSphere / float(n) - sphere.p0), 0.0, 0.5 * k * 1.8);
    EXPECT_NEAR(sumR2 / n, 2.0, 4.0 / std::sqrt(12.0) * k);
    EXPECT_GT(std::abs(sumR2 / n - 4.0 / 3.0), 4.0 / std::sqrt(12.0) * k)
        << "control: E[r^2] of points uniform in radius (R^2 / 3) is rejected";
    // Quad: y = 1 + 4v with v uniform, so E[y] = 3 and E[y^2] = 9 + 16/12 (sd of y <= 1.16,
    // of y^2 < 9).
    EXPECT_NEAR(sumQuadY / n, 3.0, 4.0 / std::sqrt(12.0) * k);
    EXPECT_NEAR(sumQuadYY / n, 9.0 + 16.0 / 12.0, 9.0 * k);
    EXPECT_GT(std::abs(sumHalfY / n - 3.0), 4.0 / std::sqrt(12.0) * k)
        << "control: points on the triangle of the same three points (one half) are rejected";
}

// ---- Sample sums ----

TEST(SharedSampleSums, ChannelsAndNonFiniteSamples) {
    SampleSums s = sampleSumsZero();
    sampleSumsAdd(s, vec3(1.0f, 2.0f, 3.0f), vec3(0.5f, -1.0f, 0.0f));
    sampleSumsAdd(s, vec3(2.0f), vec3(-0.25f, 0.25f, 1.0f));
    const float nan = std::nanf("");
    sampleSumsAdd(s, vec3(1.0f, nan, 1.0f), vec3(0.0f));
    sampleSumsAdd(s, vec3(1.0f), vec3(0.0f, 0.0f, INFINITY));
    EXPECT_EQ(s.dropped, 2.0f);
    EXPECT_EQ(s.z, vec3(1.5f + 1.75f, 1.0f + 2.25f, 3.0f + 3.0f));
    EXPECT_EQ(s.z2, vec3(2.25f + 3.0625f, 1.0f + 5.0625f, 9.0f + 9.0f));
    EXPECT_EQ(s.base, vec3(3.0f, 4.0f, 5.0f));
    EXPECT_EQ(s.correction, vec3(0.25f, -0.75f, 1.0f));
    EXPECT_EQ(s.correctionPos, vec3(0.5f, 0.25f, 1.0f));
    EXPECT_EQ(s.correctionNeg, vec3(-0.25f, -1.0f, 0.0f));
    EXPECT_EQ(s.count, 0.0f);
}

// TwoSum is exact (hi + lo carries the sum to ~40 bits); a plain float sum of the same samples
// (the control) is off by far more than the bound.
TEST(SharedSampleSums, CompensatedSumsKeepTheLowBits) {
    vec4 hi(0.0f), lo(0.0f);
    float naive = 0.0f;
    double exact = 0.0;
    Rng rng = rngCreate(1, 1, 1);
    const int n = 1000000;
    for (int i = 0; i < n; ++i) {
        const float x = 0.1f + rngNext(rng);
        vec4 err;
        hi = twoSum(hi, vec4(x, -x, 0.0f, 1.0f), err);
        lo += err;
        naive += x;
        exact += double(x);
    }
    const double sum = double(hi.x) + double(lo.x);
    EXPECT_LT(std::abs(sum - exact) / exact, 1e-9);
    EXPECT_EQ(double(hi.y) + double(lo.y), -sum);
    EXPECT_EQ(hi.w, float(n));
    EXPECT_GT(std::abs(double(naive) - exact) / exact, 1e-6) << "control: the uncompensated float sum";
    vec4 e;
    const vec4 s = twoSum(vec4(1.0f), vec4(1e-9f), e);
    EXPECT_EQ(double(s.x) + double(e.x), 1.0 + double(1e-9f));
}

// ---- Level pmf below a cap ----

TEST(SharedLevelPmf, TruncatedPmfSumsToOneAndIsSampledExactly) {
    const LevelPmf pmfs[] = {makeLevelPmf(kPmfGeometric, 0.3f, 0.0f), makeLevelPmf(kPmfPowerLaw, 0.0f, 0.6f)};
    const uint cap = 8;
    for (const LevelPmf& pmf : pmfs) {
        double total = 0.0;
        for (uint m = 0; m < cap; ++m) total += levelProbabilityBelow(pmf, m, cap);
        EXPECT_NEAR(total, 1.0, 1e-5) << "type " << pmf.type;
        EXPECT_NEAR(levelMassBelow(pmf, cap), 1.0 - levelTail(pmf, cap), 1e-6);

        std::vector<double> counts(cap, 0.0);
        Rng rng = rngCreate(11, 12, 13 + pmf.type);
        const int draws = 200000;
        for (int i = 0; i < draws; ++i) {
            const float u1 = rngNext(rng), u2 = rngNext(rng);
            const uint m = levelSampleBelow(pmf, cap, u1, u2);
            ASSERT_LT(m, cap);
            counts[m] += 1.0;
        }
        // Chi-square against the truncated pmf passes at the 1e-4 level; against the pmf of
        // another cap (the control: a mis-weighted pmf by a few per cent) it fails.
        auto chi2 = [&](uint pmfCap) {
            double c = 0.0;
            for (uint m = 0; m < cap; ++m) {
                const double e = draws * (m < pmfCap ? levelProbabilityBelow(pmf, m, pmfCap) : 0.0);
                c += (counts[m] - e) * (counts[m] - e) / e;
            }
            return c;
        };
        const double bound = chiSquareQuantile(cap - 1, 3.72);
        EXPECT_LT(chi2(cap), bound) << "type " << pmf.type;
        EXPECT_GT(chi2(cap + 4), bound) << "control, type " << pmf.type;
    }
}

// ---- Density grid ----

TEST(SharedDensityGrid, TrilinearBetweenVoxelCentres) {
    // 2 x 2 x 2 voxels: v = x + 2 y + 4 z at the centres (1/4 and 3/4 of the box).
    std::vector<float> v;
    for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 2; ++x) v.push_back(float(x + 2 * y + 4 * z));
    auto at = [&](vec3 unit) {
        GridStencil g;
        if (!gridStencil(uvec3(2), unit, g)) return -1.0f;
        const float* p = v.data() + g.corner;
        const uint x = g.step.x, y = g.step.y, z = g.step.z;
        return gridTrilinear(g.t, p[0], p[x], p[y], p[x + y], p[z], p[x + z], p[y + z], p[x + y + z]);
    };
    EXPECT_NEAR(at(vec3(0.5f)), 3.5f, 1e-6f);                  // the middle: the mean
    EXPECT_NEAR(at(vec3(0.25f, 0.75f, 0.25f)), 2.0f, 1e-6f);   // a voxel centre
    EXPECT_NEAR(at(vec3(0.375f, 0.5f, 0.625f)), 0.25f + 1.0f + 4.0f * 0.75f, 1e-5f);
    EXPECT_NEAR(at(vec3(0.0f, 0.0f, 1.0f)), 4.0f, 1e-6f);      // clamped at the faces
    EXPECT_EQ(at(vec3(1.01f, 0.5f, 0.5f)), -1.0f);             // outside the box
}

// ---- Stratified photon emission (sampling.h: curvePosition, curveCoordinate2/4) ----

// The paths' stretches of the curve tile [0, 2^32): path 0 starts at 0, the last ends at 2^32 - 1,
// and each path starts where the one before ended (or one further on). With this, the N 2^32
// numerators map onto every T exactly N times, so T is uniform over the pass.
TEST(SharedCurveEmission, PathStretchesTileTheCurve) {
    for (uint n : {1u, 3u, 7u, 1000u, 1u << 20, (1u << 24) + 1u}) {
        EXPECT_EQ(curvePosition(0u, n, 0u), 0u) << n;
        EXPECT_EQ(curvePosition(n - 1u, n, 0xffffffffu), 0xffffffffu) << n;
        const uint step = std::max(1u, n / 997u);
        for (uint i = 0; i + 1 < n; i += step) {
            const uint end = curvePosition(i, n, 0xffffffffu), next = curvePosition(i + 1u, n, 0u);
            ASSERT_TRUE(next == end || next == end + 1u) << "n " << n << " path " << i;
            ASSERT_LE(curvePosition(i, n, 0u), end);
        }
    }
    // Control: a stretch computed with one random bit too few leaves gaps the check sees.
    const uint n = 1000u, i = 417u;
    const uint end = uint(((uint64_t(i) << 32u) | uint64_t(0x7fffffffu)) / n);
    EXPECT_GT(curvePosition(i + 1u, n, 0u), end + 1u);
}

// The cell coordinates are the curve's de-interleaved bits: re-interleaving gives T back, so
// distinct curve positions are distinct cells (a bijection of [0, 2^32) onto 2^16 x 2^16 and 2^8^4).
TEST(SharedCurveEmission, CellCoordinatesDeinterleaveTheCurve) {
    Rng rng = rngCreate(11, 12, 13);
    for (int k = 0; k < 100000; ++k) {
        const uint t = k < 4 ? std::array<uint, 4>{0u, 1u, 0xffffffffu, 0x80000000u}[k] : rngNextUint(rng);
        uint two = 0u, four = 0u;
        for (uint b = 0; b < 16; ++b)
            for (uint axis = 0; axis < 2; ++axis) two |= ((curveCoordinate2(t, axis) >> b) & 1u) << (2u * b + axis);
        for (uint b = 0; b < 8; ++b)
            for (uint axis = 0; axis < 4; ++axis) four |= ((curveCoordinate4(t, axis) >> b) & 1u) << (4u * b + axis);
        ASSERT_EQ(two, t) << k;
        ASSERT_EQ(four, t) << k;
        ASSERT_LT(curveCoordinate2(t, 1u), 65536u);
        ASSERT_LT(curveCoordinate4(t, 3u), 256u);
    }
    // Neighbours along the curve share their cell but for the lowest bits: T and T + 1 from an even
    // T differ in axis 0 only.
    EXPECT_EQ(curveCoordinate2(6u, 0u) + 1u, curveCoordinate2(7u, 0u));
    EXPECT_EQ(curveCoordinate2(6u, 1u), curveCoordinate2(7u, 1u));
}
