// The session layer between the front ends (src/cli, src/viewer) and the renderer: the scene
// loaded with its --set overrides, the Vulkan context options, output path checks, and the EXR
// (with its metadata), PNG and checkpoint a render writes. Nothing here parses a command line.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gpu/context.h"
#include "render/film.h"
#include "render/derivative.h"
#include "render/resolved_scene.h"
#include "render/film_io.h"
#include "scene/scene.h"
#include "scene/scene_overrides.h"
#include "session/options.h"

namespace telescope::session {

// The first key where two JSON documents differ, as a key path ("integrator.max_bounces"; "" when
// they are equal or unreadable): for errors that name the key.
std::string firstDifference(const std::string& a, const std::string& b);

// "block N in progress (level k, d of t photon passes)": how every message names a photon block
// that a checkpoint keeps (Film::pending, CheckpointHeader's pending fields).
std::string pendingBlockText(uint64_t block, uint32_t level, uint32_t done, uint32_t total);

// The scene file with the --set overrides applied, then `more` (a converge method's; throws
// InputError naming the file and key).
Scene loadWithOverrides(const CommonOptions& o, const std::vector<SceneOverride>& more = {});
// Resuming checkpoint `c` (at `path`) of a scene with a pmf "auto": each such pmf becomes the one
// the checkpoint's own pilot chose (its recorded settings, read by the scene file's reader), so the
// resumed samples draw their levels as the first ones did and no pilot runs again. A scene without
// "auto" is left as it is. InputError naming the key when the checkpoint records no settings
// (version 1) or recorded "auto" itself.
void takeRecordedPmfs(Scene& scene, const Checkpoint& c, const std::string& path);
// The scene with every pmf "auto" resolved by its pilot (render/pmf_pilot.h; seeded from the
// render's seed), each pilot's summary printed to stderr unless quiet: what render, reference,
// plan and view build their renderers from.
ResolvedScene resolve(gpu::Context& context, Scene scene, uint32_t seed, bool quiet);
void reportIgnoredKeys(const Scene& scene, bool quiet);
// --derivative and its options as settings; throws InputError naming the option.
DerivativeSettings derivativeSettings(const DerivativeOptions& d);
// A derivative render's EXR metadata beyond OutputInfo's (the parameter, its value, h_0).
std::vector<std::pair<std::string, std::string>> derivativeMetadata(const DerivativeRenderer& r);
// The settings a derivative render runs with, as its outputs record them (OutputInfo::settings):
// resolvedSettings(scene) plus a "derivative" object (key, value, h_0, estimator, levels, and the
// level pmf as run, p(j) for each level: the pilot's table where pmf "auto" chose it). Resuming
// compares these; a shard merge compares the scene's part with its plan.
std::string derivativeSettingsAsRun(const Scene& scene, const DerivativeRenderer& r);
// Recorded settings (OutputInfo::settings) split into the scene's part (resolvedSettings) and the
// "derivative" object (null for a radiance render, and for settings that are not a JSON object).
struct SettingsParts {
    std::string scene;
    nlohmann::json derivative;
};
SettingsParts splitDerivativeSettings(const std::string& settings);
gpu::ContextOptions contextOptions(const CommonOptions& o);

// Throw InputError naming the option when a path has the wrong extension or no directory.
void checkOutputPath(const std::string& path, const char* option, const char* extension);
void checkImageOutputs(ImageOutputOptions& o);  // fills in the default PNG path

// Throws when the validation layer reported anything.
void checkValidation(const gpu::Context& context);

struct OutputInfo {
    std::string sceneFile, sceneDocument, estimator, device;
    std::string settings;  // resolvedSettings(): the settings as run (defaults filled, auto resolved)
    uint32_t seed = 0;
    double seconds = 0.0;
    std::vector<uint32_t> seeds;  // a merge: every shard's seed (empty: {seed})
    std::string shards;           // a merge: JSON list of the merged checkpoints (telescope:shards)
    std::vector<std::pair<std::string, std::string>> extra;  // more metadata (a derivative's parameter)
};

// The checkpoint of a film rendered as `info` says.
Checkpoint checkpointOf(const Film& film, const OutputInfo& info);

// The EXR (estimate, base, correction and its parts, variance; metadata: scene, seed, spp,
// device, timings), the PNG preview and the checkpoint, as `telescope render` writes them.
void writeImages(const ImageOutputOptions& o, const Film& film, const OutputInfo& info);

}  // namespace telescope::session
