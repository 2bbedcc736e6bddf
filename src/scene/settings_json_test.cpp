// The settings as JSON, both ways: what resolvedSettings writes, applySettings reads back into a
// scene whose settings were all different, for every shipped scene and a few patched ones.
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

// A scene whose every recorded setting differs from the shipped scenes' (a photon-mapped box with
// a medium would be rejected, so the photon and media parts are set directly).
Scene allDifferent() {
    Scene s;
    s.integrator.type = IntegratorType::ProgressivePhotonMap;
    s.integrator.minBounces = 7;
    s.integrator.maxBounces = 9;
    s.integrator.enableLightSampling = false;
    s.integrator.enableTwoSidedShading = false;
    s.integrator.debias.estimator = DebiasEstimator::Sum;
    s.integrator.debias.pmf = {PmfType::PowerLaw, 0.1f, 0.3f, 3, 5, "elsewhere"};
    s.integrator.debias.schedule = LevelSchedule::Queued;
    s.integrator.debias.photon = {0.3f, 7, 3};
    s.integrator.debias.testPmfWeight = 2.0f;
    s.integrator.photon = {5, 0.5f, 0.1f, PhotonKernel::Epanechnikov, DirectLighting::Photons};
    s.integrator.transmittance = {TransmittanceEstimatorType::RatioTracking, 9, {PmfType::PowerLaw, 0.1f, 0.2f, 1, 3, "x"}};
    s.camera.width = 3;
    s.camera.height = 5;
    s.camera.fovDegrees = 11.0f;
    s.camera.filter = PixelFilter::Lanczos;
    return s;
}

void expectRoundTrip(const Scene& scene, const std::string& what) {
    const json recorded = resolvedSettings(scene);
    Scene other = allDifferent();
    other.media = scene.media;  // what decides whether the transmittance estimator is recorded
    applySettings(other, recorded, what);
    EXPECT_EQ(resolvedSettings(other), recorded) << what;
    EXPECT_EQ(other.camera.width, scene.camera.width) << what;
    if (scene.integrator.debias.estimator != DebiasEstimator::None) {
        EXPECT_EQ(other.integrator.debias.pmf.origin, scene.integrator.debias.pmf.origin) << what;
    }
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
    expectRoundTrip(loadScene(TELESCOPE_SOURCE_DIR "/scenes/smoke-box.json",
                              {{"integrator.transmittance_estimator", R"({"type":"debiased_ray_march","level":3,
                                                                          "pmf":{"type":"power_law","alpha":0.5}})"}}),
                    "debiased ray marching with a power-law pmf");
}

// The control of the round trip: a key left out of the JSON keeps the other scene's value.
TEST(SettingsJson, AMissingKeyIsNotRestored) {
    const Scene box = loadScene(TELESCOPE_SOURCE_DIR "/scenes/cornell-box.json");
    json recorded = resolvedSettings(box);
    recorded["integrator"].erase("max_bounces");
    Scene other = allDifferent();
    applySettings(other, recorded, "test");
    EXPECT_NE(resolvedSettings(other), resolvedSettings(box));
    EXPECT_EQ(other.integrator.maxBounces, 9u);
}

TEST(SettingsJson, BadSettingsNameTheSource) {
    Scene s;
    try {
        applySettings(s, json::parse(R"({"integrator": {"kernel": "gaussian"}})"), "render.exr");
        FAIL() << "an unknown kernel was accepted";
    } catch (const InputError& e) {
        EXPECT_EQ(e.file(), "render.exr");
        EXPECT_EQ(e.key(), "integrator");
        EXPECT_NE(std::string(e.what()).find("gaussian"), std::string::npos) << e.what();
    }
    EXPECT_THROW(applySettings(s, json::parse(R"({"camera": {"fov": "wide"}})"), "render.exr"), InputError);
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
