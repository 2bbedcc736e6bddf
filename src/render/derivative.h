// Derivative images (docs/DERIVATIVES.md): the derivative of every pixel with respect to one
// numeric scene value, by finite differences that the telescoping series makes unbiased.
//
// A parameter theta is any number `--set` can address (bsdfs[0].albedo, primitives[3].transform.
// position[1], media[0].density, ...). A version of the scene with theta + delta is read from the
// same document with that one value changed; its buffers replace the base scene's in one Renderer
// (one set of pipelines), so every version must have the same plan and buffer sizes.
//
// Every evaluation of one sample (pixel p, global sample index s) renders with the same random
// numbers: the Renderer's numbers depend only on (p, s, seed). Russian roulette is off and the
// light selection probabilities are the base scene's in every version, so that discrete decisions
// agree between the versions.
//
// With f(delta) the estimate of sample s with theta + delta and h_k = h_0 2^-k, the forward
// difference I(k) = (f(h_k) - f(0)) / h_k; the estimators (per sample s):
//   forward      I(0)                                              biased, O(h_0)
//   central      (f(h_0) - f(-h_0)) / (2 h_0)                      biased, O(h_0^2)
//   single_term  I(0) + (I(j+1) - I(j)) / p(j)                    unbiased (to level `levels`)
//   sum          I(0) + sum_{i<=j} (I(i+1) - I(i)) / P(J >= i)     unbiased (to level `levels`)
//   progressive  (f(h_k) - f(-h_k)) / (2 h_k), k = floor(log2(s+1) / 3)   consistent
// The level j is drawn per sample index, shared by all pixels (a version is a whole scene: a level
// per pixel would need every version at every sample); each pixel's estimate is unbiased, and
// the pixels of one sample index are correlated.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "gpu/context.h"
#include "render/film.h"
#include "render/renderer.h"
#include "scene/enum_names.h"
#include "scene/scene.h"

namespace telescope {

enum class DerivativeEstimator : uint32_t { Forward, Central, SingleTerm, Sum, Progressive };
inline constexpr Named<DerivativeEstimator> kDerivativeEstimatorNames[] = {
    {DerivativeEstimator::Forward, "forward"},
    {DerivativeEstimator::Central, "central"},
    {DerivativeEstimator::SingleTerm, "single_term"},
    {DerivativeEstimator::Sum, "sum"},
    {DerivativeEstimator::Progressive, "progressive"}};

const char* derivativeEstimatorName(DerivativeEstimator e);
// Throws InputError naming `option` for an unknown name.
DerivativeEstimator parseDerivativeEstimator(const std::string& name, const std::string& option);

// Test-only deliberately wrong variants (positive controls of the unbiasedness tests).
enum class DerivativeControl : uint32_t {
    None,
    ShiftedPmf,          // the correction of level j divided by p(j+1) instead of p(j)
    IndependentNumbers,  // every version of a sample renders with its own random numbers
};

struct DerivativeSettings {
    std::string key;   // the parameter, as --set addresses it
    double step = 0.0; // h_0; 0: the default (defaultDerivativeStep)
    DerivativeEstimator estimator = DerivativeEstimator::SingleTerm;
    // The level pmf of single_term and sum, truncated to levels 0 .. levels-1. The default follows
    // the recipe: for a smooth f, E[D_j] and its spread fall as 2^-j, so p(j) ~ 2^-j (r = 0.5).
    PmfSettings pmf = defaultDerivativePmf();
    // The series stops at I(levels): h_levels = h_0 / 256 by default. Deeper levels cost variance:
    // single-precision rounding makes E[D_j^2] grow again past about level 7 (docs/DERIVATIVES.md).
    uint32_t levels = 8;
    // pmf "auto": a pilot of pilotSpp samples measures the image's second moment E[D_j^2] at every
    // level and sets p(j) ~ sqrt(E[D_j^2]) (the recipe; every level costs the same two renders).
    bool autoPmf = false;
    uint32_t pilotSpp = 8;
    DerivativeControl control = DerivativeControl::None;

    static PmfSettings defaultDerivativePmf();
};

// The parameter as read from the scene.
struct DerivativeParameter {
    std::string key;
    double value = 0.0;  // theta
    double step = 0.0;   // h_0
    std::string stepOrigin;  // how h_0 was chosen
};

// The default h_0: for a position (a key with "position": its value depends on an arbitrary
// origin) 1/16 of `size`: the moved object's smallest transform scale, else the smaller of |theta|
// (where not 0) and the scene's extent;
// for any other value 1/16 of |theta|, or 1/16 where theta is 0.
double defaultDerivativeStep(double theta, const std::string& key, double size);

class DerivativeRenderer {
public:
    // Throws InputError (naming the scene file and the key) for a parameter that does not exist,
    // is not a number, is discrete, lies in the integrator or renderer settings, cannot be varied
    // by +-h_0 (the scene refuses the value), changes nothing, or changes the render's plan or
    // buffer sizes; and for integrators that are not the path tracer.
    DerivativeRenderer(gpu::Context& context, const ResolvedScene& scene, const DerivativeSettings& settings, uint32_t seed);
    ~DerivativeRenderer();

    const DerivativeParameter& parameter() const { return parameter_; }
    const DerivativeSettings& settings() const { return settings_; }
    // The estimator in one line (EXR metadata, plan).
    std::string description() const;
    // The plan's lines: parameter, h_0, estimator, pmf, evaluations per sample.
    std::string planText() const;
    std::string pmfText() const;  // the level pmf in words (with the pilot's table)
    const Renderer& renderer() const { return *renderer_; }

    // Continues from a film of this derivative render (same scene, settings and seed): later
    // samples continue the same sequence (sample indices and levels), so a resumed render equals
    // one long render. Only before the first render() call.
    void resume(const Film& film);
    // Starts again from an empty film at sample index 0 with another control (tests: the same
    // pipelines serve an estimator and its control).
    void restart(DerivativeControl control);
    // Adds samples (request.spp, or until request.timeLimit) to the derivative film.
    void render(const RenderRequest& request);
    const Film& film() const { return film_; }
    double seconds() const { return seconds_; }
    uint64_t evaluations() const { return evaluations_; }  // image renders, all versions
    double versionSeconds() const { return versionSeconds_; }  // building and uploading versions

    // The parameter offsets (delta) sample index s evaluates, and its level (0 where none).
    std::vector<double> offsetsOf(uint64_t sample, uint32_t* level = nullptr) const;
    // Level j of sample s (single_term, sum).
    uint32_t drawLevel(uint64_t sample) const;
    // P(J = j) and P(J >= j) of the truncated pmf (or of the pilot's table).
    double levelProbability(uint32_t j) const;
    double levelTail(uint32_t j) const;
    // pmf "auto": the pilot's measured sum over pixels of E[D_j^2] per level (empty without one).
    const std::vector<double>& pilotSecondMoments() const { return pilotMoments_; }
    // The correction's predicted second moment sum_j M_j / p(j) (M_j: the pilot's moments) with
    // this render's pmf and with the default geometric pmf; 0 without a pilot.
    double predictedSecondMoment(bool defaultPmf) const;

private:
    struct Version;
    const Version& version(double delta);
    void runPilot();  // pmf "auto": fills pilotMoments_ and table_
    void addSample(uint64_t sample, const std::map<double, std::vector<glm::vec4>>& images);

    gpu::Context& context_;
    Scene scene_;  // the base, roulette off
    DerivativeSettings settings_;
    DerivativeParameter parameter_;
    uint32_t seed_;
    std::unique_ptr<Renderer> renderer_;
    std::map<double, std::unique_ptr<Version>> versions_;
    double current_ = 0.0;  // the version in the renderer's buffers
    Film film_;
    uint64_t nextSample_ = 0;
    double seconds_ = 0.0, versionSeconds_ = 0.0;
    uint64_t evaluations_ = 0;
    std::vector<double> pilotMoments_;
    std::vector<double> table_;  // pmf "auto": p(j), j < levels (empty: the parametric pmf)
    double pilotSeconds_ = 0.0;
};

}  // namespace telescope
