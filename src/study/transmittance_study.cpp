#include "study/transmittance_study.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "gpu/buffer.h"
#include "gpu/pipeline.h"
#include "shared/transmittance_estimators.h"
#include "shared/transmittance_study.h"
#include "core/atomic_file.h"
#include "scene/enum_names.h"

namespace fs = std::filesystem;

namespace telescope {

namespace {

constexpr double kTargets[] = {0.01, 0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9, 0.99};
constexpr double kLooseness[] = {1.0, 1.25, 1.5, 1.75, 2.0};
// One estimate per thread: lavapipe ends a loop after 65535 iterations per SIMD group, so a
// thread must not accumulate the lookups of many estimates.
constexpr uint32_t kSamplesPerThread = 1;

// The models: exponential, and Davis at three values of c (C^2 = c^2 = 1/alpha; c = 0.8 as in
// Misso et al.): a light, the paper's and a heavy tail.
struct ModelSpec {
    std::string name;
    double davisAlpha;  // 0: exponential
};
const std::vector<ModelSpec>& models() {
    static const std::vector<ModelSpec> list = {
        {"exponential", 0.0}, {"davis", 1.0 / (0.8 * 0.8)}, {"davis_c0.4", 1.0 / (0.4 * 0.4)}, {"davis_c1.6", 1.0 / (1.6 * 1.6)}};
    return list;
}

struct Problem {
    std::string model, profile;
    shader::TrModel trModel;
    shader::DensityProfile density;  // scaled so that the optical depth over [0, 1] is tau
    double target, looseness, truth;
    float densityMin, densityMax;
};

struct EstimatorSpec {
    std::string name;
    uint32_t type;
    bool exponentialOnly;
};

// Every transmittance estimator, named by the scene file's table (scene/enum_names.h); the trackers
// and Kettunen et al.'s unbiased marching need an exponential model.
const std::vector<EstimatorSpec>& estimators() {
    static const std::vector<EstimatorSpec> list = [] {
        std::vector<EstimatorSpec> l;
        for (const auto& [value, name] : kTransmittanceEstimatorNames)
            l.push_back({name, uint32_t(value), estimatesExponentialOnly(value)});
        return l;
    }();
    return list;
}

// The optical depth at which the model's T_ss equals the target.
double depthFor(const ModelSpec& model, double target) {
    if (model.davisAlpha == 0.0) return -std::log(target);
    return model.davisAlpha * (std::pow(target, -1.0 / model.davisAlpha) - 1.0);  // (1 + tau/a)^-a = T
}

std::vector<Problem> problems() {
    std::vector<Problem> out;
    const std::vector<std::pair<std::string, shader::DensityProfile>> shapes = {
        {"constant", shader::makeProfile(shader::kProfileConstant, 1.0f, 0.0f, 0.0f)},
        {"sine", shader::makeProfile(shader::kProfileSine, 1.0f, 0.9f, 2.3f)},
        {"gaussian", shader::makeProfile(shader::kProfileGaussian, 1.0f, 0.45f, 0.12f)},
    };
    for (const ModelSpec& model : models()) {
        shader::TrModel m = model.davisAlpha == 0.0
                                ? shader::trSimple(shader::kTrExponential, glm::vec4(0.0f))
                                : shader::trSimple(shader::kTrDavis, glm::vec4(float(model.davisAlpha), 0, 0, 0));
        for (const auto& [name, unit] : shapes)
            for (double target : kTargets)
                for (double looseness : kLooseness) {
                    const double tau = depthFor(model, target);
                    shader::DensityProfile p = unit;
                    p.a = float(tau / shader::profileIntegral(unit, 0.0, 1.0));
                    const glm::vec2 bounds = shader::profileBounds(p, 0.0f, 1.0f);
                    Problem pr{model.name, name, m, p, target, looseness,
                               shader::trForm(m, shader::kFormSurfaceSurface, float(tau)), bounds.x,
                               float(bounds.y * looseness)};
                    out.push_back(pr);
                }
    }
    return out;
}


}  // namespace

TransmittanceStudyReport runTransmittanceStudy(gpu::Context& context, const TransmittanceStudyOptions& o) {
    auto log = [&](const std::string& s) { if (o.log) o.log(s); };
    TransmittanceStudyReport report;
    const std::vector<Problem> list = problems();
    const uint32_t threads = std::max<uint32_t>(1, (o.samples + kSamplesPerThread - 1) / kSamplesPerThread);
    const double samples = double(threads) * kSamplesPerThread;

    gpu::ComputePipeline pipeline(context, "transmittance_study", shader::kTrStudyBindingCount,
                                  uint32_t(sizeof(shader::TrStudyPush)));
    constexpr uint32_t kPerBatch = 64;
    gpu::Buffer results(context, uint64_t(kPerBatch) * threads * sizeof(glm::vec4), "study results");
    pipeline.bindBuffers({&results});
    gpu::CommandBatch batch(context, kPerBatch);

    // ---- Every (estimator, problem) pair, in batches of dispatches ----
    struct Job {
        const EstimatorSpec* estimator;
        const Problem* problem;
    };
    std::vector<Job> jobs;
    for (const EstimatorSpec& e : estimators())
        for (const Problem& p : list)
            if (!e.exponentialOnly || p.model == "exponential") jobs.push_back({&e, &p});
    log(fmt::format("{} estimator x problem pairs, {} estimates each", jobs.size(), uint64_t(samples)));

    for (size_t first = 0; first < jobs.size(); first += kPerBatch) {
        const size_t count = std::min<size_t>(kPerBatch, jobs.size() - first);
        batch.begin();
        for (size_t i = 0; i < count; ++i) {
            const Job& job = jobs[first + i];
            shader::TrStudyPush push{};
            push.model = job.problem->trModel;
            push.profile = job.problem->density;
            push.estimator = job.estimator->type;
            push.level = o.level;
            push.pmfR = o.pmfR;
            push.terms = o.taylorTerms;
            push.seed = o.seed * 7919u + uint32_t(first + i);
            push.densityMin = job.problem->densityMin;
            push.densityMax = job.problem->densityMax;
            push.threads = threads;
            push.samplesPerThread = kSamplesPerThread;
            push.outputOffset = uint32_t(i * threads);
            batch.dispatch(pipeline, &push, sizeof(push), (threads + shader::kTrStudyGroupSize - 1) / shader::kTrStudyGroupSize,
                           1, 1, "transmittance_study");
        }
        batch.submitAndWait();
        std::vector<glm::vec4> raw(count * threads);
        results.download(raw.data(), raw.size() * sizeof(glm::vec4));
        for (size_t i = 0; i < count; ++i) {
            const Job& job = jobs[first + i];
            double s = 0, s2 = 0, lookups = 0, maxAbs = 0;
            for (uint32_t t = 0; t < threads; ++t) {
                const glm::vec4& v = raw[i * threads + t];
                s += v.x;
                s2 += v.y;
                lookups += v.z;
                maxAbs = std::max(maxAbs, double(v.w));
            }
            TransmittanceStudyRow row;
            row.estimator = job.estimator->name;
            row.model = job.problem->model;
            row.profile = job.problem->profile;
            row.target = job.problem->target;
            row.looseness = job.problem->looseness;
            row.mean = s / samples;
            row.variance = std::max(0.0, s2 / samples - row.mean * row.mean) * samples / (samples - 1.0);
            // Per-estimate MSE against the closed form: variance + bias^2 (bias from the mean of all estimates).
            const double bias = row.mean - job.problem->truth;
            row.mse = row.variance + bias * bias;
            row.lookups = lookups / samples;
            row.maxAbs = maxAbs;
            report.rows.push_back(row);
        }
    }

    // ---- CSV ----
    fs::create_directories(o.outDir);
    auto out = [&](const std::string& name) { return (fs::path(o.outDir) / name).string(); };
    std::string csv = "estimator,model,profile,target,looseness,mean,truth,variance,bias,mse,lookups,work_x_rel_mse,max_abs_z\n";
    for (size_t i = 0; i < report.rows.size(); ++i) {
        const auto& r = report.rows[i];
        const double truth = jobs[i].problem->truth;
        csv += fmt::format("{},{},{},{},{},{:.9g},{:.9g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g}\n", r.estimator, r.model,
                           r.profile, r.target, r.looseness, r.mean, truth, r.variance, r.mean - truth, r.mse, r.lookups,
                           r.workTimesRelMse(), r.maxAbs);
    }
    writeTextAtomically(out("transmittance.csv"), csv);
    report.files.push_back(out("transmittance.csv"));

    // ---- Heat maps: one PNG per estimator, a panel per (model, profile) ----
    // Colour: log10(work x relative MSE), shown with a floor of 1e-12 (zero-variance estimates).
    bool gnuplotOk = true;
    for (const EstimatorSpec& e : estimators()) {
        std::string data;
        std::vector<std::string> panels;
        for (const ModelSpec& spec : models()) {
            const std::string& model = spec.name;
            if (e.exponentialOnly && model != "exponential") continue;
            for (const std::string profile : {"constant", "sine", "gaussian"}) {
                panels.push_back(model + " / " + profile);
                for (size_t ti = 0; ti < std::size(kTargets); ++ti) {
                    for (size_t li = 0; li < std::size(kLooseness); ++li)
                        for (const auto& r : report.rows)
                            if (r.estimator == e.name && r.model == model && r.profile == profile &&
                                r.target == kTargets[ti] && r.looseness == kLooseness[li])
                                data += fmt::format("{} {} {:.6g}\n", ti, li, std::log10(std::max(r.workTimesRelMse(), 1e-12)));
                    data += "\n";
                }
                data += "\n\n";
            }
        }
        const std::string dat = "heat_" + e.name + ".dat";
        writeTextAtomically(out(dat), data);
        std::string xtics, ytics;
        for (size_t i = 0; i < std::size(kTargets); ++i) xtics += fmt::format("{}\"{}\" {}", i ? ", " : "", kTargets[i], i);
        for (size_t i = 0; i < std::size(kLooseness); ++i) ytics += fmt::format("{}\"{}\" {}", i ? ", " : "", kLooseness[i], i);
        std::string gp = fmt::format(
            "set terminal pngcairo size {},{} font ',10' noenhanced\nset output 'heat_{}.png.partial'\n"
            "set multiplot layout {},3 title '{}: log10(density lookups x MSE / T^2), level {}'\n"
            "set xtics ({}) rotate by 45 right\nset ytics ({})\nset xlabel 'target transmittance'\n"
            "set ylabel 'majorant looseness'\nset cbrange [-8:2]\nset palette defined (0 '#000080', 1 '#2080ff', 2 '#40ffb0', 3 '#ffff40', 4 '#ff4020')\n"
            "set xrange [-0.5:{}]\nset yrange [-0.5:{}]\n",
            1500, 60 + 420 * (panels.size() / 3), e.name, panels.size() / 3, e.name, o.level, xtics, ytics,
            std::size(kTargets) - 0.5, std::size(kLooseness) - 0.5);
        for (size_t i = 0; i < panels.size(); ++i)
            gp += fmt::format("set title '{}'\nplot '{}' index {} using 1:2:3 with image notitle\n", panels[i], dat, i);
        gp += "unset multiplot\n";
        writeTextAtomically(out("heat_" + e.name + ".gp"), gp);
        const bool ok = std::system(fmt::format("cd '{}' && gnuplot heat_{}.gp >/dev/null 2>&1", o.outDir, e.name).c_str()) == 0 &&
                        fs::exists(out("heat_" + e.name + ".png.partial"));
        if (ok) {
            fs::rename(out("heat_" + e.name + ".png.partial"), out("heat_" + e.name + ".png"));
            report.files.push_back(out("heat_" + e.name + ".png"));
        } else {
            gnuplotOk = false;
        }
    }
    if (!gnuplotOk) log("gnuplot failed or is not installed: heat maps not written (their .gp and .dat files are)");

    // ---- Summary: geometric mean of work x relative MSE per estimator and model ----
    std::string md = fmt::format(
        "# Transmittance study\n\n{} estimates per (estimator, problem); level {} for ray marching (2^k points) and "
        "the base of debiased marching (geometric pmf, r = {}), the pivot of taylor (forced terms: {}). Problems: "
        "density constant / sine / Gaussian on a unit segment, target transmittance {} values in [0.01, 0.99], "
        "majorant looseness 1 to 2; exponential and Davis transmittance (`davis`: c = 0.8 as in Misso et al.; "
        "`davis_c0.4`, `davis_c1.6`: c = 0.4 and 1.6, alpha = 1/c^2). Work = density lookups per estimate; MSE per "
        "estimate against the closed form (variance + bias^2).\n\n"
        "| estimator | model | geometric mean of work x MSE / T^2 | mean lookups | largest |bias| / T | best on |\n"
        "|---|---|---|---|---|---|\n",
        uint64_t(samples), o.level, o.pmfR, o.taylorTerms, std::size(kTargets));
    std::map<std::string, int> bestCount;
    std::map<std::string, int> problemsPerModel;
    for (const ModelSpec& spec : models()) {
        const std::string& model = spec.name;
        // Best estimator per problem (lowest work x MSE).
        std::map<std::string, std::pair<double, std::string>> best;
        for (const auto& r : report.rows) {
            if (r.model != model) continue;
            std::string key = r.profile + fmt::format("/{}/{}", r.target, r.looseness);
            auto it = best.find(key);
            if (it == best.end() || r.workTimesRelMse() < it->second.first) best[key] = {r.workTimesRelMse(), r.estimator};
        }
        for (const auto& [key, b] : best) bestCount[model + ":" + b.second]++;
        problemsPerModel[model] = int(best.size());
        for (const EstimatorSpec& e : estimators()) {
            double logSum = 0, lookups = 0, worstBias = 0;
            int n = 0;
            for (size_t i = 0; i < report.rows.size(); ++i) {
                const auto& r = report.rows[i];
                if (r.estimator != e.name || r.model != model) continue;
                logSum += std::log(std::max(r.workTimesRelMse(), 1e-12));
                lookups += r.lookups;
                worstBias = std::max(worstBias, std::abs(r.mean - jobs[i].problem->truth) / r.target);
                ++n;
            }
            if (n == 0) continue;
            md += fmt::format("| {} | {} | {:.3g} | {:.1f} | {:.2g} | {} of {} |\n", e.name, model, std::exp(logSum / n),
                              lookups / n, worstBias, bestCount[model + ":" + e.name], problemsPerModel[model]);
        }
    }
    md += "\nHeat maps: `heat_<estimator>.png`; data: `transmittance.csv`. Ray marching is biased: its bias is part of "
          "its MSE (the |bias| column shows it; a statistically significant bias needs |bias| well above "
          "sqrt(variance / estimates)).\n";
    writeTextAtomically(out("summary.md"), md);
    report.files.push_back(out("summary.md"));
    return report;
}

}  // namespace telescope
