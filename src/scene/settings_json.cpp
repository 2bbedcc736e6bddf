#include "scene/settings_json.h"

#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "core/error.h"
#include "scene/enum_names.h"
#include "scene/scene_loader.h"

namespace telescope {

using nlohmann::json;

namespace {

// Reads j[key] (when present) as one of the table's names.
template <class E, size_t N>
void readName(const json& j, const char* key, const Named<E> (&table)[N], E& value) {
    if (!j.contains(key)) return;
    const std::string name = j.at(key).get<std::string>();
    for (const Named<E>& n : table)
        if (name == n.name) {
            value = n.value;
            return;
        }
    throw std::invalid_argument(fmt::format("'{}': unknown value '{}'", key, name));
}

template <class T>
void readValue(const json& j, const char* key, T& value) {
    if (j.contains(key)) value = j.at(key).get<T>();
}

}  // namespace

const char* transmittanceEstimatorName(TransmittanceEstimatorType t) {
    return nameOf(kTransmittanceEstimatorNames, t);
}

// ---- Pmf ----
void to_json(json& j, const PmfSettings& p) {
    j = {{"type", nameOf(kPmfTypeNames, p.type)}};
    switch (p.type) {
    case PmfType::Geometric: j["r"] = p.r; break;
    case PmfType::PowerLaw: j["alpha"] = p.alpha; break;
    case PmfType::Auto: j["pilot_spp"] = p.pilotSpp, j["pilot_levels"] = p.pilotLevels; break;
    }
    j["origin"] = p.origin;
}

void from_json(const json& j, PmfSettings& p) {
    readName(j, "type", kPmfTypeNames, p.type);
    readValue(j, "r", p.r);
    readValue(j, "alpha", p.alpha);
    readValue(j, "pilot_spp", p.pilotSpp);
    readValue(j, "pilot_levels", p.pilotLevels);
    readValue(j, "origin", p.origin);
}

// ---- Debiasing (photon mapping's block parameters included) ----
void to_json(json& j, const DebiasSettings& d) {
    if (d.estimator == DebiasEstimator::None) {
        j = nullptr;
        return;
    }
    j = {{"estimator", nameOf(kDebiasEstimatorNames, d.estimator)}, {"pmf", d.pmf}};
    j["level_schedule"] = nameOf(kLevelScheduleNames, d.schedule);
    if (d.testPmfWeight != 1.0f) j["test_pmf_weight"] = d.testPmfWeight;
}

void from_json(const json& j, DebiasSettings& d) {
    if (j.is_null()) {
        d.estimator = DebiasEstimator::None;
        return;
    }
    readName(j, "estimator", kDebiasEstimatorNames, d.estimator);
    if (j.contains("pmf")) from_json(j.at("pmf"), d.pmf);
    readName(j, "level_schedule", kLevelScheduleNames, d.schedule);
    d.testPmfWeight = j.value("test_pmf_weight", 1.0f);  // written only when it is not 1
    readValue(j, "area_ratio", d.photon.areaRatio);
    readValue(j, "photon_growth", d.photon.photonGrowth);
    readValue(j, "level_cap", d.photon.levelCap);
}

// ---- Transmittance estimator ----
void to_json(json& j, const TransmittanceEstimatorSettings& t) {
    j = {{"type", transmittanceEstimatorName(t.type)}, {"level", t.level}};
    if (t.type == TransmittanceEstimatorType::DebiasedRayMarch) j["pmf"] = t.pmf;
    if (t.type == TransmittanceEstimatorType::Taylor) {
        j["terms"] = t.terms;
        j["points"] = t.points;
    }
}

void from_json(const json& j, TransmittanceEstimatorSettings& t) {
    if (j.contains("type")) {
        const std::string name = j.at("type").get<std::string>();
        const auto type = valueOf(kTransmittanceEstimatorNames, name);
        if (!type) throw std::invalid_argument(fmt::format("'type': unknown transmittance estimator '{}'", name));
        t.type = *type;
    }
    readValue(j, "level", t.level);
    readValue(j, "terms", t.terms);
    readValue(j, "points", t.points);
    if (j.contains("pmf")) from_json(j.at("pmf"), t.pmf);
}

// ---- Photon mapping ----
void to_json(json& j, const PhotonSettings& p) {
    j = {{"photon_count", p.photonCount},
         {"gather_radius", p.gatherRadius},
         {"alpha", p.alpha},
         {"kernel", nameOf(kPhotonKernelNames, p.kernel)},
         {"direct_lighting", nameOf(kDirectLightingNames, p.directLighting)},
         {"gather_photon_count", p.gatherCount}};
    if (!p.testRadianceScaling) j["test_radiance_scaling"] = false;
    if (p.testGatherCosine) j["test_gather_cosine"] = true;
}

void from_json(const json& j, PhotonSettings& p) {
    readValue(j, "photon_count", p.photonCount);
    readValue(j, "gather_radius", p.gatherRadius);
    readValue(j, "alpha", p.alpha);
    readName(j, "kernel", kPhotonKernelNames, p.kernel);
    readName(j, "direct_lighting", kDirectLightingNames, p.directLighting);
    readValue(j, "gather_photon_count", p.gatherCount);
    p.testRadianceScaling = j.value("test_radiance_scaling", true);  // written only when false
    p.testGatherCosine = j.value("test_gather_cosine", false);       // written only when true
}

// ---- Integrator ----
json integratorJson(const IntegratorSettings& in, bool withTransmittance) {
    json integrator = {{"type", nameOf(kIntegratorTypeNames, in.type)},
                       {"min_bounces", in.minBounces},
                       {"max_bounces", in.maxBounces},
                       {"enable_light_sampling", in.enableLightSampling},
                       {"enable_two_sided_shading", in.enableTwoSidedShading},
                       {"debias", in.debias}};
    if (usesPhotons(in)) {
        integrator.update(json(in.photon));
        if (in.debias.estimator != DebiasEstimator::None) {
            integrator["debias"]["area_ratio"] = in.debias.photon.areaRatio;
            integrator["debias"]["photon_growth"] = in.debias.photon.photonGrowth;
            integrator["debias"]["level_cap"] = in.debias.photon.levelCap;
        }
    }
    if (withTransmittance) integrator["transmittance_estimator"] = in.transmittance;
    return integrator;
}

void from_json(const json& j, IntegratorSettings& s) {
    readName(j, "type", kIntegratorTypeNames, s.type);
    readValue(j, "min_bounces", s.minBounces);
    readValue(j, "max_bounces", s.maxBounces);
    readValue(j, "enable_light_sampling", s.enableLightSampling);
    readValue(j, "enable_two_sided_shading", s.enableTwoSidedShading);
    if (j.contains("debias")) from_json(j.at("debias"), s.debias);
    from_json(j, s.photon);
    if (j.contains("transmittance_estimator")) from_json(j.at("transmittance_estimator"), s.transmittance);
}

// ---- A render's settings ----
json resolvedSettings(const Scene& scene) {
    return {{"integrator", integratorJson(scene.integrator, !scene.media.empty())},
            {"camera", {{"resolution", {scene.camera.width, scene.camera.height}},
                        {"fov", scene.camera.fovDegrees},
                        {"reconstruction_filter", nameOf(kPixelFilterNames, scene.camera.filter)}}}};
}

void applySettings(Scene& scene, const json& settings, const std::string& source) {
    const char* key = "";
    try {
        if (!settings.is_object()) throw std::invalid_argument("expected an object, got " + settings.dump());
        if (settings.contains("integrator")) {
            key = "integrator";
            from_json(settings.at("integrator"), scene.integrator);
        }
        if (settings.contains("camera")) {
            key = "camera";
            const json& c = settings.at("camera");
            if (c.contains("resolution")) {
                scene.camera.width = c.at("resolution").at(0).get<uint32_t>();
                scene.camera.height = c.at("resolution").at(1).get<uint32_t>();
            }
            readValue(c, "fov", scene.camera.fovDegrees);
            readName(c, "reconstruction_filter", kPixelFilterNames, scene.camera.filter);
        }
    } catch (const std::exception& e) {
        throw InputError(source, key, fmt::format("bad settings: {}", e.what()));
    }
}

Scene reproduceScene(const std::string& sceneDocument, const std::string& sceneFile, const std::string& settings) {
    Scene scene = loadSceneFromString(sceneDocument, sceneFile, std::filesystem::path(sceneFile).parent_path().string());
    const json parsed = json::parse(settings, nullptr, /*allow_exceptions=*/false);
    if (parsed.is_discarded()) throw InputError(sceneFile, "settings", "the settings are not valid JSON");
    applySettings(scene, parsed, sceneFile);
    return scene;
}

}  // namespace telescope
