// Thin sheets and mixed materials through the shared code the path tracer calls (shared/bsdf.h),
// run on the CPU.
// - thinsheet is a Dirac BSDF (specular reflection and a straight-through forward lobe), so there
//   is no density to chi-square: its reflectance is checked against the sum of the slab's internal
//   reflections computed here term by term (control: the single-interface Fresnel term, which the
//   check rejects), its interference against two known answers (a film of thickness 0 reflects
//   nothing; averaged over thickness it is the incoherent slab), and its scattering routine's
//   probabilities and weights against the closed form R and T (z-tests; control: the answer with
//   the single-interface Fresnel term); without absorption R + T = 1 and every weight is 1 (furnace).
// - mixed: the path tracer picks component 0 with probability ratio and uses that component's
//   sampling (shaders/path_tracer.glsl); the chi-square test checks that the directions drawn this
//   way have the density ratio pdf0 + (1 - ratio) pdf1 (controls: the pdfs mixed 1:1 and mixed by
//   1 - ratio are rejected); the mean weight is the quadrature of the mixture ratio f0 +
//   (1 - ratio) f1 (control: the 1:1 mixture's), and a mixture of two white lossless materials
//   passes the white furnace (control: one lossy component).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "bsdf_stats.h"
#include "test_materials.h"
#include "render/gpu_scene.h"
#include "shared/bsdf.h"

using namespace telescope::shader;
using namespace telescope::test;

namespace {

// Single-interface reflectance of one polarisation (s or p) from vacuum into index n, double
// precision, from Snell's law.
double interfaceReflectance(double n, double cosI, bool s) {
    const double sinT = std::sqrt(std::max(0.0, 1.0 - cosI * cosI)) / n;
    const double cosT = std::sqrt(std::max(0.0, 1.0 - sinT * sinT));
    const double r = s ? (cosI - n * cosT) / (cosI + n * cosT) : (n * cosI - cosT) / (n * cosI + cosT);
    return r * r;
}

// Reflectance of a non-absorbing slab summed ray by ray: the first reflection r, then light
// entering (1 - r), bouncing inside 2k + 1 times and leaving (1 - r) on the side it came from.
double slabBySeries(double n, double cosI) {
    double total = 0.0;
    for (bool s : {true, false}) {
        const double r = interfaceReflectance(n, cosI, s);
        double sum = r, inner = r;  // r^(2k+1)
        for (int k = 0; k < 2000 && inner > 1e-18; ++k) {
            sum += (1.0 - r) * (1.0 - r) * inner;
            inner *= r * r;
        }
        total += 0.5 * sum;
    }
    return total;
}

MaterialGpu thinSheet(float ior, float thickness, vec3 sigmaA, bool interference = false) {
    telescope::Material m;
    m.type = telescope::BsdfType::ThinSheet;
    m.ior = ior;
    m.thickness = thickness;
    m.sigmaA = sigmaA;
    m.enableInterference = interference;
    return telescope::gpuMaterial(m);
}

}  // namespace

TEST(ThinSheet, SlabReflectanceIsTheSumOfItsInternalReflections) {
    int controlsRejected = 0, checked = 0;
    for (float ior : {1.1f, 1.33f, 1.5f, 2.4f})
        for (int i = 1; i <= 40; ++i) {
            const float cosI = float(i) / 40.0f;
            float cosT;
            const double ref = slabBySeries(ior, cosI);
            const double got = thinSheetSlabReflectance(ior, cosI, cosT);
            ASSERT_NEAR(got, ref, 2e-6 + 2e-6 * ref) << "ior " << ior << " cos " << cosI;
            EXPECT_NEAR(cosT, std::sqrt(1.0 - (1.0 - double(cosI) * cosI) / (double(ior) * ior)), 1e-6);
            // Control: one interface's Fresnel term instead of the slab's.
            float c;
            if (std::abs(fresnelDielectric(cosI, ior, c) - ref) > 2e-6 + 2e-6 * ref) ++controlsRejected;
            ++checked;
        }
    EXPECT_EQ(controlsRejected, checked);
}

TEST(ThinSheet, InterferenceKnownAnswers) {
    for (float cosI : {1.0f, 0.7f, 0.3f}) {
        float cosT;
        // A film of thickness 0 is no film: all light goes through.
        const vec3 zero = thinFilmInterferenceReflectance(1.5f, cosI, 0.0f, cosT);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(zero[c], 0.0f, 1e-6f) << cosI;
        // Averaged over the thickness (many periods of every wavelength) the fringes average to the
        // incoherent slab.
        const double slab = thinSheetSlabReflectance(1.5f, cosI, cosT);
        glm::dvec3 mean(0.0);
        const int steps = 200000;
        for (int i = 0; i < steps; ++i) mean += glm::dvec3(thinFilmInterferenceReflectance(1.5f, cosI, 40000.0f * (i + 0.5f) / steps, cosT));
        mean /= double(steps);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], slab, 1e-3) << cosI << " channel " << c;
        // Control: one thickness (Tungsten's default film, 250 nm) is coloured, not the average.
        const vec3 film = thinFilmInterferenceReflectance(1.5f, cosI, 250.0f, cosT);
        EXPECT_GT(std::max({std::abs(film.x - slab), std::abs(film.y - slab), std::abs(film.z - slab)}), 1e-2) << cosI;
    }
    // The material uses 500 nm per unit of thickness, as Tungsten does.
    vec3 T;
    const vec3 R = thinSheetReflectance(thinSheet(1.5f, 0.5f, vec3(0.0f), true), 0.8f, T);
    float cosT;
    const vec3 direct = thinFilmInterferenceReflectance(1.5f, 0.8f, 250.0f, cosT);
    for (int c = 0; c < 3; ++c) {
        EXPECT_FLOAT_EQ(R[c], direct[c]);
        EXPECT_FLOAT_EQ(T[c], 1.0f - direct[c]);
    }
}

// thinSheetScatter: reflect with probability 1 - mean(T); E[weight; reflect] = R and
// E[weight; straight on] = T, with T = (1 - R) exp(-2 thickness sigma_a / cos theta_t).
TEST(ThinSheet, ScatterProbabilitiesAndWeightsMatchTheClosedForm) {
    const vec3 sigmaA(0.2f, 0.5f, 1.5f);
    const float thickness = 0.7f, ior = 1.5f;
    const MaterialGpu m = thinSheet(ior, thickness, sigmaA);
    for (float cosI : {1.0f, 0.6f, 0.2f}) {
        const double R = slabBySeries(ior, cosI);
        const double cosT = std::sqrt(1.0 - (1.0 - double(cosI) * cosI) / (double(ior) * ior));
        glm::dvec3 T;
        for (int c = 0; c < 3; ++c) T[c] = (1.0 - R) * std::exp(-2.0 * thickness * sigmaA[c] / cosT);
        const int n = 400000;
        std::mt19937 gen(11);
        std::uniform_real_distribution<float> uni(0.0f, 1.0f);
        glm::dvec3 sumR(0.0), sumR2(0.0), sumT(0.0), sumT2(0.0);
        double reflections = 0.0;
        for (int i = 0; i < n; ++i) {
            vec3 w;
            if (thinSheetScatter(m, cosI, uni(gen), w)) {
                reflections += 1.0;
                sumR += glm::dvec3(w);
                sumR2 += glm::dvec3(w) * glm::dvec3(w);
            } else {
                sumT += glm::dvec3(w);
                sumT2 += glm::dvec3(w) * glm::dvec3(w);
            }
        }
        const double pR = 1.0 - (T.x + T.y + T.z) / 3.0;
        const double zP = (reflections / n - pR) / std::sqrt(pR * (1.0 - pR) / n);
        EXPECT_LT(std::abs(zP), 5.0) << cosI;
        for (int c = 0; c < 3; ++c) {
            const double mR = sumR[c] / n, seR = std::sqrt(std::max(1e-14, sumR2[c] / n - mR * mR) / n);
            const double mT = sumT[c] / n, seT = std::sqrt(std::max(1e-14, sumT2[c] / n - mT * mT) / n);
            EXPECT_LT(std::abs(mR - R), 5.0 * seR) << cosI << " channel " << c << ": " << mR << " vs R " << R;
            EXPECT_LT(std::abs(mT - T[c]), 5.0 * seT) << cosI << " channel " << c << ": " << mT << " vs T " << T[c];
            // Control: the single-interface Fresnel term in place of the slab's.
            float ct;
            const double F = fresnelDielectric(cosI, ior, ct);
            EXPECT_GT(std::abs(mR - F), 5.0 * seR) << "control " << cosI << " channel " << c;
        }
    }
}

// White furnace: without absorption and interference R + T = 1, and the routine's weights are 1.
TEST(ThinSheet, NonAbsorbingSheetConservesEnergy) {
    const MaterialGpu m = thinSheet(1.5f, 0.5f, vec3(0.0f));
    const MaterialGpu absorbing = thinSheet(1.5f, 0.5f, vec3(0.3f));
    for (int i = 1; i <= 20; ++i) {
        const float cosI = float(i) / 20.0f;
        vec3 T;
        const vec3 R = thinSheetReflectance(m, cosI, T);
        for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(R[c] + T[c], 1.0f);
        for (float u : {0.0f, 0.3f, 0.9f, 0.999f}) {
            vec3 w;
            thinSheetScatter(m, cosI, u, w);
            EXPECT_EQ(w, vec3(1.0f));
        }
        // Control: absorption loses energy.
        const vec3 Ra = thinSheetReflectance(absorbing, cosI, T);
        EXPECT_LT(Ra.x + T.x, 0.99f) << cosI;
    }
}

namespace {

// A mixed material over components held in `materials` (indices 1 and 2), as the path tracer
// reads them from its material buffer.
struct Mixture {
    std::vector<MaterialGpu> materials;
    const MaterialGpu& mixed() const { return materials[0]; }
    const MaterialGpu& component(uint i) const { return materials[i]; }
};

Mixture mixture(MaterialGpu a, MaterialGpu b, float ratio, float albedo = 1.0f) {
    telescope::Material m;
    m.type = telescope::BsdfType::Mixed;
    m.component[0] = 1;
    m.component[1] = 2;
    m.ratio = ratio;
    m.albedo = vec3(albedo);
    return Mixture{{telescope::gpuMaterial(m), a, b}};
}

MaterialGpu roughConductor(float roughness) {
    telescope::Material m;
    m.type = telescope::BsdfType::RoughConductor;
    m.roughness = roughness;
    return telescope::gpuMaterial(m);
}

MaterialGpu whitePlastic() {
    telescope::Material m;
    m.type = telescope::BsdfType::Plastic;
    m.albedo = vec3(1.0f);
    return telescope::gpuMaterial(m);
}

// The path tracer's event at a mixed material: a component by mixedComponent, then its sampling.
bool sampleMixture(const Mixture& mx, vec3 wi, Rng& rng, vec3& wo, vec3& weight, bool& specular) {
    const MaterialGpu& c = mx.component(mixedComponent(mx.mixed(), rngNext(rng)));
    float pdf;
    if (!glossySample(c, wi, rng, wo, weight, pdf, specular)) return false;
    weight *= mx.mixed().albedo;
    return true;
}

double mixturePdf(const Mixture& mx, float ratio, vec3 wi, vec3 wo) {
    return ratio * glossyPdf(mx.component(1), wi, wo) + (1.0f - ratio) * glossyPdf(mx.component(2), wi, wo);
}

}  // namespace

TEST(MixedBsdf, SamplingMatchesTheRatioWeightedPdf) {
    const Mixture mx = mixture(roughConductor(0.2f), orenNayar(0.8f, 1.0f), 0.3f);
    uint32_t seed = 500;
    for (float theta : {0.0f, 45.0f, 75.0f}) {
        const vec3 wi = fromAngle(theta);
        uint32_t index = 0;
        auto sample = [&](float, float, vec3& wo) {
            Rng rng = rngCreate(index++, 0, seed);
            vec3 weight;
            bool specular;
            return sampleMixture(mx, wi, rng, wo, weight, specular);
        };
        const ChiSquareResult ok = chiSquareSphere(sample, [&](vec3 wo) { return mixturePdf(mx, 0.3f, wi, wo); }, 200000, seed);
        EXPECT_FALSE(ok.rejected()) << theta << ": " << ok.describe();
        for (float wrong : {0.5f, 0.7f}) {  // not mixed by the ratio; mixed by 1 - ratio
            index = 0;
            const ChiSquareResult c = chiSquareSphere(sample, [&](vec3 wo) { return mixturePdf(mx, wrong, wi, wo); }, 200000, seed);
            EXPECT_TRUE(c.rejected()) << "control " << wrong << " theta " << theta << ": " << c.describe();
        }
        ++seed;
    }
}

// Mean weight of the mixture's samples = albedo x the quadrature of ratio f0 + (1 - ratio) f1.
TEST(MixedBsdf, MeanWeightIsTheMixturesAlbedo) {
    const float ratio = 0.3f;
    const Mixture mx = mixture(roughConductor(0.2f), orenNayar(0.8f, 1.0f), ratio, 0.9f);
    for (float theta : {0.0f, 60.0f}) {
        const vec3 wi = fromAngle(theta);
        auto quad = [&](float r) {
            return 0.9 * integrateSphere([&](vec3 wo) {
                       return double(r * glossyEval(mx.component(1), wi, wo).x + (1.0f - r) * glossyEval(mx.component(2), wi, wo).x);
                   }, 2048, 256, vec3(-wi.x, -wi.y, wi.z));
        };
        const double expected = quad(ratio), control = quad(0.5f);
        const int n = 200000;
        double sum = 0.0, sum2 = 0.0;
        for (int i = 0; i < n; ++i) {
            Rng rng = rngCreate(uint32_t(i), 3, 77);
            vec3 wo, w;
            bool specular;
            if (!sampleMixture(mx, wi, rng, wo, w, specular)) continue;
            sum += w.x;
            sum2 += double(w.x) * w.x;
        }
        const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
        EXPECT_LT(std::abs(mean - expected), 5.0 * se + 1e-3) << theta << ": " << mean << " vs " << expected;
        EXPECT_GT(std::abs(mean - control), 5.0 * se + 1e-3) << "control " << theta << ": " << control;
    }
}

// White furnace: a white plastic (energy-conserving exactly, Dirac coat included) mixed with a
// white Oren-Nayar of roughness 0 (Lambert) reflects all light; control: a grey Oren-Nayar.
TEST(MixedBsdf, WhiteFurnace) {
    for (float grey : {1.0f, 0.8f}) {
        const Mixture mx = mixture(whitePlastic(), orenNayar(grey, 0.0f), 0.4f);
        for (float theta : {10.0f, 50.0f, 80.0f}) {
            const vec3 wi = fromAngle(theta);
            const int n = 200000;
            double sum = 0.0, sum2 = 0.0;
            for (int i = 0; i < n; ++i) {
                Rng rng = rngCreate(uint32_t(i), 5, 123);
                vec3 wo, w;
                bool specular;
                if (!sampleMixture(mx, wi, rng, wo, w, specular)) continue;
                sum += w.x;
                sum2 += double(w.x) * w.x;
            }
            const double mean = sum / n, se = std::sqrt(std::max(1e-14, sum2 / n - mean * mean) / n);
            if (grey == 1.0f) {
                EXPECT_LT(std::abs(mean - 1.0), 5.0 * se + 1e-3) << theta << ": " << mean;
            } else {
                EXPECT_GT(std::abs(mean - 1.0), 5.0 * se + 1e-3) << "control " << theta << ": " << mean;
            }
        }
    }
}
