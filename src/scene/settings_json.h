// The settings a render actually ran with, as JSON: every default filled in, an "auto" pmf
// replaced by the pmf its pilot chose, and the reason for each pmf. The EXR metadata
// ("telescope:settings") and --stats-json ("settings") record this, next to the scene as given.
#pragma once

#include <nlohmann/json.hpp>

#include "scene/scene.h"

namespace telescope {

void to_json(nlohmann::json& j, const PmfSettings& p);
void to_json(nlohmann::json& j, const DebiasSettings& d);
void to_json(nlohmann::json& j, const TransmittanceEstimatorSettings& t);
void to_json(nlohmann::json& j, const PhotonSettings& p);

// The integrator and camera settings of a loaded scene (after resolveAutoPmf, if it ran).
nlohmann::json resolvedSettings(const Scene& scene);

}  // namespace telescope
