
#include "study/converge.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "core/error.h"
#include "render/image_output.h"
#include "render/renderer.h"
#include "scene/scene_loader.h"
#include "core/atomic_file.h"
#include "render/pmf_pilot.h"
#include "scene/settings_json.h"

namespace fs = std::filesystem;

namespace telescope {

namespace {

std::string csvQuote(const std::string& s) {
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
}

std::string formatSeconds(double s) { return s < 0.0 ? std::string("not reached") : fmt::format("{:.3g} s", s); }

double gpuSeconds(const RenderStats& stats) {
    double ms = 0.0;
    for (const auto& [name, p] : stats.passes) ms += p.gpuMs;
    return ms * 1e-3;
}

// Crop of the estimate, scaled up by an integer factor (nearest neighbour).
struct Crop {
    int x = 0, y = 0, w = 0, h = 0, scale = 1;
};

Crop defaultCrop(int width, int height) {
    Crop c;
    c.w = std::max(1, width / 2);
    c.h = std::max(1, height / 2);
    c.x = (width - c.w) / 2;
    c.y = (height - c.h) / 2;
    c.scale = std::max(1, 160 / c.h);
    return c;
}

// Appends a panel to a horizontal strip with a 4-pixel white gap.
void appendPanel(std::vector<std::vector<float>>& rows, const Crop& c, int width,
                 const std::function<float(size_t pixel, int channel)>& value) {
    const int gap = rows.front().empty() ? 0 : 4;
    for (int y = 0; y < c.h * c.scale; ++y) {
        auto& row = rows[size_t(y)];
        for (int g = 0; g < gap * 3; ++g) row.push_back(1.0f);
        for (int x = 0; x < c.w * c.scale; ++x) {
            size_t p = size_t(c.y + y / c.scale) * size_t(width) + size_t(c.x + x / c.scale);
            for (int ch = 0; ch < 3; ++ch) row.push_back(value(p, ch));
        }
    }
}

// Plots each method's curve: its single run's slices, or (seeds > 1) the means over the seeds.
std::string gnuplotScript(const ConvergeReport& report, bool severalSeeds, const std::string& pngName) {
    std::string s;
    for (size_t m = 0; m < report.methods.size(); ++m) {
        s += fmt::format("$m{} << EOD\n", m);
        for (const auto& p : report.points)
            if (p.method == report.methods[m].method.label && p.gpuSeconds > 0.0 &&
                (p.seed == kAllSeeds) == severalSeeds)
                s += fmt::format("{:.9g} {:.9g} {:.9g}\n", p.gpuSeconds, p.error.relMse,
                                 std::abs(p.error.relMeanError));
        s += "EOD\n";
    }
    s += fmt::format("set terminal pngcairo size 1400,560 noenhanced font 'sans,10'\nset output '{}'\n", pngName);
    s += "set logscale xy\nset grid\nset key bottom left\nset format y '%.0e'\nset multiplot layout 1,2\n";
    auto plot = [&](const char* title, const char* ylabel, int column, bool slopes) {
        s += fmt::format("set title '{}'\nset xlabel 'GPU time (s)'\nset ylabel '{}'\nplot ", title, ylabel);
        for (size_t m = 0; m < report.methods.size(); ++m) {
            const auto& ms = report.methods[m];
            std::string label = ms.method.label;
            if (slopes) label += fmt::format(" (slope {:.2f}, late {:.2f})", ms.slope, ms.slopeLateHalf);
            label.erase(std::remove(label.begin(), label.end(), '\''), label.end());
            s += fmt::format("{}$m{} using 1:{} with linespoints lw 2 title '{}'", m ? ", " : "", m, column, label);
        }
        s += "\n";
    };
    plot("relative MSE against the reference", "relative MSE", 2, true);
    plot("|mean signed error| / mean reference (bias, plus noise)", "|relative mean error|", 3, false);
    s += "unset multiplot\n";
    return s;
}

}  // namespace

ConvergeReport runConverge(gpu::Context& context, const ConvergeOptions& o) {
    auto log = [&](const std::string& line) {
        if (o.log) o.log(line);
    };
    if (o.methods.empty()) throw InputError("", "--methods", "no methods given");
    if ((o.timeBudget > 0.0) == !o.sppList.empty())
        throw InputError("", "--time", "give exactly one of --time and --spp");
    if (o.timeBudget > 0.0 && (o.slices < 1 || o.slices > 30))
        throw InputError("", "--slices", fmt::format("{} slices: expected 1 to 30", o.slices));
    if (o.seedCount < 1 || o.seedCount > 64)
        throw InputError("", "--seeds", fmt::format("{} seeds: expected 1 to 64", o.seedCount));
    for (size_t i = 0; i < o.sppList.size(); ++i)
        if (o.sppList[i] == 0 || (i > 0 && o.sppList[i] <= o.sppList[i - 1]))
            throw InputError("", "--spp", "sample counts must be positive and increasing");
    for (size_t i = 0; i < o.methods.size(); ++i)
        for (size_t j = 0; j < i; ++j)
            if (o.methods[i].label == o.methods[j].label)
                throw InputError("", "--methods", fmt::format("method '{}' is given twice", o.methods[i].label));

    // ---- Everything that can be bad input is checked before any rendering ----
    std::vector<Scene> scenes;
    for (const auto& m : o.methods) scenes.push_back(o.load(m.overrides));
    if (!fs::exists(o.referencePath)) throw InputError(o.referencePath, "", "reference image not found");
    RgbImage reference;
    try {
        reference = readExrChannels(o.referencePath, {"R", "G", "B"});
    } catch (const std::exception& e) {
        throw InputError(o.referencePath, "", fmt::format("cannot read the reference: {}", e.what()));
    }
    for (const auto& s : scenes)
        if (reference.width != int(s.camera.width) || reference.height != int(s.camera.height))
            throw InputError(o.referencePath, "",
                             fmt::format("reference is {}x{} but the scene renders {}x{} (use the same --set "
                                         "camera.resolution for both)",
                                         reference.width, reference.height, s.camera.width, s.camera.height));
    std::error_code ec;
    fs::create_directories(o.outDir, ec);
    if (!fs::is_directory(o.outDir))
        throw InputError("", "-o", fmt::format("cannot create output directory '{}'", o.outDir));

    // ---- Slices ----
    std::vector<double> timeTargets;
    if (o.timeBudget > 0.0)
        for (uint32_t i = 0; i < o.slices; ++i) timeTargets.push_back(o.timeBudget * std::ldexp(1.0, int(i) - int(o.slices) + 1));
    const size_t sliceCount = o.timeBudget > 0.0 ? timeTargets.size() : o.sppList.size();

    ConvergeReport report;
    const int width = reference.width, height = reference.height;
    Crop crop = defaultCrop(width, height);
    if (o.region.w > 0) {
        if (o.region.x < 0 || o.region.y < 0 || o.region.h <= 0 || o.region.x + o.region.w > width ||
            o.region.y + o.region.h > height)
            throw InputError("", "--region", fmt::format("{},{},{},{} is not inside the {}x{} image", o.region.x,
                                                         o.region.y, o.region.w, o.region.h, width, height));
        crop = Crop{o.region.x, o.region.y, o.region.w, o.region.h, std::max(1, 160 / o.region.h)};
    }
    std::vector<std::vector<float>> strip(size_t(crop.h * crop.scale));
    appendPanel(strip, crop, width, [&](size_t p, int c) { return reference.pixels[p * 3 + c]; });

    for (size_t mi = 0; mi < o.methods.size(); ++mi) {
        const Method& method = o.methods[mi];
        MethodSummary summary;
        summary.method = method;
        std::vector<std::vector<ConvergePoint>> runs;
        Film firstFilm;
        for (uint32_t si = 0; si < o.seedCount; ++si) {
            const uint32_t seed = o.seed + si;
            // A pilot's time is part of the method's cost: its curve starts after it. Each seed
            // runs its own pilots (a pmf chosen from the first seed's would tie the runs together).
            const Resolution resolution = resolveScene(context, scenes[mi], seed);
            const Scene& scene = resolution.scene.scene();
            PmfPilotResult pilot;  // the pilots' times, summed
            for (const PmfPilotResult& one : resolution.pilots) {
                log(one.summary());
                const PmfSettings& c = one.chosen.pmf;
                summary.pilotChoices += fmt::format("{}{}{}", summary.pilotChoices.empty() ? "" : ", ",
                                                    one.kind == PilotKind::Transmittance ? "transmittance " : "",
                                                    c.type == PmfType::Geometric ? fmt::format("r = {:.2f}", c.r)
                                                                                 : fmt::format("alpha = {:.2f}", c.alpha));
                pilot.pilotGpuSeconds += one.pilotGpuSeconds;
                pilot.pilotWallSeconds += one.pilotWallSeconds;
            }
            summary.settings.push_back(resolvedSettings(scene));
            // A radiance render, or a derivative render (its own Renderer inside).
            std::unique_ptr<Renderer> radiance;
            std::unique_ptr<DerivativeRenderer> derivative;
            if (o.derivative) {
                DerivativeSettings d = o.derivativeSettings;
                d.estimator = o.derivativeEstimators.at(mi);
                derivative = std::make_unique<DerivativeRenderer>(context, resolution.scene, d, seed);
            } else {
                radiance = std::make_unique<Renderer>(context, resolution.scene, seed);
            }
            const Renderer& renderer = derivative ? derivative->renderer() : *radiance;
            auto wallSeconds = [&] { return derivative ? derivative->seconds() : renderer.stats().wallSeconds; };
            auto samples = [&] { return derivative ? derivative->film().samplesPerPixel() : renderer.stats().samplesPerPixel; };
            if (si == 0) summary.estimator = derivative ? derivative->description() : renderer.plan().estimator;
            summary.pilotGpuSeconds += pilot.pilotGpuSeconds / o.seedCount;
            summary.pilotWallSeconds += pilot.pilotWallSeconds / o.seedCount;
            if (si == 0) log(fmt::format("{}: {}", method.label, summary.estimator));
            std::vector<ConvergePoint> run;
            Film film;
            for (size_t s = 0; s < sliceCount; ++s) {
                RenderRequest request;
                if (o.timeBudget > 0.0) {
                    request.timeLimit = timeTargets[s] - wallSeconds() - pilot.pilotWallSeconds;
                    const bool lastSlice = s + 1 == sliceCount;
                    if (request.timeLimit <= 0.0 && !(lastSlice && samples() == 0))
                        continue;  // the last batch (or the pilot) already reached this slice
                    // A pilot that used the whole budget still gets one batch, so its method shows
                    // up, late, in the plot and the table.
                    if (request.timeLimit <= 0.0) request.spp = 1, request.timeLimit = 0.0;
                } else {
                    request.spp = o.sppList[s] - samples();
                }
                if (derivative) {
                    derivative->render(request);
                    film = derivative->film();
                } else {
                    radiance->render(request);
                    film = radiance->film();
                }
                ConvergePoint p;
                p.method = method.label;
                p.seed = seed;
                p.slice = uint32_t(s);
                p.spp = film.samplesPerPixel();
                p.wallSeconds = wallSeconds() + pilot.pilotWallSeconds;
                p.gpuSeconds = gpuSeconds(renderer.stats()) + pilot.pilotGpuSeconds;
                p.error = compareToReference(film, reference, o.region);
                run.push_back(p);
                report.points.push_back(p);
                log(fmt::format("  seed {} slice {}: {} spp, {:.3f} s GPU, relMSE {:.4g}, bias {:+.4g}", seed, s, p.spp,
                                p.gpuSeconds, p.error.relMse, p.error.relMeanError));
            }
            if (run.empty()) throw std::runtime_error(fmt::format("method '{}' rendered no slice", method.label));
            summary.seedWorkTimesMse.push_back(run.back().gpuSeconds * run.back().error.relMse);
            summary.nonFiniteSamples += film.nonFiniteSamples();
            if (si == 0) firstFilm = film;
            runs.push_back(std::move(run));
        }
        if (!summary.pilotChoices.empty())
            summary.estimator += fmt::format(" (pmf chosen by a {:.2f} s pilot{}: {})", summary.pilotGpuSeconds,
                                             o.seedCount > 1 ? " per seed" : "", summary.pilotChoices);

        // ---- The curve: the run itself, or the means over the seeds of the slices all reached ----
        std::vector<ConvergePoint> curve = runs.front();
        if (o.seedCount > 1) {
            curve.clear();
            for (size_t s = 0; s < sliceCount; ++s) {
                ConvergePoint mean;
                mean.method = method.label;
                mean.slice = uint32_t(s);
                size_t found = 0;
                for (const auto& run : runs)
                    for (const auto& p : run) {
                        if (p.slice != s) continue;
                        ++found;
                        const double w = 1.0 / double(runs.size());
                        mean.spp += p.spp;
                        mean.wallSeconds += w * p.wallSeconds;
                        mean.gpuSeconds += w * p.gpuSeconds;
                        mean.error.rmse += w * p.error.rmse * p.error.rmse;  // mean square, root below
                        mean.error.relMse += w * p.error.relMse;
                        mean.error.meanError += w * p.error.meanError;
                        mean.error.relMeanError += w * p.error.relMeanError;
                    }
                if (found != runs.size()) continue;
                mean.spp /= runs.size();
                mean.error.rmse = std::sqrt(mean.error.rmse);
                curve.push_back(mean);
                report.points.push_back(mean);
            }
            if (curve.empty()) curve.push_back(runs.front().back());
        }
        std::vector<double> t, e;
        for (const auto& p : curve) t.push_back(p.gpuSeconds), e.push_back(p.error.relMse);
        summary.last = curve.back();
        summary.slope = logLogSlope(t, e);
        size_t half = t.size() / 2;
        summary.slopeLateHalf = logLogSlope(std::vector<double>(t.begin() + half, t.end()),
                                            std::vector<double>(e.begin() + half, e.end()));
        summary.secondsTo1e2 = timeToReach(t, e, 1e-2);
        summary.secondsTo1e3 = timeToReach(t, e, 1e-3);
        report.methods.push_back(summary);
        appendPanel(strip, crop, width,
                    [&](size_t p, int c) { return float(firstFilm.mean(shader::kChannelEstimate, p)[c]); });
    }

    // ---- Files ----
    auto out = [&](const char* name) { return (fs::path(o.outDir) / name).string(); };
    // seed: the run's seed, or "mean" for the means over the seeds.
    std::string csv = "method,seed,slice,spp,wall_seconds,gpu_seconds,rmse,rel_mse,mean_error,rel_mean_error\n";
    for (const auto& p : report.points)
        csv += fmt::format("{},{},{},{},{:.6f},{:.6f},{:.9g},{:.9g},{:.9g},{:.9g}\n", csvQuote(p.method),
                           p.seed == kAllSeeds ? std::string("mean") : std::to_string(p.seed), p.slice, p.spp,
                           p.wallSeconds, p.gpuSeconds, p.error.rmse, p.error.relMse, p.error.meanError,
                           p.error.relMeanError);
    writeTextAtomically(out("convergence.csv"), csv);
    report.files.push_back(out("convergence.csv"));

    std::vector<float> stripPixels;
    for (const auto& row : strip) stripPixels.insert(stripPixels.end(), row.begin(), row.end());
    writeSrgbPng(out("strip.png"), int(strip.front().size() / 3), int(strip.size()), stripPixels);
    report.files.push_back(out("strip.png"));

    writeTextAtomically(out("convergence.gp"), gnuplotScript(report, o.seedCount > 1, "convergence.png.partial"));
    report.files.push_back(out("convergence.gp"));
    std::string plotCommand = fmt::format("cd '{}' && gnuplot convergence.gp 2>&1", o.outDir);
    bool plotted = std::system(plotCommand.c_str()) == 0 && fs::exists(out("convergence.png.partial"));
    if (plotted) {
        fs::rename(out("convergence.png.partial"), out("convergence.png"));
        report.files.push_back(out("convergence.png"));
    } else {
        fs::remove(out("convergence.png.partial"), ec);
        log("gnuplot failed or is not installed: convergence.png not written (convergence.gp is)");
    }

    std::string md = fmt::format("# Convergence: {}\n\nReference: `{}` ({}x{}). ", o.scenePath, o.referencePath, width,
                                 height);
    md += o.seedCount > 1 ? fmt::format("Seeds {} to {}: each row is the mean over {} independent runs. ", o.seed,
                                        o.seed + o.seedCount - 1, o.seedCount)
                          : fmt::format("Seed {}. ", o.seed);
    if (o.region.w > 0)
        md += fmt::format("Errors over the region x = {}..{}, y = {}..{} only (`--region`). ", o.region.x,
                          o.region.x + o.region.w - 1, o.region.y, o.region.y + o.region.h - 1);
    md += o.timeBudget > 0.0 ? fmt::format("Equal render time: {:g} s per method in {} doubling slices.\n\n",
                                           o.timeBudget, o.slices)
                             : "Equal sample counts per slice.\n\n";
    md += "| method | spp | GPU s | wall s | RMSE | relMSE | work x relMSE | rel. bias | slope | late slope | to relMSE 1e-2 "
          "| to 1e-3 | non-finite |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    auto workTimesMse = [](const MethodSummary& m) { return m.last.gpuSeconds * m.last.error.relMse; };
    for (const auto& m : report.methods)
        md += fmt::format("| {} | {} | {:.3f} | {:.3f} | {:.4g} | {:.4g} | {:.3g} | {:+.3g} | {:.2f} | {:.2f} | {} | {} | {} |\n",
                          m.method.label, m.last.spp, m.last.gpuSeconds, m.last.wallSeconds, m.last.error.rmse,
                          m.last.error.relMse, workTimesMse(m), m.last.error.relMeanError, m.slope, m.slopeLateHalf,
                          formatSeconds(m.secondsTo1e2), formatSeconds(m.secondsTo1e3), m.nonFiniteSamples);

    // ---- Auto pmf against the fixed defaults at the same base level ----
    std::string autoLines;
    for (const auto& a : report.methods) {
        const size_t at = a.method.label.find("_auto:");
        if (at == std::string::npos) continue;
        const std::string family = a.method.label.substr(0, at), level = a.method.label.substr(at + 5);
        for (const auto& d : report.methods) {
            if (&d == &a || d.method.label.rfind(family, 0) != 0 || d.method.label.find("_auto:") != std::string::npos ||
                d.method.label.size() < level.size() ||
                d.method.label.compare(d.method.label.size() - level.size(), level.size(), level) != 0)
                continue;
            const double ratio = workTimesMse(a) / workTimesMse(d);
            std::string perSeed;
            if (o.seedCount > 1) {
                auto median = [](std::vector<double> v) {
                    std::sort(v.begin(), v.end());
                    return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
                };
                perSeed = fmt::format("; ratio of the medians over seeds {:.3f}",
                                      median(a.seedWorkTimesMse) / median(d.seedWorkTimesMse));
            }
            autoLines += fmt::format("- {} vs {}: work x relMSE ratio {:.3f} ({}){}\n", a.method.label, d.method.label,
                                     ratio, ratio < 0.9 ? "auto wins" : ratio <= 1.1 ? "within 10%" : "auto loses",
                                     perSeed);
        }
    }
    if (!autoLines.empty())
        md += "\nAuto pmf against the fixed defaults (GPU time x relative MSE at the end of the budget, pilot "
              "included, means over the seeds; below 1 is better):\n\n" + autoLines;
    md += "\nMethods:\n\n";
    for (const auto& m : report.methods)
        md += fmt::format("- **{}**: {}. {}\n", m.method.label, m.method.description, m.estimator);
    md += "\nHow to read it: an unbiased method's relative MSE keeps falling with time (slope about -1 for "
          "finite variance, shallower for infinite-variance estimators such as unbiased photon mapping); a "
          "biased method's flattens at its squared bias (late slope near 0) and its relative bias stays away "
          "from zero. The reference's own noise puts a floor under every curve. `strip.png` shows the same "
          "crop of the reference and of each method's final image, left to right in the order above.\n";
    writeTextAtomically(out("report.md"), md);
    report.files.push_back(out("report.md"));

    // ---- The settings each method's runs rendered with (an auto pmf resolved per seed) ----
    nlohmann::json settings = {{"scene", o.scenePath}, {"first_seed", o.seed}, {"methods", nlohmann::json::array()}};
    for (const auto& m : report.methods)
        settings["methods"].push_back({{"label", m.method.label}, {"description", m.method.description},
                                       {"estimator", m.estimator}, {"settings_per_seed", m.settings}});
    writeTextAtomically(out("settings.json"), settings.dump(2) + "\n");
    report.files.push_back(out("settings.json"));
    return report;
}

}  // namespace telescope
