// "media" and every medium reference (docs/MEDIA.md): homogeneous, exponential and voxel media,
// their phase functions, Tungsten's transmittance models and the density grids. A new medium is
// read here (and added to MediumType, scene.h).
#include "scene/scene_reader.h"

#include "scene/enum_names.h"

#include <array>

#include <glm/gtc/matrix_transform.hpp>

#include "scene/density_grid.h"
#include "scene/transform.h"
#include "scene/vdb_file.h"
#include "shared/transmittance.h"
#include "shared/transmittance_estimators.h"

namespace telescope::scene_reader {

namespace {

// ---- Tungsten's transmittance models: names, shader types (shared/transmittance.h), parameters ----
struct TransmittanceParam {
    const char* key = nullptr;  // Tungsten's name; params[i] of the model
    float fallback = 0.0f;
    bool positive = false;
};

struct TransmittanceModelSpec {
    const char* name;
    uint32_t type;
    std::array<TransmittanceParam, 3> params;
};

// "interpolated" mixes two of these (not another interpolated one).
const TransmittanceModelSpec kTransmittanceModels[] = {
    {"exponential", shader::kTrExponential, {}},
    {"linear", shader::kTrLinear, {{{"max_t", 1.0f, true}}}},
    {"quadratic", shader::kTrQuadratic, {{{"max_t", 0.75f, true}}}},
    {"double_exponential", shader::kTrDoubleExponential, {{{"sigma_a", 0.5f, true}, {"sigma_b", 10.0f, true}}}},
    {"erlang", shader::kTrErlang, {{{"rate", 5.0f, true}}}},
    {"davis", shader::kTrDavis, {{{"alpha", 1.1f, true}}}},
    {"davis_weinstein", shader::kTrDavisWeinstein, {{{"h", 0.75f, true}, {"c", 1.0f, true}}}},
    // params.z: "num_pulses", an integer (4 by default)
    {"pulse", shader::kTrPulse, {{{"min", 0.0f, false}, {"max", 1.0f, false}, {nullptr, 4.0f, false}}}},
};

const TransmittanceModelSpec* findTransmittanceModel(const std::string& name) {
    for (const TransmittanceModelSpec& s : kTransmittanceModels)
        if (name == s.name) return &s;
    return nullptr;
}

// A model with every parameter at its default.
TransmittanceModel defaultTransmittanceModel(const std::string& name) {
    const TransmittanceModelSpec& spec = *findTransmittanceModel(name);
    TransmittanceModel t;
    t.name = spec.name;
    t.type = spec.type;
    for (size_t i = 0; i < spec.params.size(); ++i) t.params[int(i)] = spec.params[i].fallback;
    t.typeA = t.typeB = t.type;
    t.paramsB = t.params;
    return t;
}

}  // namespace

void SceneReader::readMedia(const json& list) {
    for (size_t i = 0; i < list.size(); ++i) {
        const std::string key = element("media", i);
        Medium m = readMedium(list[i], key);
        if (!m.name.empty()) mediumByName_.emplace(m.name, int32_t(scene_.media.size()));
        scene_.media.push_back(std::move(m));
    }
}

// A medium reference: a name from the media list or an inline medium object.
int32_t SceneReader::mediumRef(const json& ref, const std::string& key) {
    if (ref.is_string()) {
        const auto it = mediumByName_.find(ref.get<std::string>());
        if (it == mediumByName_.end()) fail(key, fmt::format("unknown medium '{}'", ref.get<std::string>()));
        return it->second;
    }
    if (ref.is_object()) {
        scene_.media.push_back(readMedium(ref, key));
        return int32_t(scene_.media.size() - 1);
    }
    fail(key, "expected a medium name or an inline medium object, got " + quote(ref));
}

Medium SceneReader::readMedium(const json& v, const std::string& key) {
    const std::string type = requiredType(v, key);
    const std::string typeKey = member(key, "type");
    Medium m;
    if (type == "homogeneous") m.type = MediumType::Homogeneous;
    else if (type == "exponential") m.type = MediumType::Exponential;
    else if (type == "voxel") m.type = MediumType::Grid;
    else if (type == "atmosphere") fail(typeKey, "unsupported medium type 'atmosphere'");
    else fail(typeKey, fmt::format("unknown medium type '{}' (expected \"homogeneous\", \"exponential\" or \"voxel\")", type));

    if (const json* name = find(v, "name")) m.name = string(*name, member(key, "name"));
    auto nonNegative = [&](const char* field, glm::vec3 fallback) {
        const json* f = find(v, field);
        if (!f) return fallback;
        glm::vec3 c = vec3(*f, member(key, field));
        if (c.x < 0.0f || c.y < 0.0f || c.z < 0.0f) fail(member(key, field), "must be non-negative");
        return c;
    };
    m.sigmaA = nonNegative("sigma_a", glm::vec3(0.0f));
    m.sigmaS = nonNegative("sigma_s", glm::vec3(0.0f));
    if (const json* d = find(v, "density")) {
        m.density = number(*d, member(key, "density"));
        if (m.density < 0.0f) fail(member(key, "density"), "must be non-negative");
    }
    std::vector<std::string_view> read = {"name", "type", "sigma_a", "sigma_s", "density", "phase_function", "transmittance",
                                          "max_bounces"};
    // Tungsten's per-medium limit (HomogeneousMedium::sampleDistance): a path ends when it would
    // take a free flight after more than max_bounces scattering events in a row in media (the
    // count restarts at every surface, forward boundaries included).
    if (const json* b = find(v, "max_bounces")) m.maxBounces = integer(*b, member(key, "max_bounces"), 0, 1u << 20);

    if (m.type == MediumType::Exponential) {
        if (const json* f = find(v, "falloff_scale")) {
            m.falloffScale = number(*f, member(key, "falloff_scale"));
            if (m.falloffScale < 0.0f) fail(member(key, "falloff_scale"), "must be non-negative");
        }
        if (const json* f = find(v, "unit_point")) m.unitPoint = vec3(*f, member(key, "unit_point"));
        if (const json* f = find(v, "falloff_direction")) {
            glm::vec3 d = vec3(*f, member(key, "falloff_direction"));
            if (isDegenerate(d)) fail(member(key, "falloff_direction"), "the direction has zero length");
            m.falloffDirection = glm::normalize(d);
        }
        read.insert(read.end(), {"falloff_scale", "unit_point", "falloff_direction"});
    }
    if (m.type == MediumType::Grid) {
        const json* grid = find(v, "grid");
        if (!grid) fail(key, "missing 'grid' (a voxel medium needs a grid)");
        m.grid = readGrid(*grid, member(key, "grid"));
        read.push_back("grid");
        // Every grid shares one storage buffer (lavapipe binds at most 128 MiB).
        uint64_t floats = 0;
        for (const Medium& other : scene_.media) floats += gridFloats(other.grid);
        if (floats + gridFloats(m.grid) > kMaxGridFloats)
            fail(member(key, "grid"), fmt::format("the scene's grids take {} MiB, more than the {} MiB the device binds",
                                                  (floats + gridFloats(m.grid)) * 4 >> 20, kMaxGridFloats * 4 >> 20));
    }

    if (const json* phase = find(v, "phase_function")) {
        const std::string pk = member(key, "phase_function");
        expectObject(*phase, pk);
        const std::string ptype = typeOr(*phase, pk, "isotropic");
        if (ptype == "isotropic") {
            m.phase = PhaseFunction::Isotropic;
            ignoreUnread(*phase, pk, {"type"});
        } else if (ptype == "henyey_greenstein") {
            m.phase = PhaseFunction::HenyeyGreenstein;
            if (const json* g = find(*phase, "g")) m.phaseG = number(*g, member(pk, "g"));
            if (!(m.phaseG > -1.0f && m.phaseG < 1.0f)) fail(member(pk, "g"), "must be in (-1, 1)");
            ignoreUnread(*phase, pk, {"type", "g"});
        } else if (ptype == "rayleigh") {
            fail(member(pk, "type"), "unsupported phase function 'rayleigh'");
        } else {
            fail(member(pk, "type"), fmt::format("unknown phase function '{}'", ptype));
        }
    }
    if (const json* t = find(v, "transmittance")) m.transmittance = readTransmittance(*t, member(key, "transmittance"), false);
    ignoreUnread(v, key, read);
    return m;
}

// Tungsten's transmittance models with its parameter names and defaults.
TransmittanceModel SceneReader::readTransmittance(const json& v, const std::string& key, bool nested) {
    expectObject(v, key);
    const std::string type = typeOr(v, key, "exponential");
    if (type == "interpolated") {
        if (nested) fail(member(key, "type"), "an interpolated transmittance cannot nest another interpolated one");
        const TransmittanceModel a = find(v, "tr_a") ? readTransmittance(v["tr_a"], member(key, "tr_a"), true)
                                                     : defaultTransmittanceModel("linear");
        const TransmittanceModel b = find(v, "tr_b") ? readTransmittance(v["tr_b"], member(key, "tr_b"), true)
                                                     : defaultTransmittanceModel("erlang");
        TransmittanceModel t;
        t.name = type;
        t.type = shader::kTrInterpolated;
        t.typeA = a.type;
        t.params = a.params;
        t.typeB = b.type;
        t.paramsB = b.params;
        t.ratio = find(v, "ratio") ? number(v["ratio"], member(key, "ratio")) : 0.5f;
        if (t.ratio < 0.0f || t.ratio > 1.0f) fail(member(key, "ratio"), "must be in [0, 1]");
        ignoreUnread(v, key, {"type", "tr_a", "tr_b", "ratio"});
        return t;
    }
    const TransmittanceModelSpec* spec = findTransmittanceModel(type);
    if (!spec) fail(member(key, "type"), fmt::format("unknown transmittance type '{}'", type));

    TransmittanceModel t = defaultTransmittanceModel(type);
    std::vector<std::string_view> read = {"type"};
    for (size_t i = 0; i < spec->params.size() && spec->params[i].key; ++i) {
        const TransmittanceParam& p = spec->params[i];
        read.push_back(p.key);
        const json* f = find(v, p.key);
        if (!f) continue;
        t.params[int(i)] = number(*f, member(key, p.key));
        if (p.positive && !(t.params[int(i)] > 0.0f)) fail(member(key, p.key), "must be positive");
    }
    if (t.type == shader::kTrDavisWeinstein && (t.params.x < 0.5f || t.params.x > 1.0f))
        fail(member(key, "h"), "must be in [0.5, 1]");
    if (t.type == shader::kTrPulse) {
        if (!(t.params.y > t.params.x)) fail(member(key, "max"), "must be larger than min");
        if (const json* n = find(v, "num_pulses")) t.params.z = float(integer(*n, member(key, "num_pulses"), 1, 1024));
        read.push_back("num_pulses");
    }
    ignoreUnread(v, key, read);
    t.typeA = t.typeB = t.type;
    t.paramsB = t.params;
    return t;
}

// A grid: {"type": "procedural_cloud" | "constant" | "linear" | "vdb", "transform", ...}.
DensityGrid SceneReader::readGrid(const json& v, const std::string& key) {
    expectObject(v, key);
    const std::string type = typeOr(v, key, "");
    if (type == "vdb") return readVdbGrid(v, key);
    if (type != "procedural_cloud" && type != "constant" && type != "linear")
        fail(member(key, "type"),
             fmt::format("unknown grid type '{}' (expected \"procedural_cloud\", \"constant\", \"linear\" or \"vdb\")", type));
    glm::uvec3 res(32);
    if (const json* r = find(v, "resolution")) {
        const std::string rk = member(key, "resolution");
        if (r->is_array()) {
            if (r->size() != 3) fail(rk, fmt::format("expected [x, y, z], got {} elements", r->size()));
            for (int i = 0; i < 3; ++i) res[i] = integer((*r)[i], element(rk, i), 1, 512);
        } else {
            res = glm::uvec3(integer(*r, rk, 1, 512));
        }
    }
    DensityGrid g;
    if (type == "linear") {
        auto value = [&](const char* field) {
            const float x = find(v, field) ? number(v[field], member(key, field)) : 1.0f;
            if (x < 0.0f) fail(member(key, field), "must be non-negative");
            return x;
        };
        g = linearGrid(res, value("from"), value("to"));
        rejectUnknownKeys(v, key, {"type", "resolution", "transform", "from", "to", "majorant_cell"});
    } else if (type == "constant") {
        const float value = find(v, "value") ? number(v["value"], member(key, "value")) : 1.0f;
        if (value < 0.0f) fail(member(key, "value"), "must be non-negative");
        g = constantGrid(res, value);
        rejectUnknownKeys(v, key, {"type", "resolution", "transform", "value", "majorant_cell"});
    } else {
        ProceduralCloudSettings c;
        c.resolution = res;
        if (const json* f = find(v, "seed")) c.seed = integer(*f, member(key, "seed"), 0, 0x7fffffff);
        if (const json* f = find(v, "frequency")) c.frequency = number(*f, member(key, "frequency"));
        if (const json* f = find(v, "coverage")) c.coverage = number(*f, member(key, "coverage"));
        if (!(c.frequency > 0.0f)) fail(member(key, "frequency"), "must be positive");
        g = proceduralCloud(c);
        rejectUnknownKeys(v, key, {"type", "resolution", "transform", "seed", "frequency", "coverage", "majorant_cell"});
    }
    // The grid fills the unit cube [-0.5, 0.5]^3 placed by the transform.
    const glm::mat4 m = find(v, "transform") ? transform(v["transform"], member(key, "transform")) : glm::mat4(1.0f);
    g.unitToWorld = m * glm::translate(glm::mat4(1.0f), glm::vec3(-0.5f));
    readGridCommon(v, key, g);
    return g;
}

// The keys every grid has: the majorant cell, and a placement that is not degenerate.
void SceneReader::readGridCommon(const json& v, const std::string& key, DensityGrid& g) {
    if (const json* f = find(v, "majorant_cell")) g.majorantCell = integer(*f, member(key, "majorant_cell"), 0, 512);
    const float det = glm::determinant(glm::mat3(g.unitToWorld));
    if (!(std::abs(det) > 1e-30f) || !std::isfinite(det))
        fail(member(key, "transform"), "the grid box has zero size (the transform is singular)");
}

// Tungsten's "vdb" grid (src/core/grids/VdbGrid.cpp): a float density grid and an optional vec3
// emission grid from an OpenVDB file, read through libtelescope_vdb.so (scene/vdb_file.h).
DensityGrid SceneReader::readVdbGrid(const json& v, const std::string& key) {
    const json* fileValue = find(v, "file");
    if (!fileValue) fail(key, "missing 'file' (a vdb grid needs a .vdb file)");
    const std::string fileKey = member(key, "file");
    const fs::path relative = string(*fileValue, fileKey);
    const std::string path = (relative.is_absolute() ? relative : baseDir_ / relative).string();

    std::string densityName = "density", densityKey = member(key, "density_name");
    if (const json* f = find(v, "grid_name")) {  // Tungsten's older name of density_name
        densityName = string(*f, member(key, "grid_name"));
        densityKey = member(key, "grid_name");
    }
    if (const json* f = find(v, "density_name")) densityName = string(*f, member(key, "density_name"));
    const json* emissionValue = find(v, "emission_name");
    const std::string emissionName = emissionValue ? string(*emissionValue, member(key, "emission_name")) : "Cd";
    auto scalar = [&](const char* field, float fallback) {
        const float x = find(v, field) ? number(v[field], member(key, field)) : fallback;
        if (x < 0.0f) fail(member(key, field), "must be non-negative");
        return x;
    };
    const float densityScale = scalar("density_scale", 1.0f);
    const float emissionScale = scalar("emission_scale", 1.0f);
    DensityGrid g;
    g.source = "vdb";
    g.emissionByDensity = find(v, "scale_emission_by_density")
                              ? boolean(v["scale_emission_by_density"], member(key, "scale_emission_by_density"))
                              : true;
    const bool normalizeSize = find(v, "normalize_size") ? boolean(v["normalize_size"], member(key, "normalize_size")) : true;

    // Tungsten's methods choose how the density between voxels is read; Telescope's transmittance
    // estimator (integrator.transmittance_estimator) decides how it is integrated and sampled.
    auto method = [&](const char* field, std::initializer_list<const char*> names) {
        const std::string name = find(v, field) ? string(v[field], member(key, field)) : "exact_nearest";
        bool known = false;
        for (const char* n : names) known = known || name == n;
        if (!known) {
            std::string list;
            for (const char* n : names) list += fmt::format("{}\"{}\"", list.empty() ? "" : ", ", n);
            fail(member(key, field), fmt::format("unknown method '{}' (expected {})", name, list));
        }
        return name;
    };
    const std::string integration =
        method("integration_method", {"exact_nearest", "exact_linear", "raymarching", "residual_ratio"});
    const std::string sampling = method("sampling_method", {"exact_nearest", "exact_linear", "raymarching"});
    g.nearest = integration == "exact_nearest";
    if ((sampling == "exact_nearest") != g.nearest)
        fail(member(key, "sampling_method"),
             fmt::format("'{}' reads the density {} but integration_method '{}' reads it {}: Telescope integrates "
                         "and samples one density field (choose both exact_nearest, or both trilinear)",
                         sampling, sampling == "exact_nearest" ? "per nearest voxel" : "trilinearly", integration,
                         g.nearest ? "per nearest voxel" : "trilinearly"));
    for (const char* k : {"step_size", "supergrid_subsample"})
        if (find(v, k)) ignore(member(key, k));

    // Trilinear lookups read one voxel beyond the active box: one layer of zeros around it.
    TelescopeVdbRequest request{};
    request.path = path.c_str();
    request.densityName = densityName.c_str();
    request.emissionName = emissionName.c_str();
    request.emissionRequired = emissionValue ? 1 : 0;
    request.padding = g.nearest ? 0 : 1;
    request.maxVoxels = kMaxGridFloats;
    int32_t status = kVdbOk;
    VdbFileData d;
    try {
        d = readVdbFile(request, status);
    } catch (const std::exception& e) {
        const std::string where = status == kVdbNoDensityGrid || status == kVdbDensityNotFloat || status == kVdbEmpty
                                      ? densityKey
                                  : status == kVdbNoEmissionGrid || status == kVdbEmissionNotVec3
                                      ? member(key, "emission_name")
                                      : fileKey;
        fail(where, e.what());
    }
    g.resolution = d.res;
    g.density = std::move(d.density);
    for (float& x : g.density) x *= densityScale;
    g.emission = std::move(d.emission);
    for (float& x : g.emission) x *= emissionScale;

    // Index space -> Tungsten's grid space (normalize_size: the active box scaled to a largest side
    // of 1, centred on x and z, standing on y = 0; else the file's own voxel size and origin).
    const glm::dvec3 diag = glm::dvec3(d.activeMax - d.activeMin + 1);
    double scale;
    glm::dvec3 offset;
    if (normalizeSize) {
        scale = 1.0 / std::max(diag.x, std::max(diag.y, diag.z));
        offset = -(glm::dvec3(d.activeMin) * scale + glm::dvec3(diag.x, 0.0, diag.z) * (0.5 * scale));
    } else {
        scale = std::min(d.voxelSize.x, std::min(d.voxelSize.y, d.voxelSize.z));
        offset = d.indexOrigin;
    }
    // Unit box -> index space: voxel i's centre (i + 1/2) / res is index lo + i.
    const glm::dvec3 indexMin = glm::dvec3(d.lo) - 0.5, indexSize = glm::dvec3(d.res);
    glm::mat4 unitToLocal(1.0f);
    for (int a = 0; a < 3; ++a) {
        unitToLocal[a][a] = float(indexSize[a] * scale);
        unitToLocal[3][a] = float(indexMin[a] * scale + offset[a]);
    }
    const glm::mat4 config = find(v, "transform") ? transform(v["transform"], member(key, "transform")) : glm::mat4(1.0f);
    g.unitToWorld = config * unitToLocal;
    readGridCommon(v, key, g);
    rejectUnknownKeys(v, key,
                      {"type", "file", "grid_name", "density_name", "density_scale", "emission_name", "emission_scale",
                       "scale_emission_by_density", "normalize_size", "integration_method", "sampling_method",
                       "step_size", "supergrid_subsample", "transform", "majorant_cell"});
    return g;
}

// The trackers and unbiased ray marching estimate exp(-tau) only.
void SceneReader::checkEstimatorFitsMedia(const json& doc) const {
    if (usesPhotons(scene_.integrator) && !scene_.media.empty())
        fail("media", fmt::format("the '{}' integrator does not support participating media (use path_tracer)",
                                  nameOf(kIntegratorTypeNames, scene_.integrator.type)));
    const TransmittanceEstimatorType t = scene_.integrator.transmittance.type;
    if (t == TransmittanceEstimatorType::RayMarch || t == TransmittanceEstimatorType::DebiasedRayMarch) return;
    const std::string key = find(doc, "integrator") ? "integrator.transmittance_estimator.type" : "media";
    for (size_t i = 0; i < scene_.media.size(); ++i) {
        const TransmittanceModel& m = scene_.media[i].transmittance;
        const std::string where = scene_.media[i].name.empty() ? fmt::format("medium {}", i)
                                                                 : fmt::format("medium '{}'", scene_.media[i].name);
        if (t == TransmittanceEstimatorType::Taylor) {
            // A power series in the optical depth around the pivot (shared/transmittance_estimators.h).
            const bool fits = m.type == shader::kTrInterpolated
                                  ? shader::trTaylorSimpleSupported(m.typeA) && shader::trTaylorSimpleSupported(m.typeB)
                                  : shader::trTaylorSimpleSupported(m.type);
            if (!fits)
                fail(key, fmt::format("taylor needs a transmittance that is a power series in the optical depth "
                                      "(exponential, double_exponential, erlang, davis, or an interpolation of them), "
                                      "but {} has the '{}' transmittance (linear, quadratic and pulse have kinks or "
                                      "steps, davis_weinstein a branch point at zero depth; use debiased_ray_march)",
                                      where, m.name));
        } else if (estimatesExponentialOnly(t) && !m.exponential()) {
            fail(key, fmt::format("{} works for exponential media only, but {} has the '{}' transmittance "
                                  "(use ray_march, debiased_ray_march or taylor)",
                                  transmittanceEstimatorName(t), where, m.name));
        }
    }
}

}  // namespace telescope::scene_reader
