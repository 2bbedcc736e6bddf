#include "render/pmf_pilot.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "render/renderer.h"
#include "shared/gpu_types.h"
#include "shared/transmittance_estimators.h"

namespace telescope {

namespace {

constexpr double kWeightEpsilon = 1e-2;  // as in the relative MSE
constexpr double kLogMisfit = 0.05;      // floor on the standard deviation of a level's log E[D^2]
constexpr double kUpperSigmas = 2.0;     // the tail's decay: fit plus this many standard errors
constexpr double kMaxDecay = 0.999;

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

struct Line {
    double intercept = 0.0, slope = 0.0, slopeError = 0.0;
    bool valid = false;
};

// Weighted least-squares line y = a + b x (weights 1 / sigma^2). The slope's standard error is
// the larger of the one the sigmas predict and the one the scatter about the line shows.
Line fitLine(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& sigma) {
    Line line;
    double sw = 0, sx = 0, sy = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        const double w = 1.0 / (sigma[i] * sigma[i]);
        sw += w, sx += w * x[i], sy += w * y[i];
    }
    if (x.size() < 2 || !(sw > 0.0)) return line;
    const double mx = sx / sw, my = sy / sw;
    double sxx = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) {
        const double w = 1.0 / (sigma[i] * sigma[i]);
        sxx += w * (x[i] - mx) * (x[i] - mx), sxy += w * (x[i] - mx) * (y[i] - my);
    }
    if (!(sxx > 0.0)) return line;
    line.slope = sxy / sxx;
    line.intercept = my - line.slope * mx;
    double chi2 = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
        const double r = (y[i] - line.intercept - line.slope * x[i]) / sigma[i];
        chi2 += r * r;
    }
    const double scatter = x.size() > 2 ? chi2 / double(x.size() - 2) : 1.0;
    line.slopeError = std::sqrt(std::max(1.0, scatter) / sxx);
    line.valid = std::isfinite(line.slope) && std::isfinite(line.slopeError);
    return line;
}

}  // namespace

double PilotModel::logSecondMomentAt(uint32_t m) const {
    if (secondMoment.empty() || m >= levelCap) return -std::numeric_limits<double>::infinity();
    if (m < secondMoment.size()) return std::log(secondMoment[m]);
    return std::log(secondMoment.back()) + double(m - secondMoment.size() + 1) * std::log(decayUpper);
}

double PilotModel::secondMomentAt(uint32_t m) const { return std::exp(logSecondMomentAt(m)); }

double PilotModel::costAt(uint32_t m) const {
    if (rays.empty()) return costIntercept;
    m = std::min(m, levelCap);
    double r = rays.back();
    if (m < rays.size()) {
        r = rays[m];
    } else if (raySurvival > 0.0) {
        // Increments shrink by raySurvival per level: rays.back() + d (s + s^2 + ... + s^n).
        const double d = rays.size() > 1 ? rays.back() - rays[rays.size() - 2] : 0.0;
        const double n = double(m - rays.size() + 1), s = raySurvival;
        r += d * (std::abs(s - 1.0) < 1e-12 ? n : s * -std::expm1(n * std::log(s)) / (1.0 - s));
    }
    return costIntercept + costPerRay * std::min(r, rayCap);
}

void fitPilotModel(PmfPilotResult& pilot) {
    PilotModel& model = pilot.model;
    model = PilotModel{};
    model.levelCap = pilot.levelCap;
    model.rayCap = pilot.rayCap;
    const size_t n = pilot.levels.size();
    if (n == 0) return;

    // ---- E[D^2]: a weighted line in log space; the tail decays at its upper bound ----
    std::vector<double> x, y, sigma;
    for (const auto& l : pilot.levels) {
        if (!(l.secondMoment > 0.0)) continue;
        x.push_back(double(l.level));
        y.push_back(std::log(l.secondMoment));
        sigma.push_back(std::sqrt(std::log1p(l.relativeError * l.relativeError) + kLogMisfit * kLogMisfit));
    }
    const Line line = fitLine(x, y, sigma);
    if (line.valid) {
        model.decay = std::clamp(std::exp(line.slope), 1e-6, kMaxDecay);
        model.decayUpper = std::clamp(std::exp(line.slope + kUpperSigmas * line.slopeError), model.decay, kMaxDecay);
    } else {
        // One level or none with a correction seen: nothing to fit, so a slow decay.
        model.decay = 0.5;
        model.decayUpper = 0.9;
    }
    for (const auto& l : pilot.levels) {
        const double fitted = line.valid ? std::exp(line.intercept + line.slope * double(l.level)) : 0.0;
        model.secondMoment.push_back(std::max(l.secondMoment, fitted));
    }
    if (!line.valid && !x.empty()) {
        // A single level with a correction: the levels after it decay from it.
        for (size_t i = 1; i < n; ++i)
            model.secondMoment[i] = std::max(model.secondMoment[i], model.secondMoment[i - 1] * model.decayUpper);
    }

    // ---- Cost: seconds per path = a + b rays, rays extrapolated by their survival ----
    double rmax = 0.0;
    for (const auto& l : pilot.levels) model.rays.push_back(rmax = std::max(rmax, l.raysPerPath));
    std::vector<double> cx, cy, ones;
    for (const auto& l : pilot.levels) cx.push_back(l.raysPerPath), cy.push_back(l.secondsPerPath), ones.push_back(1.0);
    const Line cost = fitLine(cx, cy, ones);
    double meanCost = 0.0;
    for (double c : cy) meanCost += c / double(cy.size());
    if (cost.valid && cost.slope > 0.0 && cost.intercept >= 0.0) {
        model.costIntercept = cost.intercept;
        model.costPerRay = cost.slope;
    } else if (cost.valid && cost.slope > 0.0) {
        model.costIntercept = 0.0;  // through the origin: cost proportional to rays
        double sxy = 0.0, sxx = 0.0;
        for (size_t i = 0; i < cx.size(); ++i) sxy += cx[i] * cy[i], sxx += cx[i] * cx[i];
        model.costPerRay = sxy / sxx;
    } else {
        model.costIntercept = std::max(meanCost, 1e-15);  // no measurable growth with rays
    }
    // Survival: the ratio of successive ray increments over the second half of the levels.
    std::vector<double> sx, sy, sone;
    for (size_t i = std::max<size_t>(1, n / 2); i < n; ++i) {
        const double d = model.rays[i] - model.rays[i - 1];
        if (d > 1e-9 * model.rays[i]) sx.push_back(double(i)), sy.push_back(std::log(d)), sone.push_back(1.0);
    }
    const Line survival = fitLine(sx, sy, sone);
    model.raySurvival = survival.valid ? std::clamp(std::exp(survival.slope), 0.0, pilot.maxRaySurvival)
                                       : (sx.empty() ? 0.0 : std::min(1.0, pilot.maxRaySurvival));
}

PmfCandidate predictPmf(const PmfPilotResult& pilot, const PmfSettings& pmf, DebiasEstimator estimator) {
    PmfCandidate c;
    c.pmf = pmf;
    const PilotModel& model = pilot.model;
    if (model.secondMoment.empty()) return c;
    double variance = 0.0, cost = 0.0;
    const uint32_t measured = uint32_t(model.secondMoment.size());
    for (uint32_t m = 0; m < model.levelCap; ++m) {
        // Single term: D_m / p(m) with probability p(m). Sum: D_m / P(M >= m) whenever M >= m
        // (the covariances between levels are left out of the prediction).
        const double lp = logProbability(pmf, m);
        const double lv = estimator == DebiasEstimator::Sum ? logTail(pmf, m) : lp;
        // In log space: a term that grows overflows to infinity rather than its E[D^2] underflowing.
        const double dv = std::exp(model.logSecondMomentAt(m) - lv), dc = std::exp(lp) * model.costAt(m);
        variance += dv;
        cost += dc;
        if (m > measured + 32 && dv <= 1e-9 * variance && std::exp(logTail(pmf, m + 1)) * model.costAt(model.levelCap) <= 1e-9 * cost)
            break;
        if (m + 1 == model.levelCap) cost += std::exp(logTail(pmf, m + 1)) * model.costAt(model.levelCap);
    }
    c.variance = pilot.baseVariance + variance;
    c.cost = cost;
    return c;
}

void choosePmf(PmfPilotResult& result, DebiasEstimator estimator) {
    fitPilotModel(result);
    result.idealPmf.clear();
    double norm = 0.0;
    for (size_t m = 0; m < result.levels.size(); ++m) {
        result.idealPmf.push_back(std::sqrt(result.model.secondMomentAt(uint32_t(m)) / result.model.costAt(uint32_t(m))));
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
}

PmfPilotResult runPmfPilot(gpu::Context& context, const Scene& sceneIn, uint32_t seed) {
    PmfPilotResult result;
    const PmfSettings settings = sceneIn.integrator.debias.pmf;
    const uint32_t spp = settings.pilotSpp;
    const DebiasEstimator estimator = sceneIn.integrator.debias.estimator;
    const uint32_t k = pathDepthK(sceneIn.integrator);
    result.levelCap = shader::kTraceDepthCap > k ? shader::kTraceDepthCap - k : 1u;

    // ---- One renderer for every level (the level is a push constant: one pipeline compile) ----
    // Every level uses the same seed: level m + 1 traces the same paths as level m, one bounce
    // further, so the ray counts of successive levels differ by exactly the paths that survive.
    Scene s = sceneIn;
    s.integrator.debias.estimator = DebiasEstimator::SingleTerm;
    s.integrator.debias.pmf = PmfSettings{};
    s.integrator.debias.schedule = LevelSchedule::PerPixel;
    Renderer r(context, resolveScene(context, s, seed).scene, seed + 7919u, PlanOptions{0, PilotKind::PathDepth});
    std::vector<glm::dvec3> weight;
    double pixels = 0.0;
    for (uint32_t m = 0; m < settings.pilotLevels; ++m) {
        if (m > 0) r.restartAtFixedLevel(m);
        RenderRequest req;
        req.spp = m == 0 ? std::max<uint32_t>(spp, 2) : spp;  // the base variance needs two samples
        r.render(req);
        const PilotSums sums = r.passes().pilotSums(r.nextSampleIndex());
        const double n = double(sums.samples);
        const size_t pixelCount = sums.sums[shader::kPilotBase].size();
        if (m == 0) {
            // ---- The base I(k) (the same paths at every level): per-pixel weights and variance ----
            pixels = double(pixelCount);
            weight.resize(pixelCount);
            for (size_t i = 0; i < pixelCount; ++i) {
                const glm::dvec3 b = sums.mean(shader::kPilotBase, i);
                const glm::dvec3 b2 = sums.mean(shader::kPilotBaseSq, i);
                weight[i] = 1.0 / (b * b + kWeightEpsilon);
                const glm::dvec3 v = glm::max(b2 - b * b, glm::dvec3(0.0)) * (n / (n - 1.0)) * weight[i];
                result.baseVariance += (v.x + v.y + v.z) / (3.0 * pixels);
            }
        }
        PilotLevel level;
        level.level = m;
        double sumSq = 0.0;
        for (size_t i = 0; i < pixelCount; ++i) {
            glm::dvec3 m2 = sums.mean(shader::kPilotCorrectionSq, i) * weight[i];
            const double value = (m2.x + m2.y + m2.z) / 3.0;
            level.secondMoment += value / pixels;
            sumSq += value * value;
            level.raysPerPath += sums.mean(shader::kPilotRays, i).x / pixels;
        }
        // Pixels are independent: the spread of their values bounds the error of the mean.
        const double spread = std::sqrt(std::max(0.0, sumSq / pixels - level.secondMoment * level.secondMoment));
        level.relativeError = level.secondMoment > 0.0 ? spread / std::sqrt(pixels) / level.secondMoment : 0.0;
        const double seconds = gpuSeconds(r.stats());
        level.secondsPerPath = seconds / (n * pixels);
        result.pilotGpuSeconds += seconds;
        result.pilotWallSeconds += r.stats().wallSeconds;
        result.levels.push_back(level);
    }

    choosePmf(result, estimator);
    result.chosen.pmf.pilotSpp = settings.pilotSpp;
    result.chosen.pmf.pilotLevels = settings.pilotLevels;
    return result;
}

PmfPilotResult runTransmittancePmfPilot(gpu::Context& context, const Scene& sceneIn, uint32_t seed) {
    PmfPilotResult result;
    result.kind = PilotKind::Transmittance;
    const TransmittanceEstimatorSettings& t = sceneIn.integrator.transmittance;
    if (t.type != TransmittanceEstimatorType::DebiasedRayMarch)
        throw std::logic_error("the transmittance pmf pilot needs debiased ray marching");
    const PmfSettings settings = t.pmf;
    const uint32_t k = t.level;
    // The shader truncates j at kTrMaxCombLog2 - 1: levels m >= levelCap add nothing.
    result.levelCap = shader::kTrMaxCombLog2 > k + 1 ? shader::kTrMaxCombLog2 - k : 1u;
    result.maxRaySurvival = 2.0;  // points per estimate double per level
    result.rayCap = double(1u << shader::kTrMaxCombLog2);
    const uint32_t levels = std::min(settings.pilotLevels, result.levelCap);
    const uint32_t spp = std::max<uint32_t>(settings.pilotSpp, 2);  // the base variance needs two samples

    Scene s = sceneIn;
    if (s.integrator.debias.estimator != DebiasEstimator::None) {
        s.integrator.debias.estimator = DebiasEstimator::None;  // paths to the base depth k
        s.integrator.debias.pmf = PmfSettings{};
    }
    s.integrator.russianRoulette = false;  // survival would depend on the weighted correction
    s.integrator.transmittance.pmf = defaultTransmittancePmf();
    Renderer r(context, resolveScene(context, s, seed).scene, seed + 7919u, PlanOptions{0, PilotKind::Transmittance});
    const size_t pixelCount = size_t(s.camera.width) * s.camera.height;
    const double pixels = double(pixelCount);
    std::vector<glm::dvec3> weight(pixelCount), baseSum(pixelCount), baseSq(pixelCount);
    std::vector<double> d2(pixelCount);
    for (uint32_t m = 0; m < levels; ++m) {
        std::fill(d2.begin(), d2.end(), 0.0);
        for (uint32_t i = 0; i < spp; ++i) {
            r.restartAtFixedLevel(m);
            const std::vector<glm::vec4> once = r.renderSample(i);
            result.pilotGpuSeconds += gpuSeconds(r.stats());
            result.pilotWallSeconds += r.stats().wallSeconds;
            r.restartAtFixedLevel(m | shader::kTrPilotHalfWeight);
            const std::vector<glm::vec4> twice = r.renderSample(i);
            result.pilotGpuSeconds += gpuSeconds(r.stats());
            result.pilotWallSeconds += r.stats().wallSeconds;
            for (size_t p = 0; p < pixelCount; ++p) {
                if (once[p].w != 0.0f || twice[p].w != 0.0f) continue;  // a non-finite sample, dropped
                const glm::dvec3 a(once[p]), b(twice[p]);
                const glm::dvec3 d = b - a;
                if (m == 0) {
                    const glm::dvec3 base = 2.0 * a - b;
                    baseSum[p] += base;
                    baseSq[p] += base * base;
                }
                d2[p] += (d.x * d.x + d.y * d.y + d.z * d.z) / 3.0;  // weighted below (weights need level 0)
            }
        }
        // The cost of a path at this level: a batched render, as the real one runs (one sample per
        // dispatch would charge every sample the dispatch overhead).
        r.restartAtFixedLevel(m);
        RenderRequest req;
        req.spp = spp;
        r.render(req);
        const double seconds = gpuSeconds(r.stats());
        result.pilotGpuSeconds += seconds;
        result.pilotWallSeconds += r.stats().wallSeconds;

        const double n = double(spp);
        if (m == 0) {
            for (size_t p = 0; p < pixelCount; ++p) {
                const glm::dvec3 mean = baseSum[p] / n;
                weight[p] = 1.0 / (mean * mean + kWeightEpsilon);
                const glm::dvec3 v = glm::max(baseSq[p] / n - mean * mean, glm::dvec3(0.0)) * (n / (n - 1.0)) * weight[p];
                result.baseVariance += (v.x + v.y + v.z) / (3.0 * pixels);
            }
        }
        PilotLevel level;
        level.level = m;
        double sumSq = 0.0;
        for (size_t p = 0; p < pixelCount; ++p) {
            // The per-channel weights: mean weight x mean D^2 over channels would mix them, so
            // weight the channel sum by the channels' mean weight (grey media: equal).
            const double w = (weight[p].x + weight[p].y + weight[p].z) / 3.0;
            const double value = w * d2[p] / n;
            level.secondMoment += value / pixels;
            sumSq += value * value;
        }
        const double spread = std::sqrt(std::max(0.0, sumSq / pixels - level.secondMoment * level.secondMoment));
        level.relativeError = level.secondMoment > 0.0 ? spread / std::sqrt(pixels) / level.secondMoment : 0.0;
        level.secondsPerPath = seconds / (n * pixels);
        level.raysPerPath = double(1u << std::min(k + m + 1, shader::kTrMaxCombLog2));
        result.levels.push_back(level);
    }

    choosePmf(result, DebiasEstimator::SingleTerm);
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
    const bool marching = kind == PilotKind::Transmittance;
    std::string s = fmt::format("{} pmf pilot ({} levels, {:.2f} s GPU): chosen {}\n",
                                marching ? "transmittance (debiased ray marching)" : "path-depth", levels.size(),
                                pilotGpuSeconds, describe(chosen));
    s += fmt::format("  default {}\n  default {}\n", describe(geometricDefault), describe(powerLawDefault));
    s += fmt::format("  level: E[D^2] (weighted) +- relative error, modelled E[D^2], us per path, {}, ideal p\n",
                     marching ? "points per estimate" : "rays per path");
    for (size_t i = 0; i < levels.size(); ++i)
        s += fmt::format("    {}: {:.4g} +- {:.2f}, {:.4g}, {:.3f}, {:.3f}, {:.3f}\n", levels[i].level,
                         levels[i].secondMoment, levels[i].relativeError, model.secondMomentAt(uint32_t(i)),
                         levels[i].secondsPerPath * 1e6, levels[i].raysPerPath, idealPmf[i]);
    if (marching)
        s += fmt::format("  tail: E[D^2] ratio {:.3f} per level (upper bound used: {:.3f}); cost {:.3g} us + {:.3g} us "
                         "per point, points double per level up to level {}; base variance {:.4g}\n",
                         model.decay, model.decayUpper, model.costIntercept * 1e6, model.costPerRay * 1e6, levelCap - 1,
                         baseVariance);
    else
        s += fmt::format("  tail: E[D^2] ratio {:.3f} per level (upper bound used: {:.3f}); cost {:.3g} us + {:.3g} us "
                         "per ray, ray increments shrink by {:.3f} per level; base variance {:.4g}\n",
                         model.decay, model.decayUpper, model.costIntercept * 1e6, model.costPerRay * 1e6,
                         model.raySurvival, baseVariance);
    return s;
}

Resolution resolveScene(gpu::Context& context, Scene scene, uint32_t seed) {
    std::vector<PmfPilotResult> pilots;
    const char* chosen = "chosen by the auto pilot: the lowest predicted work x variance over geometric and power-law pmfs";
    // Transmittance first: its pilot traces paths to the base depth only, and the path-depth
    // pilot then renders with the transmittance pmf the render will use.
    TransmittanceEstimatorSettings& t = scene.integrator.transmittance;
    if (transmittancePmfIsAuto(scene.integrator)) {
        if (scene.media.empty()) {
            t.pmf = defaultTransmittancePmf();
            t.pmf.origin = "auto: the scene has no media, so no transmittance is estimated (the default pmf)";
        } else {
            pilots.push_back(runTransmittancePmfPilot(context, scene, seed));
            t.pmf = pilots.back().chosen.pmf;
            t.pmf.origin = chosen;
        }
    }
    DebiasSettings& d = scene.integrator.debias;
    if (debiasPmfIsAuto(scene.integrator)) {
        pilots.push_back(runPmfPilot(context, scene, seed));
        d.pmf = pilots.back().chosen.pmf;
        d.pmf.origin = chosen;
    }
    return Resolution{ResolvedScene(std::move(scene)), std::move(pilots)};
}

}  // namespace telescope
