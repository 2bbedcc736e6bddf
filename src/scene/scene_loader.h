// Reads a scene in Tungsten's JSON format (see docs/SCENE-FORMAT.md).
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"
#include "scene/scene_overrides.h"

namespace telescope {

// Loads and validates a scene. Throws InputError (file + JSON key path + reason) on any bad
// input: malformed JSON, unknown or unsupported type, wrong value type or range, missing file.
Scene loadScene(const std::string& path, const std::vector<SceneOverride>& overrides = {});

// Same, from JSON text already in memory; baseDir resolves relative mesh paths.
Scene loadSceneFromString(const std::string& text, const std::string& displayName,
                          const std::string& baseDir, const std::vector<SceneOverride>& overrides = {});

// Why an ignored key (Scene::ignoredKeys) is safe to ignore: for Tungsten's output, scheduling
// and display keys, the reason it cannot change the EXR; for a key known to change the image that
// Telescope does not honour yet, a sentence starting "NOT HONOURED"; empty for keys Telescope does
// not know (misspellings, other renderers' keys).
std::string ignoredKeyReason(const std::string& key);

}  // namespace telescope
