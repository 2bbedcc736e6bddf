// The settings as JSON, both ways: what resolvedSettings writes, reproduceScene puts into a
// document whose settings were all different and reads back with the scene file's reader, for
// every shipped scene and a few patched ones.
#include "scene/settings_json.h"

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.h"
#include "scene/enum_names.h"
#include "scene/scene_loader.h"

namespace telescope {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The scene's document with every recorded setting different: another integrator (another type,
// bounces, switches, estimator, pmf and schedule) and another camera resolution, field of view
// and filter. Only the recorded settings can bring the scene's back.
std::string allDifferent(const Scene& scene) {
    json doc = scene.document;
    doc["integrator"] = json::parse(R"({"type": "path_tracer", "min_bounces": 7, "max_bounces": 9,
        "enable_light_sampling": false, "enable_two_sided_shading": false,
        "debias": {"estimator": "sum", "pmf": {"type": "power_law", "alpha": 0.3, "origin": "elsewhere"},
                   "level_schedule": "queued", "test_pmf_weight": 2.0}})");
    if (!scene.media.empty())
        doc["integrator"]["transmittance_estimator"] = json::parse(R"({"type": "ratio_tracking", "level": 9})");
    doc["camera"]["resolution"] = {3, 5};
    doc["camera"]["fov"] = 11.0;
    doc["camera"]["reconstruction_filter"] = "lanczos";
    return doc.dump();
}

Scene reproduced(const Scene& scene, const json& recorded) {
    return reproduceScene(allDifferent(scene), scene.path, recorded.dump());
}

void expectRoundTrip(const Scene& scene, const std::string& what) {
    const json recorded = resolvedSettings(scene);
    const Scene other = reproduced(scene, recorded);
    EXPECT_EQ(resolvedSettings(other), recorded) << what;
    EXPECT_EQ(other.camera.width, scene.camera.width) << what;
    EXPECT_EQ(other.integrator.debias.pmf.origin, scene.integrator.debias.pmf.origin) << what;
    EXPECT_EQ(other.integrator.transmittance.pmf.origin, scene.integrator.transmittance.pmf.origin) << what;
    // Every recorded key is one the reader uses: none is reported as ignored.
    for (const std::string& key : other.ignoredKeys) EXPECT_NE(key.rfind("integrator", 0), 0u) << what << ": " << key;
}

TEST(SettingsJson, EveryShippedSceneRoundTrips) {
    int scenes = 0;
    // Tungsten example scenes that fail to load by design, each with its one message
    // (scenes/tungsten/README.md; checked by TungstenExampleScenes in scene_loader_test.cpp).
    const std::vector<std::string> failing = {"hair", "voxel-medium", "water-caustic", "volumetric-caustic"};
    for (const auto& entry : fs::recursive_directory_iterator(TELESCOPE_SOURCE_DIR "/scenes")) {
        if (entry.path().extension() != ".json") continue;
        if (std::find(failing.begin(), failing.end(), entry.path().parent_path().filename().string()) != failing.end())
            continue;
        // non-exponential asks for adaptive sampling, refused unless turned off.
        const bool adaptive = entry.path().parent_path().filename() == "non-exponential";
        expectRoundTrip(loadScene(entry.path().string(),
                                  adaptive ? std::vector<SceneOverride>{{"renderer.adaptive_sampling", "false"}}
                                           : std::vector<SceneOverride>{}),
                        entry.path().string());
        ++scenes;
    }
    EXPECT_GE(scenes, 9);
}

TEST(SettingsJson, PatchedSettingsRoundTrip) {
    const std::string box = TELESCOPE_SOURCE_DIR "/scenes/cornell-box.json";
    expectRoundTrip(loadScene(box, {{"integrator.debias", R"({"estimator":"single_term","pmf":{"type":"power_law","alpha":0.4},
                                                              "level_schedule":"queued","test_pmf_weight":1.5})"}}),
                    "power law, queued, test weight");
    expectRoundTrip(loadScene(TELESCOPE_SOURCE_DIR "/scenes/point-plane-photon.json",
                              {{"integrator.kernel", R"("epanechnikov")"}, {"integrator.direct_lighting", R"("photons")"}}),
                    "photon kernel and direct lighting");
    expectRoundTrip(loadScene(TELESCOPE_SOURCE_DIR "/scenes/point-plane-photon.json",
                              {{"integrator.type", R"("progressive_photon_map")"},
                               {"integrator.debias", R"({"estimator":"single_term","pmf":{"type":"geometric","r":0.6},
                                                          "area_ratio":0.6,"photon_growth":2,"level_cap":9})"}}),
                    "unbiased progressive photon mapping's blocks");
    expectRoundTrip(loadScene(TELESCOPE_SOURCE_DIR "/scenes/smoke-box.json",
                              {{"integrator.transmittance_estimator", R"({"type":"debiased_ray_march","level":3,
                                                                          "pmf":{"type":"power_law","alpha":0.5}})"}}),
                    "debiased ray marching with a power-law pmf");
    // A pilot's pmf: what resolveScene puts in the scene, with its reason.
    Scene piloted = loadScene(box, {{"integrator.debias", R"({"estimator":"sum","pmf":{"type":"auto"}})"}});
    piloted.integrator.debias.pmf = {PmfType::Geometric, 0.41f, 0.6f, 4, 8, "chosen by the auto pilot"};
    expectRoundTrip(piloted, "a pilot's pmf");
}

// The control of the round trip: a recorded key left out keeps the other document's value.
TEST(SettingsJson, AMissingKeyIsNotRestored) {
    const Scene box = loadScene(TELESCOPE_SOURCE_DIR "/scenes/cornell-box.json");
    json recorded = resolvedSettings(box);
    recorded["camera"].erase("fov");
    const Scene other = reproduced(box, recorded);
    EXPECT_NE(resolvedSettings(other), resolvedSettings(box));
    EXPECT_EQ(other.camera.fovDegrees, 11.0f);
}

// Recorded settings are read by the scene file's reader: a bad value is refused as in a scene
// file, naming the file and the key.
TEST(SettingsJson, BadSettingsNameTheFileAndKey) {
    const Scene box = loadScene(TELESCOPE_SOURCE_DIR "/scenes/point-plane-photon.json");
    auto refusal = [&](const std::string& settings) -> std::pair<std::string, std::string> {
        try {
            reproduceScene(box.document.dump(), box.path, settings);
        } catch (const InputError& e) {
            EXPECT_EQ(e.file(), box.path);
            return {e.key(), e.what()};
        }
        ADD_FAILURE() << "accepted: " << settings;
        return {};
    };
    json recorded = resolvedSettings(box);
    recorded["integrator"]["kernel"] = "gaussian";
    const auto [kernelKey, kernelWhy] = refusal(recorded.dump());
    EXPECT_EQ(kernelKey, "integrator.kernel");
    EXPECT_NE(kernelWhy.find("gaussian"), std::string::npos) << kernelWhy;
    EXPECT_EQ(refusal(R"({"camera": {"fov": "wide"}})").first, "camera.fov");
    EXPECT_EQ(refusal(R"({"integrator": {"type": "path_tracer", "debias": {"estimator": "sum",
                          "pmf": {"type": "geometric", "origin": 3}}}})").first, "integrator.debias.pmf.origin");
    EXPECT_EQ(refusal("[1, 2]").first, "settings");
}

}  // namespace
}  // namespace telescope

namespace telescope {

// Every enum's names live once (scene/enum_names.h): each table names each value once and reads
// back to it, and the reader's messages list the names from the same table.
TEST(EnumNames, EachTableRoundTripsAndNamesEveryValueOnce) {
    auto check = [](const auto& table, size_t values) {
        EXPECT_EQ(std::size(table), values);
        std::set<std::string> names;
        for (const auto& n : table) {
            EXPECT_TRUE(names.insert(n.name).second) << n.name;
            EXPECT_EQ(valueOf(table, n.name), n.value) << n.name;
            EXPECT_STREQ(nameOf(table, n.value), n.name);
        }
        EXPECT_FALSE(valueOf(table, "no such name").has_value());
    };
    check(kPmfTypeNames, 3);
    check(kDebiasEstimatorNames, 2);  // DebiasEstimator::None is the absence of a debias block
    check(kLevelScheduleNames, 3);
    check(kIntegratorTypeNames, 3);
    check(kPhotonKernelNames, 3);
    check(kDirectLightingNames, 2);
    check(kTransmittanceEstimatorNames, size_t(shader::kTrEstCount));
    check(kPixelFilterNames, 7);
    EXPECT_EQ(expectedNames(kLevelScheduleNames), "\"per_pixel\", \"uniform\" or \"queued\"");
    EXPECT_EQ(expectedNames(kPmfTypeNames, 2), "\"geometric\" or \"power_law\"");
}

}  // namespace telescope
