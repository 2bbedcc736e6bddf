// Every glossy material through the dispatch the path tracer calls (shared/bsdf.h glossyEval,
// glossyPdf, glossySample on a MaterialGpu), run on the CPU:
// - chi-square of glossySample against glossyPdf (tests/unit/bsdf_stats.h; samples of a Dirac
//   lobe count with the lost ones against the mass the pdf leaves out), with a control: the same
//   histogram against the pdf of a wrong parameter is rejected;
// - the sample weight is eval / pdf and its mean is the quadrature of eval (plus the Dirac lobe);
// - white furnaces with known answers: a plastic of albedo 1 without absorption reflects all
//   light (its multiple-bounce substrate term makes it exactly energy-conserving); Oren-Nayar of
//   roughness 0 is Lambert; a nearly smooth rough dielectric reflects F and transmits 1 - F; a
//   rough plastic never creates energy;
// - reciprocity: f(a, b) = f(b, a) for reflection, f(a, b) / n_b^2 = f(b, a) / n_a^2 for refraction
//   (Tungsten's transmission is the adjoint form, without the radiance scaling).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bsdf_stats.h"
#include "test_materials.h"
#include "render/gpu_scene.h"
#include "shared/bsdf.h"

using namespace telescope::shader;
using namespace telescope::test;

namespace {

MaterialGpu plastic(telescope::BsdfType type, float albedo, float ior, float tau, float roughness = 0.0f,
                    uint dist = kMicrofacetGGX) {
    telescope::Material m;
    m.type = type;
    m.albedo = vec3(albedo);
    m.ior = ior;
    m.roughness = roughness;
    m.distribution = dist;
    m.sigmaA = vec3(tau);
    return telescope::gpuMaterial(m);
}

MaterialGpu roughDielectric(float roughness, float ior, uint dist = kMicrofacetGGX, bool refracts = true) {
    telescope::Material m;
    m.type = telescope::BsdfType::RoughDielectric;
    m.ior = ior;
    m.roughness = roughness;
    m.distribution = dist;
    m.enableRefraction = refracts;
    return telescope::gpuMaterial(m);
}

constexpr auto kPlastic = telescope::BsdfType::Plastic;
constexpr auto kRoughPlastic = telescope::BsdfType::RoughPlastic;

struct Case {
    std::string name;
    MaterialGpu m;
    MaterialGpu wrong;  // the control's pdf
};

std::vector<Case> cases() {
    std::vector<Case> c;
    c.push_back({"plastic", plastic(kPlastic, 0.5f, 1.5f, 0.0f), plastic(kPlastic, 0.5f, 2.0f, 0.0f)});
    c.push_back({"plastic absorbing", plastic(kPlastic, 0.8f, 1.5f, 0.3f), plastic(kPlastic, 0.8f, 1.5f, 0.0f)});
    // (the coat's lobe takes a few percent of the samples: the controls change its roughness by half)
    c.push_back({"rough_plastic ggx", plastic(kRoughPlastic, 0.5f, 1.5f, 0.0f, 0.2f),
                 plastic(kRoughPlastic, 0.5f, 1.5f, 0.0f, 0.3f)});
    c.push_back({"rough_plastic beckmann", plastic(kRoughPlastic, 0.3f, 1.5f, 0.1f, 0.4f, kMicrofacetBeckmann),
                 plastic(kRoughPlastic, 0.3f, 1.5f, 0.1f, 0.6f, kMicrofacetBeckmann)});
    c.push_back({"oren_nayar 0.3", orenNayar(0.8f, 0.3f), orenNayar(0.8f, 0.4f)});
    c.push_back({"oren_nayar 1", orenNayar(0.8f, 1.0f), orenNayar(0.8f, 0.9f)});
    c.push_back({"rough_dielectric ggx", roughDielectric(0.3f, 1.5f), roughDielectric(0.33f, 1.5f)});
    c.push_back({"rough_dielectric beckmann", roughDielectric(0.5f, 1.33f, kMicrofacetBeckmann),
                 roughDielectric(0.55f, 1.33f, kMicrofacetBeckmann)});
    c.push_back({"rough_dielectric reflection only", roughDielectric(0.3f, 1.5f, kMicrofacetGGX, false),
                 roughDielectric(0.33f, 1.5f, kMicrofacetGGX, false)});
    return c;
}

bool isDielectric(const MaterialGpu& m) { return m.type == kBsdfRoughDielectric; }

std::vector<vec3> viewDirections(const MaterialGpu& m) {
    std::vector<vec3> v = {fromAngle(0.0f), fromAngle(45.0f), fromAngle(75.0f)};
    if (isDielectric(m)) {  // from inside too
        v.push_back(fromAngle(150.0f));
        v.push_back(fromAngle(170.0f));
    }
    return v;
}

}  // namespace

TEST(GlossyBsdf, SamplingMatchesPdf) {
    uint32_t seed = 1000;
    for (const Case& c : cases())
        for (const vec3& wi : viewDirections(c.m)) {
            uint32_t index = 0;
            auto sample = [&](float, float, vec3& wo) {
                Rng rng = rngCreate(index++, 0, seed);
                vec3 weight;
                float pdf;
                bool specular;
                return glossySample(c.m, wi, rng, wo, weight, pdf, specular) && !specular;
            };
            const std::string what = fmt::format("{} wi.z {:.3f}", c.name, wi.z);
            const ChiSquareResult ok =
                chiSquareSphere(sample, [&](vec3 wo) { return double(glossyPdf(c.m, wi, wo)); }, 200000, seed);
            EXPECT_FALSE(ok.rejected()) << what << ": " << ok.describe();
            index = 0;
            const ChiSquareResult control =
                chiSquareSphere(sample, [&](vec3 wo) { return double(glossyPdf(c.wrong, wi, wo)); }, 200000, seed);
            EXPECT_TRUE(control.rejected()) << "control " << what << ": " << control.describe();
            ++seed;
        }
}

// Weight = eval / pdf for non-Dirac samples; the mean weight (Dirac lobes included) equals the
// quadrature of eval plus the Dirac lobe's reflectance; the control (weights x 1.05) does not.
TEST(GlossyBsdf, SampleWeightsAndDirectionalAlbedo) {
    for (const Case& c : cases())
        for (const vec3& wi : viewDirections(c.m)) {
            const std::string what = fmt::format("{} wi.z {:.3f}", c.name, wi.z);
            double dirac = 0.0;
            if (c.m.type == kBsdfPlastic) dirac = fresnelDielectricSigned(wi.z, c.m.ior);
            const double albedo =
                dirac + integrateSphere([&](vec3 wo) { return double(glossyEval(c.m, wi, wo).x); }, 4096, 256);
            const int n = 200000;
            double sum = 0.0, sum2 = 0.0;
            for (int i = 0; i < n; ++i) {
                Rng rng = rngCreate(uint32_t(i), 7, 99);
                vec3 wo, weight;
                float pdf;
                bool specular;
                if (!glossySample(c.m, wi, rng, wo, weight, pdf, specular)) continue;
                if (!specular) {
                    const float p = glossyPdf(c.m, wi, wo);
                    const vec3 f = glossyEval(c.m, wi, wo);
                    ASSERT_NEAR(pdf, p, 1e-3f * p) << what;
                    ASSERT_NEAR(weight.x, f.x / p, 2e-3f * weight.x + 1e-6f) << what;
                }
                sum += weight.x;
                sum2 += double(weight.x) * weight.x;
            }
            const double mean = sum / n, se = std::sqrt(std::max(1e-12, sum2 / n - mean * mean) / n);
            EXPECT_LT(std::abs(mean - albedo), 5.0 * se + 1e-3) << what << ": mean weight " << mean << " albedo " << albedo;
            if (albedo > 0.2) {
                EXPECT_GT(std::abs(1.05 * mean - albedo), 5.0 * se + 1e-3) << "control " << what;
            }
        }
}

// The coat's internal diffuse reflectance obeys n^2 (1 - Fdr_internal) = 1 - Fdr_external, which
// makes the white plastic conserve energy exactly: E(wi) = F(wi) + (1 - F(wi)) = 1.
TEST(GlossyBsdf, WhitePlasticFurnaceIsOne) {
    for (float ior : {1.2f, 1.5f, 2.0f}) {
        const double internal = telescope::plasticDiffuseFresnel(ior);
        const double external =
            integrateSphere([&](vec3 w) { return w.z > 0.0f ? fresnelDielectricSigned(w.z, ior) * w.z / kPi : 0.0; });
        EXPECT_NEAR(ior * ior * (1.0 - internal), 1.0 - external, 2e-4) << ior;
        for (float theta : {0.0f, 50.0f, 80.0f}) {
            const vec3 wi = fromAngle(theta);
            const MaterialGpu m = plastic(kPlastic, 1.0f, ior, 0.0f);
            const double e = fresnelDielectricSigned(wi.z, ior) +
                             integrateSphere([&](vec3 wo) { return double(glossyEval(m, wi, wo).x); }, 2048, 128);
            EXPECT_NEAR(e, 1.0, 1e-3) << "ior " << ior << " theta " << theta;
            // Control: the diffuse Fresnel term of another index breaks the balance.
            MaterialGpu wrong = m;
            wrong.diffuseFresnel = float(telescope::plasticDiffuseFresnel(ior * 1.05f));
            const double ew = fresnelDielectricSigned(wi.z, ior) +
                              integrateSphere([&](vec3 wo) { return double(glossyEval(wrong, wi, wo).x); }, 2048, 128);
            EXPECT_GT(std::abs(ew - 1.0), 5e-3) << "control ior " << ior << " theta " << theta;
            // Rough plastic: never above 1, close to 1 when nearly smooth (the microfacet lobe loses
            // a little to shadowing).
            for (float r : {0.02f, 0.3f}) {
                const MaterialGpu rp = plastic(kRoughPlastic, 1.0f, ior, 0.0f, r);
                const double er = integrateSphere([&](vec3 wo) { return double(glossyEval(rp, wi, wo).x); }, 4096, 512,
                                                  vec3(-wi.x, -wi.y, wi.z));
                EXPECT_LE(er, 1.0 + 2e-3) << "rough " << r << " ior " << ior << " theta " << theta;
                if (r <= 0.02f && theta <= 50.0f) {
                    EXPECT_NEAR(er, 1.0, 1e-2) << "rough " << r << " ior " << ior << " theta " << theta;
                }
            }
        }
    }
}

TEST(GlossyBsdf, OrenNayarOfRoughnessZeroIsLambert) {
    std::mt19937 gen(3);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    const MaterialGpu m = orenNayar(1.0f, 0.0f), rough = orenNayar(1.0f, 0.5f);
    int differs = 0;
    for (int i = 0; i < 1000; ++i) {
        const vec3 wi = fromAngle(89.0f * uni(gen), 360.0f * uni(gen)), wo = fromAngle(89.0f * uni(gen), 360.0f * uni(gen));
        EXPECT_NEAR(glossyEval(m, wi, wo).x, wo.z / kPi, 1e-6f);
        if (std::abs(glossyEval(rough, wi, wo).x - wo.z / kPi) > 1e-3f) ++differs;  // control
    }
    EXPECT_GT(differs, 900);
    const double e = integrateSphere([&](vec3 wo) { return double(glossyEval(m, fromAngle(40.0f), wo).x); }, 2048, 128);
    EXPECT_NEAR(e, 1.0, 1e-3);
}

// A nearly smooth rough dielectric reflects F(wi) and transmits 1 - F(wi). Tungsten's
// transmission has no radiance scaling by the squared index ratio (it cancels on paths that enter
// and leave an object), so it conserves energy from both sides; the control is the scaled value.
TEST(GlossyBsdf, NearlySmoothDielectricSplitsByFresnel) {
    // (inside, away from the critical angle of 41.8 degrees, where F is too steep for the blur)
    for (float theta : {0.0f, 30.0f, 60.0f, 150.0f, 170.0f}) {
        const vec3 wi = fromAngle(theta);
        const MaterialGpu m = roughDielectric(0.01f, 1.5f);
        const float ior = 1.5f;
        float cosT;
        const float F = fresnelDielectricSigned(wi.z, ior, cosT);
        const double eta = wi.z > 0.0f ? 1.0 / ior : ior;  // n(wi side) / n(wo side)
        // The refracted direction: tangential part scaled by eta, on the other side.
        const vec3 refracted = normalize(vec3(-wi.x * float(eta), -wi.y * float(eta), wi.z > 0.0f ? -cosT : cosT));
        const double r = integrateSphere([&](vec3 wo) { return wo.z * wi.z > 0.0f ? double(glossyEval(m, wi, wo).x) : 0.0; },
                                         4096, 512, vec3(-wi.x, -wi.y, wi.z));
        const double t = integrateSphere([&](vec3 wo) { return wo.z * wi.z < 0.0f ? double(glossyEval(m, wi, wo).x) : 0.0; },
                                         4096, 512, refracted);
        EXPECT_NEAR(r, F, 5e-3) << theta;
        EXPECT_NEAR(t, 1.0 - F, 1e-2) << theta;
        if (F < 0.9f) {
            EXPECT_GT(std::abs(t - (1.0 - F) * eta * eta), 0.1) << "control " << theta;
        }
    }
}

TEST(GlossyBsdf, Reciprocity) {
    std::mt19937 gen(17);
    std::uniform_real_distribution<float> uni(0.0f, 1.0f);
    for (const Case& c : cases()) {
        int checked = 0;
        for (int i = 0; i < 2000; ++i) {
            const bool dielectric = isDielectric(c.m);
            const vec3 a = fromAngle((dielectric ? 178.0f : 88.0f) * uni(gen), 360.0f * uni(gen));
            const vec3 b = fromAngle((dielectric ? 178.0f : 88.0f) * uni(gen), 360.0f * uni(gen));
            if (std::abs(a.z) < 0.02f || std::abs(b.z) < 0.02f) continue;
            // n on each side: 1 outside (z > 0), ior inside
            const double na = a.z > 0.0f ? 1.0 : c.m.ior, nb = b.z > 0.0f ? 1.0 : c.m.ior;
            const double fab = glossyEval(c.m, a, b).x / std::abs(b.z) / (nb * nb);
            const double fba = glossyEval(c.m, b, a).x / std::abs(a.z) / (na * na);
            // (single precision: refraction near the critical angle amplifies rounding)
            ASSERT_NEAR(fab, fba, 5e-3 * std::max(fab, fba) + 1e-7) << c.name;
            if (fab > 1e-3) ++checked;
        }
        EXPECT_GT(checked, 100) << c.name;
    }
}
