#include "session/outputs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "scene/enum_names.h"
#include "scene/settings_json.h"
#include "render/image_output.h"
#include "render/pmf_pilot.h"
#include "scene/scene_loader.h"

namespace fs = std::filesystem;

namespace telescope::session {

// The first key where two JSON documents differ ("" when they are equal or unreadable).
std::string firstDifference(const std::string& a, const std::string& b) {
    nlohmann::json ja = nlohmann::json::parse(a, nullptr, false), jb = nlohmann::json::parse(b, nullptr, false);
    if (ja.is_discarded() || jb.is_discarded()) return "";
    nlohmann::json d = nlohmann::json::diff(ja, jb);
    if (d.empty()) return "";
    std::string path = d[0].value("path", "");
    // JSON pointer "/integrator/max_bounces" -> "integrator.max_bounces"
    if (!path.empty() && path[0] == '/') path.erase(0, 1);
    std::replace(path.begin(), path.end(), '/', '.');
    return path.empty() ? "(the whole document)" : path;
}

std::string pendingBlockText(uint64_t block, uint32_t level, uint32_t done, uint32_t total) {
    return fmt::format("block {} in progress (level {}, {} of {} photon passes)", block, level, done, total);
}

Scene loadWithOverrides(const CommonOptions& o, const std::vector<SceneOverride>& more) {
    std::vector<SceneOverride> overrides;
    for (const auto& s : o.sets) overrides.push_back(parseOverride(s));
    overrides.insert(overrides.end(), more.begin(), more.end());
    return loadScene(o.scenePath, overrides);
}

void takeRecordedPmfs(Scene& scene, const Checkpoint& c, const std::string& path) {
    const char* key = autoPmfKey(scene.integrator);
    if (!*key) return;
    if (c.settings.empty())
        throw InputError(path, key, "the checkpoint records no settings, so not the pmf its pilot chose: put a pmf in "
                                    "the scene, or render again");
    const Scene recorded = reproduceScene(c.scene, scene.path, c.settings);
    IntegratorSettings& in = scene.integrator;
    if (debiasPmfIsAuto(in)) in.debias.pmf = recorded.integrator.debias.pmf;
    if (transmittancePmfIsAuto(in)) in.transmittance.pmf = recorded.integrator.transmittance.pmf;
    if (const char* left = autoPmfKey(in); *left)
        throw InputError(path, left, "the checkpoint records this pmf as \"auto\" too: it has no pilot's choice to resume with");
}

ResolvedScene resolve(gpu::Context& context, Scene scene, uint32_t seed, bool quiet) {
    Resolution r = resolveScene(context, std::move(scene), seed);
    if (!quiet)
        for (const PmfPilotResult& pilot : r.pilots) fmt::print(stderr, "{}", pilot.summary());
    return std::move(r.scene);
}

// ---- Derivative renders (render/derivative.h) ----

DerivativeSettings derivativeSettings(const DerivativeOptions& d) {
    DerivativeSettings s;
    s.key = d.key;
    if (!std::isnan(d.step) && !(d.step > 0.0 && std::isfinite(d.step)))
        throw InputError("", "--step", fmt::format("h_0 must be a positive number, not {}", d.step));
    s.step = std::isnan(d.step) ? 0.0 : d.step;
    s.estimator = parseDerivativeEstimator(d.estimator, "--derivative-estimator");
    s.levels = d.levels;
    if (!d.pmf.empty()) {
        nlohmann::json j;
        try {
            j = nlohmann::json::parse(d.pmf);
        } catch (const nlohmann::json::exception&) {
            throw InputError("", "--derivative-pmf", fmt::format("'{}' is not JSON", d.pmf));
        }
        const std::string type = j.is_object() && j.contains("type") && j["type"].is_string() ? j["type"].get<std::string>() : "";
        const std::optional<PmfType> pmfType = valueOf(kPmfTypeNames, type);
        if (pmfType == PmfType::Auto) {
            for (const auto& [k, v] : j.items())
                if (k != "type" && k != "pilot_spp")
                    throw InputError("", "--derivative-pmf", fmt::format("unknown key \"{}\" of the auto pmf", k));
            s.autoPmf = true;
            if (j.contains("pilot_spp")) {
                if (!j["pilot_spp"].is_number_unsigned() || j["pilot_spp"].get<uint32_t>() < 1 || j["pilot_spp"].get<uint32_t>() > 1024)
                    throw InputError("", "--derivative-pmf", "\"pilot_spp\" must be an integer in [1, 1024]");
                s.pilotSpp = j["pilot_spp"].get<uint32_t>();
            }
            s.pmf.origin = "auto";
            return s;
        }
        auto number = [&](const char* name) {
            if (!j.contains(name) || !j[name].is_number())
                throw InputError("", "--derivative-pmf", fmt::format("a {} pmf needs a number \"{}\"", type, name));
            const double v = j[name].get<double>();
            if (!(v > 0.0 && v < 1.0))
                throw InputError("", "--derivative-pmf", fmt::format("\"{}\" must lie in (0, 1), not {}", name, v));
            return float(v);
        };
        for (const auto& [k, v] : j.items())
            if (k != "type" && k != "r" && k != "alpha")
                throw InputError("", "--derivative-pmf", fmt::format("unknown key \"{}\"", k));
        if (pmfType == PmfType::Geometric) {
            s.pmf.type = PmfType::Geometric;
            s.pmf.r = number("r");
        } else if (pmfType == PmfType::PowerLaw) {
            s.pmf.type = PmfType::PowerLaw;
            s.pmf.alpha = number("alpha");
        } else {
            throw InputError("", "--derivative-pmf", "expected {\"type\": \"geometric\", \"r\": R} or "
                                                     "{\"type\": \"power_law\", \"alpha\": A}");
        }
        s.pmf.origin = "given (--derivative-pmf)";
    }
    return s;
}

std::vector<std::pair<std::string, std::string>> derivativeMetadata(const DerivativeRenderer& r) {
    const DerivativeParameter& p = r.parameter();
    return {{"telescope:derivative_key", p.key},
            {"telescope:derivative_value", fmt::format("{:.17g}", p.value)},
            {"telescope:derivative_step", fmt::format("{:.17g}", p.step)},
            {"telescope:derivative_estimator", derivativeEstimatorName(r.settings().estimator)}};
}

std::string derivativeSettingsAsRun(const Scene& scene, const DerivativeRenderer& r) {
    const DerivativeParameter& p = r.parameter();
    const DerivativeSettings& d = r.settings();
    nlohmann::json j = resolvedSettings(scene);
    nlohmann::json& dj = j["derivative"];
    dj["key"] = p.key;
    dj["value"] = p.value;
    dj["step"] = p.step;
    dj["estimator"] = derivativeEstimatorName(d.estimator);
    dj["levels"] = d.levels;
    if (d.estimator == DerivativeEstimator::SingleTerm || d.estimator == DerivativeEstimator::Sum) {
        std::vector<double> pmf;
        for (uint32_t level = 0; level < d.levels; ++level) pmf.push_back(r.levelProbability(level));
        dj["pmf"] = pmf;  // P(J = j), j < levels (after "levels" in key order: that difference is named first)
    }
    return j.dump();
}

SettingsParts splitDerivativeSettings(const std::string& settings) {
    if (settings.empty()) return {settings, nullptr};
    nlohmann::json j = nlohmann::json::parse(settings, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("derivative")) return {settings, nullptr};
    SettingsParts parts{"", j["derivative"]};
    j.erase("derivative");
    parts.scene = j.dump();
    return parts;
}

void reportIgnoredKeys(const Scene& scene, bool quiet) {
    if (quiet) return;
    for (const auto& key : scene.ignoredKeys) {
        const std::string why = ignoredKeyReason(key);
        fmt::print(stderr, "{}: ignoring '{}' ({})\n", scene.path, key, why.empty() ? "not used by Telescope" : why);
    }
}

gpu::ContextOptions contextOptions(const CommonOptions& o) {
    gpu::ContextOptions c;
    c.deviceIndex = o.device;
    c.validation = o.validation;
    return c;
}

// ---- Output paths are checked before any work is done ----
void checkOutputPath(const std::string& path, const char* option, const char* extension) {
    fs::path p(path);
    if (extension && p.extension() != extension)
        throw InputError("", option, fmt::format("'{}' must end in {}", path, extension));
    fs::path dir = p.parent_path().empty() ? fs::path(".") : p.parent_path();
    if (!fs::is_directory(dir))
        throw InputError("", option, fmt::format("directory '{}' does not exist", dir.string()));
}

void checkImageOutputs(ImageOutputOptions& o) {
    checkOutputPath(o.exrPath, "-o", ".exr");
    if (!o.noPng) {
        if (o.pngPath.empty()) o.pngPath = fs::path(o.exrPath).replace_extension(".png").string();
        checkOutputPath(o.pngPath, "--png", ".png");
    }
    if (!o.checkpointPath.empty()) checkOutputPath(o.checkpointPath, "--checkpoint", nullptr);
}

void checkValidation(const gpu::Context& context) {
    if (context.validationMessageCount() > 0)
        throw std::runtime_error(
            fmt::format("{} Vulkan validation message(s) were reported", context.validationMessageCount()));
}

void writeImages(const ImageOutputOptions& o, const Film& film, const OutputInfo& info) {
    ImageMetadata meta;
    meta.entries = {
        {"telescope:version", TELESCOPE_VERSION},
        {"telescope:scene_file", info.sceneFile},
        {"telescope:scene", info.sceneDocument},
        {"telescope:estimator", info.estimator},
        {"telescope:settings", info.settings},
        {"telescope:seed", std::to_string(info.seed)},
        {"telescope:spp", std::to_string(film.samplesPerPixel())},
        {"telescope:render_seconds", fmt::format("{:.6f}", info.seconds)},
        {"telescope:device", info.device},
        {"telescope:non_finite_samples", std::to_string(film.nonFiniteSamples())},
    };
    for (const auto& e : info.extra) meta.entries.push_back(e);
    if (!info.shards.empty()) {
        std::string seeds;
        for (uint32_t seed : info.seeds) {
            if (!seeds.empty()) seeds += ',';
            seeds += std::to_string(seed);
        }
        meta.entries.push_back({"telescope:seeds", seeds});
        meta.entries.push_back({"telescope:shards", info.shards});
    }
    writeExr(o.exrPath, film, meta);
    if (!o.noPng) writePngPreview(o.pngPath, film);
    if (!o.checkpointPath.empty()) saveCheckpoint(o.checkpointPath, checkpointOf(film, info));
}

Checkpoint checkpointOf(const Film& film, const OutputInfo& info) {
    return Checkpoint{film, info.seed, info.sceneDocument, info.estimator, info.settings,
                      info.seeds.empty() ? std::vector<uint32_t>{info.seed} : info.seeds};
}

}  // namespace telescope::session
