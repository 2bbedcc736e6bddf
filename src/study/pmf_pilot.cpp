#include "study/pmf_pilot.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "render/renderer.h"

namespace telescope {

namespace {

constexpr double kWeightEpsilon = 1e-2;  // as in the relative MSE
constexpr uint32_t kMaxPredictedLevels = 20000;

double gpuSeconds(const RenderStats& stats) {
    double ms = 0.0;
    for (const auto& [name, p] : stats.passes) ms += p.gpuMs;
    return ms * 1e-3;
}

// log P(M >= m) for the two families.
double logTail(const PmfSettings& pmf, uint32_t m) {
    if (pmf.type == PmfType::Geometric) return double(m) * std::log1p(-double(pmf.r));
    return (double(pmf.alpha) - 1.0) * std::log(double(m) + 1.0);
}

// log p(m) for the two families, without underflow for large m.
double logProbability(const PmfSettings& pmf, uint32_t m) {
    if (pmf.type == PmfType::Geometric) return std::log(double(pmf.r)) + double(m) * std::log1p(-double(pmf.r));
    const double a = pmf.alpha, n = double(m) + 1.0;
    return (a - 1.0) * std::log(n) + std::log(-std::expm1((1.0 - a) * std::log1p(-1.0 / (n + 1.0))));
}

// Least-squares line y = a + b x.
std::pair<double, double> fitLine(const std::vector<double>& x, const std::vector<double>& y) {
    const double n = double(x.size());
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) sx += x[i], sy += y[i], sxx += x[i] * x[i], sxy += x[i] * y[i];
    const double den = n * sxx - sx * sx;
    if (x.size() < 2 || !(std::abs(den) > 0.0)) return {x.empty() ? 0.0 : sy / n, 0.0};
    const double b = (n * sxy - sx * sy) / den;
    return {(sy - b * sx) / n, b};
}

struct Model {
    std::vector<double> logM2, logCost;  // measured levels
    double logDecay = 0.0, logGrowth = 0.0;
    double logM2At(uint32_t m) const {
        if (m < logM2.size()) return logM2[m];
        return logM2.back() + double(m - logM2.size() + 1) * logDecay;
    }
    double logCostAt(uint32_t m) const {
        if (m < logCost.size()) return logCost[m];
        return logCost.back() + double(m - logCost.size() + 1) * logGrowth;
    }
};

Model makeModel(const PmfPilotResult& pilot) {
    Model model;
    // A level whose correction was never seen keeps a small floor below the smallest seen.
    double floorM2 = std::numeric_limits<double>::infinity();
    for (const auto& l : pilot.levels)
        if (l.secondMoment > 0.0) floorM2 = std::min(floorM2, l.secondMoment);
    if (!std::isfinite(floorM2)) floorM2 = 1e-30;
    for (const auto& l : pilot.levels) {
        model.logM2.push_back(std::log(std::max(l.secondMoment, 1e-3 * floorM2)));
        model.logCost.push_back(std::log(std::max(l.secondsPerPath, 1e-15)));
    }
    model.logDecay = std::log(pilot.tailDecay);
    model.logGrowth = std::log1p(std::max(pilot.tailCostSlope, 0.0));
    return model;
}

}  // namespace

PmfCandidate predictPmf(const PmfPilotResult& pilot, const PmfSettings& pmf, DebiasEstimator estimator) {
    PmfCandidate c;
    c.pmf = pmf;
    if (pilot.levels.empty()) return c;
    const Model model = makeModel(pilot);
    double variance = 0.0, cost = 0.0;
    for (uint32_t m = 0; m < kMaxPredictedLevels; ++m) {
        // Single term: D_m / p(m) with probability p(m). Sum: D_m / P(M >= m) whenever M >= m
        // (the covariances between levels are left out of the prediction).
        const double lp = logProbability(pmf, m);
        const double lv = estimator == DebiasEstimator::Sum ? logTail(pmf, m) : lp;
        const double dv = std::exp(model.logM2At(m) - lv), dc = std::exp(lp + model.logCostAt(m));
        variance += dv;
        cost += dc;
        if (m > pilot.levels.size() + 32 && dv <= 1e-9 * variance && dc <= 1e-9 * cost) break;
        if (m + 1 == kMaxPredictedLevels) variance = cost = std::numeric_limits<double>::infinity();
    }
    c.variance = pilot.baseVariance + variance;
    c.cost = cost;
    return c;
}

PmfPilotResult runPmfPilot(gpu::Context& context, const Scene& sceneIn, uint32_t seed) {
    PmfPilotResult result;
    const PmfSettings settings = sceneIn.integrator.debias.pmf;
    const uint32_t spp = settings.pilotSpp;
    const DebiasEstimator estimator = sceneIn.integrator.debias.estimator;

    // ---- The base I(k): per-pixel weights and the base variance ----
    Scene base = sceneIn;
    base.integrator.debias.estimator = DebiasEstimator::None;
    base.integrator.debias.pmf = PmfSettings{};
    Renderer baseRenderer(context, base, seed ^ 0x9E3779B9u);
    RenderRequest request;
    request.spp = std::max<uint32_t>(spp, 2);
    baseRenderer.render(request);
    const Film baseFilm = baseRenderer.film();
    const double pixels = double(baseFilm.pixelCount());
    std::vector<glm::dvec3> weight(baseFilm.pixelCount());
    for (size_t i = 0; i < baseFilm.pixelCount(); ++i) {
        glm::dvec3 b = baseFilm.mean(shader::kChannelEstimate, i);
        weight[i] = 1.0 / (b * b + kWeightEpsilon);
        glm::dvec3 v = baseFilm.varianceOfMean(i) * double(baseFilm.samplesPerPixel()) * weight[i];
        result.baseVariance += (v.x + v.y + v.z) / (3.0 * pixels);
    }
    result.pilotGpuSeconds += gpuSeconds(baseRenderer.stats());
    result.pilotWallSeconds += baseRenderer.stats().wallSeconds;

    // ---- One fixed level at a time: the unweighted correction D_j and its cost ----
    for (uint32_t m = 0; m < settings.pilotLevels; ++m) {
        Scene s = sceneIn;
        s.integrator.debias.estimator = DebiasEstimator::SingleTerm;
        s.integrator.debias.pmf = PmfSettings{};
        s.integrator.pilotLevel = m;
        Renderer r(context, s, seed + 7919u * (m + 1));
        RenderRequest req;
        req.spp = spp;
        r.render(req);
        const Film film = r.film();
        PilotLevel level;
        level.level = m;
        for (size_t i = 0; i < film.pixelCount(); ++i) {
            glm::dvec3 m2 = film.mean(shader::kChannelEstimateSq, i) * weight[i];
            level.secondMoment += (m2.x + m2.y + m2.z) / (3.0 * pixels);
        }
        const double seconds = gpuSeconds(r.stats());
        level.secondsPerPath = seconds / (double(spp) * pixels);
        result.pilotGpuSeconds += seconds;
        result.pilotWallSeconds += r.stats().wallSeconds;
        result.levels.push_back(level);
    }

    // ---- Tail: geometric decay of the second moment, geometric growth of the cost ----
    std::vector<double> x, logM2, cost, logCost;
    const size_t half = result.levels.size() / 2;
    for (size_t i = half; i < result.levels.size(); ++i) {
        if (result.levels[i].secondMoment > 0.0) {
            x.push_back(double(i));
            logM2.push_back(std::log(result.levels[i].secondMoment));
        }
    }
    double decay = std::exp(fitLine(x, logM2).second);
    result.tailDecay = std::isfinite(decay) && decay > 0.0 ? std::min(decay, 0.999) : 0.5;
    std::vector<double> xc;
    for (size_t i = half; i < result.levels.size(); ++i) {
        xc.push_back(double(i));
        logCost.push_back(std::log(std::max(result.levels[i].secondsPerPath, 1e-15)));
    }
    result.tailCostSlope = std::max(0.0, std::expm1(fitLine(xc, logCost).second));

    // ---- The ideal shape and the best member of each family ----
    double norm = 0.0;
    for (const auto& l : result.levels) {
        result.idealPmf.push_back(std::sqrt(std::max(l.secondMoment, 0.0) / std::max(l.secondsPerPath, 1e-15)));
        norm += result.idealPmf.back();
    }
    for (double& p : result.idealPmf) p = norm > 0.0 ? p / norm : 0.0;

    PmfSettings geometric, powerLaw;
    geometric.type = PmfType::Geometric;
    powerLaw.type = PmfType::PowerLaw;
    result.geometricDefault = predictPmf(result, geometric, estimator);
    result.powerLawDefault = predictPmf(result, powerLaw, estimator);
    result.chosen = result.geometricDefault;
    for (int i = 2; i <= 98; ++i) {
        PmfSettings g = geometric, p = powerLaw;
        g.r = float(i) / 100.0f;
        p.alpha = float(i) / 100.0f;
        for (const PmfSettings& candidate : {g, p}) {
            PmfCandidate c = predictPmf(result, candidate, estimator);
            if (c.product() < result.chosen.product()) result.chosen = c;
        }
    }
    result.chosen.pmf.pilotSpp = settings.pilotSpp;
    result.chosen.pmf.pilotLevels = settings.pilotLevels;
    return result;
}

std::string PmfPilotResult::summary() const {
    auto describe = [](const PmfCandidate& c) {
        std::string name = c.pmf.type == PmfType::Geometric ? fmt::format("geometric r = {:.2f}", c.pmf.r)
                                                            : fmt::format("power law alpha = {:.2f}", c.pmf.alpha);
        return fmt::format("{}: predicted variance x cost {:.4g}", name, c.product());
    };
    std::string s = fmt::format("pmf pilot ({} levels, {:.2f} s GPU): chosen {}\n", levels.size(), pilotGpuSeconds,
                                describe(chosen));
    s += fmt::format("  default {}\n  default {}\n", describe(geometricDefault), describe(powerLawDefault));
    s += "  level: E[D^2] (weighted), us per path, ideal p\n";
    for (size_t i = 0; i < levels.size(); ++i)
        s += fmt::format("    {}: {:.4g}, {:.3f}, {:.3f}\n", levels[i].level, levels[i].secondMoment,
                         levels[i].secondsPerPath * 1e6, idealPmf[i]);
    s += fmt::format("  tail: E[D^2] ratio {:.3f} per level, cost growth {:.3f} per level; base variance {:.4g}\n",
                     tailDecay, tailCostSlope, baseVariance);
    return s;
}

bool resolveAutoPmf(gpu::Context& context, Scene& scene, uint32_t seed, PmfPilotResult* out) {
    DebiasSettings& d = scene.integrator.debias;
    if (d.estimator == DebiasEstimator::None || d.pmf.type != PmfType::Auto) return false;
    PmfPilotResult r = runPmfPilot(context, scene, seed);
    d.pmf = r.chosen.pmf;
    if (out) *out = std::move(r);
    return true;
}

}  // namespace telescope
