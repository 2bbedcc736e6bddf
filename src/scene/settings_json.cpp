#include "scene/settings_json.h"

namespace telescope {

using nlohmann::json;

void to_json(json& j, const PmfSettings& p) {
    switch (p.type) {
    case PmfType::Geometric: j = {{"type", "geometric"}, {"r", p.r}}; break;
    case PmfType::PowerLaw: j = {{"type", "power_law"}, {"alpha", p.alpha}}; break;
    case PmfType::Auto: j = {{"type", "auto"}, {"pilot_spp", p.pilotSpp}, {"pilot_levels", p.pilotLevels}}; break;
    }
    j["origin"] = p.origin;
}

void to_json(json& j, const DebiasSettings& d) {
    if (d.estimator == DebiasEstimator::None) {
        j = nullptr;
        return;
    }
    j = {{"estimator", d.estimator == DebiasEstimator::SingleTerm ? "single_term" : "sum"}, {"pmf", d.pmf}};
    j["level_schedule"] = d.schedule == LevelSchedule::PerPixel ? "per_pixel"
                          : d.schedule == LevelSchedule::Uniform ? "uniform"
                                                                 : "queued";
    if (d.testPmfWeight != 1.0f) j["test_pmf_weight"] = d.testPmfWeight;
}

void to_json(json& j, const TransmittanceEstimatorSettings& t) {
    j = {{"type", transmittanceEstimatorName(t.type)}, {"level", t.level}};
    if (t.type == TransmittanceEstimatorType::DebiasedRayMarch) j["pmf"] = t.pmf;
}

void to_json(json& j, const PhotonSettings& p) {
    const char* kernels[] = {"cone", "uniform", "epanechnikov"};
    j = {{"photon_count", p.photonCount},
         {"gather_radius", p.gatherRadius},
         {"alpha", p.alpha},
         {"kernel", kernels[uint32_t(p.kernel)]},
         {"direct_lighting", p.directLighting == DirectLighting::Photons ? "photons" : "next_event"}};
}

json resolvedSettings(const Scene& scene) {
    const IntegratorSettings& in = scene.integrator;
    const char* types[] = {"path_tracer", "photon_map", "progressive_photon_map"};
    json integrator = {{"type", types[uint32_t(in.type)]},
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
    if (!scene.media.empty()) integrator["transmittance_estimator"] = in.transmittance;
    return {{"integrator", integrator},
            {"camera", {{"resolution", {scene.camera.width, scene.camera.height}},
                        {"fov", scene.camera.fovDegrees},
                        {"reconstruction_filter", scene.camera.filter}}}};
}

}  // namespace telescope
