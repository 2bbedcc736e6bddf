// Reads a scene in Tungsten's JSON format (see docs/SCENE-FORMAT.md).
#pragma once

#include <string>
#include <vector>

#include "scene/scene.h"

namespace telescope {

// One "--set key.path=value" override, applied to the JSON before it is interpreted.
// key uses dots and [i] indices ("camera.resolution", "primitives[2].bsdf"); value is JSON
// text, or a bare string when it does not parse as JSON.
struct SceneOverride {
    std::string key;
    std::string value;
};

// Parses "key=value". Throws InputError naming the command line.
SceneOverride parseOverride(const std::string& text);

// Loads and validates a scene. Throws InputError (file + JSON key path + reason) on any bad
// input: malformed JSON, unknown or unsupported type, wrong value type or range, missing file.
Scene loadScene(const std::string& path, const std::vector<SceneOverride>& overrides = {});

// Same, from JSON text already in memory; baseDir resolves relative mesh paths.
Scene loadSceneFromString(const std::string& text, const std::string& displayName,
                          const std::string& baseDir, const std::vector<SceneOverride>& overrides = {});

}  // namespace telescope
