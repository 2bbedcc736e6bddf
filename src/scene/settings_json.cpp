#include "scene/settings_json.h"

#include <filesystem>

#include <fmt/format.h>

#include "core/error.h"
#include "scene/enum_names.h"
#include "scene/scene_loader.h"

namespace telescope {

using nlohmann::json;

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

// ---- Transmittance estimator ----
void to_json(json& j, const TransmittanceEstimatorSettings& t) {
    j = {{"type", transmittanceEstimatorName(t.type)}, {"level", t.level}};
    if (t.type == TransmittanceEstimatorType::DebiasedRayMarch) j["pmf"] = t.pmf;
    if (t.type == TransmittanceEstimatorType::Taylor) {
        j["terms"] = t.terms;
        j["points"] = t.points;
    }
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
    if (!p.testCoincidentSurfaces) j["test_coincident_surfaces"] = false;
}

// ---- Integrator ----
json integratorJson(const IntegratorSettings& in, bool withTransmittance) {
    json integrator = {{"type", nameOf(kIntegratorTypeNames, in.type)},
                       {"min_bounces", in.minBounces},
                       {"max_bounces", in.maxBounces},
                       {"enable_two_sided_shading", in.enableTwoSidedShading},
                       {"debias", in.debias}};
    if (!usesPhotons(in)) integrator["enable_light_sampling"] = in.enableLightSampling;  // photons: direct_lighting
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

// ---- A render's settings ----
json resolvedSettings(const Scene& scene) {
    return {{"integrator", integratorJson(scene.integrator, !scene.media.empty())},
            {"camera", {{"resolution", {scene.camera.width, scene.camera.height}},
                        {"fov", scene.camera.fovDegrees},
                        {"reconstruction_filter", nameOf(kPixelFilterNames, scene.camera.filter)}}}};
}

Scene reproduceScene(const std::string& sceneDocument, const std::string& sceneFile, const std::string& settings) {
    const json recorded = json::parse(settings, nullptr, /*allow_exceptions=*/false);
    if (recorded.is_discarded() || !recorded.is_object())
        throw InputError(sceneFile, "settings", "the settings are not a JSON object");
    json document = json::parse(sceneDocument, nullptr, /*allow_exceptions=*/false);
    if (document.is_discarded() || !document.is_object())
        throw InputError(sceneFile, "", "the scene document is not a JSON object");
    // The recorded integrator is complete (every default filled in): it replaces the document's
    // whole, so no key of the document's mixes into it. The camera's recorded keys replace the
    // document's; its placement stays the document's.
    if (const auto i = recorded.find("integrator"); i != recorded.end()) document["integrator"] = *i;
    if (const auto c = recorded.find("camera"); c != recorded.end()) {
        if (!c->is_object()) throw InputError(sceneFile, "camera", "the recorded camera settings are not an object");
        for (const auto& [key, value] : c->items()) document["camera"][key] = value;
    }
    return loadSceneFromString(document.dump(), sceneFile, std::filesystem::path(sceneFile).parent_path().string());
}

}  // namespace telescope
