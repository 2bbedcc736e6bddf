// Named rendering methods for convergence studies: a method is a label and the scene overrides
// that turn a scene's integrator into that estimator. Presets cover the estimators Telescope
// ships; any other method is spelled out as overrides.
#pragma once

#include <string>
#include <vector>

#include "scene/scene_loader.h"

namespace telescope {

struct Method {
    std::string label;
    std::vector<SceneOverride> overrides;
    std::string description;
};

// A preset name, e.g. "biased:1", "single_term:1", "sum:1" (path depth, k = 1), or a custom
// method "LABEL: key=value; key=value" (the same syntax as --set, separated by semicolons).
// Throws InputError naming the command-line option on an unknown preset or a malformed method.
Method parseMethod(const std::string& spec, const std::string& option);

// One line per preset, for --help and error messages.
std::string describePresets();

}  // namespace telescope
