// "--set key.path=value": overrides applied to a scene's JSON before it is interpreted.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

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

// The JSON pointer of a key path ("primitives[2].bsdf" -> /primitives/2/bsdf). Throws InputError
// for a malformed path (sceneName only goes into the message).
nlohmann::json::json_pointer overridePointer(const std::string& key, const std::string& sceneName);

// Sets the value at the key path, creating missing object keys on the way (never array
// elements). Throws InputError when the path walks into a value of the wrong kind.
void applyOverride(nlohmann::json& doc, const SceneOverride& o, const std::string& sceneName);

}  // namespace telescope
