// "camera", "integrator" (path tracer and photon mapping, the debias block, the transmittance
// estimator) and "renderer": the settings of a render.
#include "scene/scene_reader.h"

#include <cmath>

#include "scene/enum_names.h"
#include "scene/photon_levels.h"
#include "shared/gpu_types.h"
#include "shared/transmittance_estimators.h"
#include "scene/transform.h"

namespace telescope {

// ---- Default pmfs (docs/ESTIMATORS.md section 1, "Defaults") ----
PmfSettings defaultPathDepthPmf() {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = 0.25f;
    p.origin = "default for path depth: on the shipped path-traced scenes E[D_j^2] falls ~0.5 per level, so a "
               "geometric pmf has finite variance only for r < 0.5; the auto pilot picks r = 0.22 to 0.29 there "
               "(docs/ACCURACY.md)";
    return p;
}

PmfSettings defaultTransmittancePmf() {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = 0.65f;
    p.origin = "default for ray marching: finite variance and cost need 0.5 < r < 15/16 (E[D_j^2] falls about 16x "
               "per level for a smooth density, points double); pmf \"auto\" measured r = 0.74 to 0.88 on the shipped "
               "media scenes, predicting at most 7% less work x variance";
    // "auto": 2 spp (each rendered three times) at 5 levels, about 30 samples per pixel of
    // pilot, 2^(k+6) points per estimate at the deepest measured level.
    p.pilotSpp = 2;
    p.pilotLevels = 5;
    return p;
}

namespace scene_reader {

namespace {

constexpr uint32_t kMaxResolution = 16384;
constexpr uint32_t kMaxBounces = 1024;
constexpr uint32_t kMaxSpp = 1u << 24;
constexpr uint32_t kMaxPhotonCount = 1u << 27;  // photon paths per pass (4 GiB of photons at 32 bytes)

constexpr std::string_view kUnsupportedCameras[] = {"thinlens", "equirectangular", "cubemap"};
constexpr std::string_view kUnsupportedIntegrators[] = {
    "bidirectional_path_tracer", "light_tracer",
    "kelemen_mlt", "multiplexed_mlt", "reversible_jump_mlt"};

}  // namespace

// ---- Camera ----

void SceneReader::readCamera(const json& v) {
    const std::string key = "camera";
    expectObject(v, key);
    Camera& cam = scene_.camera;

    const std::string type = typeOr(v, key, "pinhole");
    if (isOneOf(kUnsupportedCameras, type)) fail("camera.type", fmt::format("unsupported camera type '{}'", type));
    if (type != "pinhole") fail("camera.type", fmt::format("unknown camera type '{}'", type));
    if (const json* medium = find(v, "medium"); medium && !medium->is_null()) cam.medium = mediumRef(*medium, "camera.medium");

    if (const json* fov = find(v, "fov")) {
        cam.fovDegrees = number(*fov, "camera.fov");
        if (!(cam.fovDegrees > 0.0f && cam.fovDegrees < 180.0f)) fail("camera.fov", "the field of view must be in (0, 180) degrees");
    }
    if (const json* res = find(v, "resolution")) {
        if (res->is_array()) {
            if (res->size() != 2) fail("camera.resolution", fmt::format("expected [width, height], got {} elements", res->size()));
            cam.width = integer((*res)[0], "camera.resolution[0]", 1, kMaxResolution);
            cam.height = integer((*res)[1], "camera.resolution[1]", 1, kMaxResolution);
        } else {
            cam.width = cam.height = integer(*res, "camera.resolution", 1, kMaxResolution);
        }
    }
    if (const json* filter = find(v, "reconstruction_filter")) {
        const std::string name = string(*filter, "camera.reconstruction_filter");
        const auto pixelFilter = valueOf(kPixelFilterNames, name);
        if (!pixelFilter)
            fail("camera.reconstruction_filter",
                 fmt::format("unknown reconstruction filter '{}' (expected {})", name, expectedNames(kPixelFilterNames)));
        cam.filter = *pixelFilter;
    }

    // Basis: z = forward, y = up; image right = forward x up (Tungsten negates its basis x)
    const glm::mat4 m = find(v, "transform") ? transform(v["transform"], "camera.transform") : glm::mat4(1.0f);
    const glm::vec3 forward = transformVector(m, {0, 0, 1}), up = transformVector(m, {0, 1, 0});
    const glm::vec3 right = glm::cross(forward, up);
    if (isDegenerate(forward) || isDegenerate(right)) fail("camera.transform", "the camera basis is degenerate");
    cam.position = glm::vec3(m[3]);
    cam.forward = glm::normalize(forward);
    cam.right = glm::normalize(right);
    cam.up = glm::cross(cam.right, cam.forward);

    ignoreUnread(v, key, {"type", "fov", "resolution", "reconstruction_filter", "transform", "medium"});
}

// ---- Integrator ----

void SceneReader::readIntegrator(const json& v) {
    const std::string key = "integrator";
    expectObject(v, key);
    IntegratorSettings& s = scene_.integrator;

    const std::string type = typeOr(v, key, "path_tracer");
    if (isOneOf(kUnsupportedIntegrators, type))
        fail("integrator.type",
             fmt::format("unsupported integrator type '{}' (Telescope has path_tracer, photon_map and "
                         "progressive_photon_map: try --set integrator.type=\"path_tracer\")",
                         type));
    const std::optional<IntegratorType> integrator = valueOf(kIntegratorTypeNames, type);
    if (!integrator) fail("integrator.type", fmt::format("unknown integrator type '{}'", type));
    s.type = *integrator;
    if (usesPhotons(s)) {
        readPhotonSettings(v, key);
        return;
    }

    if (const json* n = find(v, "min_bounces")) s.minBounces = integer(*n, "integrator.min_bounces", 0, kMaxBounces);
    if (const json* n = find(v, "max_bounces")) {
        s.maxBounces = integer(*n, "integrator.max_bounces", 0, kMaxBounces);
        if (s.maxBounces == 0)
            fail("integrator.max_bounces",
                 "0 renders nothing: max_bounces counts the light connection, as in Tungsten (1 shows only the "
                 "emitters, 2 adds direct light)");
    }
    if (const json* b = find(v, "enable_light_sampling")) s.enableLightSampling = boolean(*b, "integrator.enable_light_sampling");
    if (const json* b = find(v, "enable_two_sided_shading"))
        s.enableTwoSidedShading = boolean(*b, "integrator.enable_two_sided_shading");
    if (const json* d = find(v, "debias"); d && !d->is_null()) readDebias(*d, "integrator.debias");
    if (const json* t = find(v, "transmittance_estimator"); t && !t->is_null())
        readTransmittanceEstimator(*t, "integrator.transmittance_estimator");
    // Tungsten's switches that drop light from the image (PathTracer.cpp): false would render a
    // different image, which Telescope does not; true is what it renders.
    for (const char* name : {"low_order_scattering", "include_surfaces"})
        if (const json* b = find(v, name); b && !boolean(*b, key + "." + name))
            fail(key + "." + name, "false is not supported (Telescope renders every scattering order and the "
                                   "surfaces, Tungsten's default true)");

    onlyBoolean(v, key, "enable_consistency_checks", false,
                "Telescope does not drop paths whose shading and geometric normals disagree (Tungsten's checks)");
    onlyBoolean(v, key, "enable_volume_light_sampling", true,
                "Telescope samples a light at every medium scattering vertex when enable_light_sampling is on");
    ignoreUnread(v, key, {"type", "min_bounces", "max_bounces", "enable_light_sampling", "enable_two_sided_shading", "debias",
                          "transmittance_estimator", "low_order_scattering", "include_surfaces",
                          "enable_consistency_checks", "enable_volume_light_sampling"});
}

// photon_map and progressive_photon_map: Tungsten's keys (photon_count, gather_radius, alpha,
// max_bounces) plus Telescope's debias, direct_lighting and kernel. The gather radius is
// required: Tungsten's default (1e30 with a k-nearest-neighbour cap) has no meaning for the
// fixed-radius estimators here.
void SceneReader::readPhotonSettings(const json& v, const std::string& key) {
    IntegratorSettings& s = scene_.integrator;
    PhotonSettings& p = s.photon;
    const std::string type = string(v["type"], "integrator.type");

    if (const json* n = find(v, "min_bounces"); n && integer(*n, "integrator.min_bounces", 0, kMaxBounces) != 0)
        fail("integrator.min_bounces", "photon mapping supports only min_bounces = 0");
    if (const json* n = find(v, "max_bounces")) s.maxBounces = integer(*n, "integrator.max_bounces", 1, kMaxBounces);
    if (const json* b = find(v, "enable_two_sided_shading"))
        s.enableTwoSidedShading = boolean(*b, "integrator.enable_two_sided_shading");
    if (const json* n = find(v, "photon_count"))
        p.photonCount = integer(*n, "integrator.photon_count", 1, kMaxPhotonCount);

    const json* radius = find(v, "gather_radius");
    if (!radius) fail("integrator.gather_radius", fmt::format("missing: '{}' needs a gather radius in scene units", type));
    p.gatherRadius = number(*radius, "integrator.gather_radius");
    if (!(p.gatherRadius > 0.0f)) fail("integrator.gather_radius", fmt::format("must be positive, got {}", p.gatherRadius));

    if (const json* a = find(v, "alpha")) {
        p.alpha = number(*a, "integrator.alpha");
        if (!(p.alpha > 0.0f && p.alpha < 1.0f)) fail("integrator.alpha", fmt::format("alpha must be in (0, 1), got {}", p.alpha));
    }
    if (const json* k = find(v, "kernel")) {
        const std::string name = string(*k, "integrator.kernel");
        const auto kernel = valueOf(kPhotonKernelNames, name);
        if (!kernel)
            fail("integrator.kernel", fmt::format("unknown kernel '{}' (expected {})", name, expectedNames(kPhotonKernelNames)));
        p.kernel = *kernel;
    }
    if (const json* d = find(v, "direct_lighting")) {
        const std::string name = string(*d, "integrator.direct_lighting");
        const auto lighting = valueOf(kDirectLightingNames, name);
        if (!lighting)
            fail("integrator.direct_lighting",
                 fmt::format("unknown direct lighting '{}' (expected {})", name, expectedNames(kDirectLightingNames)));
        p.directLighting = *lighting;
    }
    if (const json* d = find(v, "debias"); d && !d->is_null()) {
        readDebias(*d, "integrator.debias", true);
        readPhotonBlocks(*d, "integrator.debias");
    }
    // Tungsten's k-nearest gather. Absent, every photon within the radius counts (Telescope's
    // fixed-radius gather; Tungsten's own default is 20: docs/SCENE-FORMAT.md). With k nearest the
    // kernel defaults to Tungsten's uniform one.
    if (const json* n = find(v, "gather_photon_count")) {
        p.gatherCount = integer(*n, "integrator.gather_photon_count", 0, shader::kMaxGatherCount);
        if (p.gatherCount > 0 && s.debias.estimator != DebiasEstimator::None)
            fail("integrator.gather_photon_count",
                 fmt::format("a k-nearest gather (k = {}) cannot be debiased: the telescoping levels need nested "
                             "fixed-radius kernels, and a k-nearest radius changes with every photon set; set "
                             "gather_photon_count to 0 or drop the debias block", p.gatherCount));
        if (p.gatherCount > 0 && !find(v, "kernel")) p.kernel = PhotonKernel::Uniform;
    }
    if (const json* t = find(v, "test_radiance_scaling"))
        p.testRadianceScaling = boolean(*t, "integrator.test_radiance_scaling");
    if (const json* t = find(v, "test_gather_cosine")) p.testGatherCosine = boolean(*t, "integrator.test_gather_cosine");
    if (const json* t = find(v, "test_coincident_surfaces"))
        p.testCoincidentSurfaces = boolean(*t, "integrator.test_coincident_surfaces");
    onlyBoolean(v, key, "enable_consistency_checks", false,
                "Telescope does not drop paths whose shading and geometric normals disagree (Tungsten's checks)");
    ignoreUnread(v, key, {"type", "min_bounces", "max_bounces", "enable_two_sided_shading", "photon_count",
                          "gather_radius", "alpha", "kernel", "direct_lighting", "debias", "gather_photon_count",
                          "test_radiance_scaling", "test_gather_cosine", "test_coincident_surfaces",
                          "enable_consistency_checks"});
}

// Photon mapping's blocks (docs/PHOTON-MAPPING.md): the geometric level pmf (r = 0.7 by default,
// continuing with q = 0.3), area_ratio s, photon_growth m, level_cap K and the schedule
// (uniform by default). Settings whose expected cost is infinite (q m >= 1) or whose samples
// have no finite mean (tail index a <= 1, i.e. m s <= 1) are rejected.
void SceneReader::readPhotonBlocks(const json& v, const std::string& key) {
    DebiasSettings& d = scene_.integrator.debias;
    PhotonBlockSettings& b = d.photon;
    if (d.estimator != DebiasEstimator::SingleTerm)
        fail(member(key, "estimator"), "photon mapping supports only the \"single_term\" estimator");
    if (!v.contains("pmf")) {
        d.pmf.type = PmfType::Geometric;
        d.pmf.r = 0.7f;
        d.pmf.origin = "default for photon mapping's blocks: r = 0.7 (continue with q = 0.3) with m = 3, s = 1/sqrt(2): "
                       "7 passes per sample, tail index 1.45, typical error ~ cost^-0.31 (docs/PHOTON-MAPPING.md)";
    } else if (d.pmf.type != PmfType::Geometric) {
        fail(member(member(key, "pmf"), "type"),
             "photon mapping's block levels take a \"geometric\" pmf (expected photon passes are infinite with a "
             "power law, and there is no pilot for \"auto\")");
    }
    d.schedule = LevelSchedule::Uniform;
    if (const json* schedule = find(v, "level_schedule")) {
        const std::string scheduleKey = member(key, "level_schedule");
        const std::string name = string(*schedule, scheduleKey);
        const auto photonSchedule = valueOf(kLevelScheduleNames, name);
        if (!photonSchedule || *photonSchedule == LevelSchedule::Queued)
            fail(scheduleKey, fmt::format("photon mapping takes the level schedule \"uniform\" or \"per_pixel\", got '{}'", name));
        d.schedule = *photonSchedule;
        if (d.schedule == LevelSchedule::PerPixel && scene_.integrator.type == IntegratorType::ProgressivePhotonMap)
            fail(scheduleKey, "progressive_photon_map shrinks the base radius per block, which needs the \"uniform\" schedule");
    }
    if (const json* a = find(v, "area_ratio")) {
        const std::string areaKey = member(key, "area_ratio");
        b.areaRatio = number(*a, areaKey);
        if (!(b.areaRatio > 0.0f && b.areaRatio < 1.0f)) fail(areaKey, fmt::format("must be in (0, 1), got {}", b.areaRatio));
    }
    if (const json* m = find(v, "photon_growth")) b.photonGrowth = integer(*m, member(key, "photon_growth"), 1, 1024);
    const PhotonBlockTheory t = photonBlockTheory(d.pmf.r, b.areaRatio, b.photonGrowth);
    if (!(t.q * b.photonGrowth < 1.0))
        fail(member(key, "photon_growth"),
             fmt::format("the expected photon passes per sample (1 - q) / (1 - q m) are infinite: q m = {:.4g} >= 1 "
                         "(q = 1 - pmf.r = {:.4g}, m = {})",
                         t.q * b.photonGrowth, t.q, b.photonGrowth));
    if (!(t.tailIndex > 1.0))
        fail(member(key, "photon_growth"),
             fmt::format("the samples have no finite mean: tail index a = ln(1/q) / (ln(1/q) - ln(m s) / 2) = {:.4g} <= 1 "
                         "(needs photon_growth x area_ratio > 1, got {} x {:.4g} = {:.4g})",
                         t.tailIndex, b.photonGrowth, b.areaRatio, b.photonGrowth * b.areaRatio));
    const std::string capKey = member(key, "level_cap");
    if (const json* k = find(v, "level_cap")) b.levelCap = integer(*k, capKey, 1, 64);
    else b.levelCap = photonDefaultLevelCap(b.areaRatio);
    const double longest = std::pow(double(b.photonGrowth), double(b.levelCap) - 1.0);
    if (!(longest < 2147483648.0))
        fail(capKey, fmt::format("a block at the last level would take m^(K-1) = {:.4g} photon passes (at most 2^31); "
                                 "lower the cap (K = {}{}) or photon_growth",
                                 longest, b.levelCap, find(v, "level_cap") ? "" : ", the default for this area_ratio"));
}

// Telescope's own block, read strictly: every key must be known.
void SceneReader::readDebias(const json& v, const std::string& key, bool photons) {
    expectObject(v, key);
    if (photons) rejectUnknownKeys(v, key, {"estimator", "pmf", "level_schedule", "area_ratio", "photon_growth", "level_cap"});
    else rejectUnknownKeys(v, key, {"estimator", "pmf", "level_schedule", "test_pmf_weight"});
    DebiasSettings& d = scene_.integrator.debias;
    if (const json* w = find(v, "test_pmf_weight")) {
        const std::string wKey = member(key, "test_pmf_weight");
        d.testPmfWeight = number(*w, wKey);
        if (!(d.testPmfWeight > 0.0f && std::isfinite(d.testPmfWeight)))
            fail(wKey, fmt::format("test_pmf_weight must be positive, got {}", d.testPmfWeight));
    }

    const std::string estimatorKey = member(key, "estimator");
    const json* estimator = find(v, "estimator");
    if (!estimator) fail(estimatorKey, fmt::format("missing (expected {})", expectedNames(kDebiasEstimatorNames)));
    const std::string name = string(*estimator, estimatorKey);
    const auto debiasEstimator = valueOf(kDebiasEstimatorNames, name);
    if (!debiasEstimator)
        fail(estimatorKey, fmt::format("unknown debias estimator '{}' (expected {})", name, expectedNames(kDebiasEstimatorNames)));
    d.estimator = *debiasEstimator;

    if (const json* schedule = find(v, "level_schedule"); schedule && !photons) {
        const std::string scheduleKey = member(key, "level_schedule");
        const std::string s = string(*schedule, scheduleKey);
        const auto levelSchedule = valueOf(kLevelScheduleNames, s);
        if (!levelSchedule)
            fail(scheduleKey, fmt::format("unknown level schedule '{}' (expected {})", s, expectedNames(kLevelScheduleNames)));
        d.schedule = *levelSchedule;
    }

    if (const json* pmf = find(v, "pmf")) d.pmf = readPmf(*pmf, member(key, "pmf"), d.pmf, true);
}

// A level pmf: geometric or power law, or (path depth and debiased ray marching) "auto", chosen by a pilot.
// Keys not given keep their value in pmf (the default of the telescope it belongs to).
PmfSettings SceneReader::readPmf(const json& v, const std::string& key, PmfSettings pmf, bool allowAuto) const {
    expectObject(v, key);
    const std::string type = typeOr(v, key, "geometric");
    auto openUnit = [&](const char* field) {
        const std::string fieldKey = member(key, field);
        const float x = number(v[field], fieldKey);
        if (!(x > 0.0f && x < 1.0f)) fail(fieldKey, fmt::format("{} must be in (0, 1), got {}", field, x));
        return x;
    };
    // Why this pmf: recorded settings (settings_json.h) carry the pilot's or the default's reason.
    pmf.origin = "given in the scene";
    if (const json* origin = find(v, "origin")) pmf.origin = string(*origin, member(key, "origin"));
    const std::optional<PmfType> pmfType = valueOf(kPmfTypeNames, type);
    if (!pmfType || (*pmfType == PmfType::Auto && !allowAuto))
        fail(member(key, "type"), fmt::format("unknown pmf type '{}' (expected {})", type,
                                              expectedNames(kPmfTypeNames, allowAuto ? 3 : 2)));
    pmf.type = *pmfType;
    switch (*pmfType) {
        case PmfType::Geometric:
            rejectUnknownKeys(v, key, {"type", "r", "origin"});
            if (find(v, "r")) pmf.r = openUnit("r");
            break;
        case PmfType::PowerLaw:
            rejectUnknownKeys(v, key, {"type", "alpha", "origin"});
            if (find(v, "alpha")) pmf.alpha = openUnit("alpha");
            break;
        case PmfType::Auto:
            rejectUnknownKeys(v, key, {"type", "pilot_spp", "pilot_levels", "origin"});
            if (const json* s = find(v, "pilot_spp")) pmf.pilotSpp = integer(*s, member(key, "pilot_spp"), 1, 1024);
            if (const json* l = find(v, "pilot_levels")) pmf.pilotLevels = integer(*l, member(key, "pilot_levels"), 3, 32);
            break;
    }
    return pmf;
}

// ---- Renderer ----

// Tungsten's switches whose one value Telescope renders: that value is honoured (read, not listed as
// ignored), any other is refused naming the key (it would change the image: a silent substitution).
void SceneReader::onlyBoolean(const json& v, const std::string& key, const char* name, bool supported,
                              const char* why) {
    if (const json* b = find(v, name); b && boolean(*b, member(key, name)) != supported)
        fail(member(key, name), fmt::format("{} is not supported: {}", supported ? "false" : "true", why));
}

void SceneReader::readRenderer(const json& v) {
    expectObject(v, "renderer");
    if (const json* spp = find(v, "spp")) scene_.renderer.spp = integer(*spp, "renderer.spp", 1, kMaxSpp);
    onlyBoolean(v, "renderer", "stratified_sampler", false,
                "Telescope draws independent random numbers per sample (a stratified sampler changes the noise "
                "of the image); remove the key or set it to false");
    onlyBoolean(v, "renderer", "enable_resume_render", false,
                "resume a render with --checkpoint FILE and --resume FILE instead");
    // Tungsten's time limits, "0" (or 0) = none: the command line's --time and --checkpoint-every.
    for (const char* name : {"timeout", "checkpoint_interval"}) {
        const json* t = find(v, name);
        if (!t) continue;
        const bool zero = (t->is_string() && (t->get<std::string>() == "0" || t->get<std::string>().empty())) ||
                          (t->is_number() && t->get<double>() == 0.0);
        if (!zero)
            fail(member("renderer", name),
                 fmt::format("only \"0\" (none) is supported in the scene; give the limit on the command line "
                             "with {}", std::string(name) == "timeout" ? "--time SECONDS" : "--checkpoint-every SECONDS"));
    }
    // Tungsten's adaptive sampling gives noisy pixels more samples, chosen from those pixels' own
    // samples: a data-dependent sample count biases a pixel's mean (heavy-tailed corrections most),
    // which an unbiased renderer must not do silently.
    onlyBoolean(v, "renderer", "adaptive_sampling", false,
                "Telescope gives every pixel the same number of samples (sample counts chosen from a pixel's own "
                "samples would bias its mean); --set renderer.adaptive_sampling=false renders the scene without it");
    ignoreUnread(v, "renderer", {"spp", "stratified_sampler", "enable_resume_render", "timeout", "checkpoint_interval",
                                 "adaptive_sampling"});
}

void SceneReader::readTransmittanceEstimator(const json& v, const std::string& key) {
    expectObject(v, key);
    rejectUnknownKeys(v, key, {"type", "level", "pmf", "terms", "points"});
    TransmittanceEstimatorSettings& t = scene_.integrator.transmittance;
    const std::string typeKey = member(key, "type");
    if (!find(v, "type")) fail(typeKey, "missing");
    const std::string type = string(v["type"], typeKey);
    const auto estimator = valueOf(kTransmittanceEstimatorNames, type);
    if (!estimator)
        fail(typeKey, fmt::format("unknown transmittance estimator '{}' (expected {})", type,
                                  expectedNames(kTransmittanceEstimatorNames)));
    t.type = *estimator;
    if (const json* l = find(v, "level")) t.level = integer(*l, member(key, "level"), 0, 16);
    if (const json* n = find(v, "terms")) {
        if (t.type != TransmittanceEstimatorType::Taylor) fail(member(key, "terms"), "only the 'taylor' estimator has terms");
        t.terms = integer(*n, member(key, "terms"), 0, int(shader::kTrTaylorMaxTerms));
    }
    if (const json* n = find(v, "points")) {
        if (t.type != TransmittanceEstimatorType::Taylor) fail(member(key, "points"), "only the 'taylor' estimator has points");
        t.points = integer(*n, member(key, "points"), 0, int(shader::kTrTaylorMaxPoints));
    }
    if (const json* pmf = find(v, "pmf")) {
        if (t.type != TransmittanceEstimatorType::DebiasedRayMarch)
            fail(member(key, "pmf"), "only the 'debiased_ray_march' estimator draws levels from a pmf");
        t.pmf = readPmf(*pmf, member(key, "pmf"), t.pmf, true);
    }
}

}  // namespace scene_reader

}  // namespace telescope
