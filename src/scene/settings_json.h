// The settings of a render as JSON, both ways: every default filled in, an "auto" pmf replaced by
// the pmf its pilot chose, and the reason for each pmf. The EXR metadata ("telescope:settings"),
// --stats-json ("settings") and the viewer's screenshots record this next to the scene as given,
// and a render is reproduced from the two (reproduceScene): the settings win over the document
// wherever they differ (a pilot's pmf, a typed patch such as `reference`'s).
//
// The keys are the scene file's (docs/SCENE-FORMAT.md) plus "origin" in each pmf; photon mapping's
// settings and block parameters sit in "integrator" and "integrator.debias" as in the file.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "scene/scene.h"

namespace telescope {

void to_json(nlohmann::json& j, const PmfSettings& p);
void from_json(const nlohmann::json& j, PmfSettings& p);
void to_json(nlohmann::json& j, const DebiasSettings& d);  // null when there is no debiasing
void from_json(const nlohmann::json& j, DebiasSettings& d);
void to_json(nlohmann::json& j, const TransmittanceEstimatorSettings& t);
void from_json(const nlohmann::json& j, TransmittanceEstimatorSettings& t);
void to_json(nlohmann::json& j, const PhotonSettings& p);
void from_json(const nlohmann::json& j, PhotonSettings& p);
// The photon and transmittance parts are written only where the integrator uses them (photon
// mapping; a scene with media: withTransmittance).
nlohmann::json integratorJson(const IntegratorSettings& s, bool withTransmittance);
void from_json(const nlohmann::json& j, IntegratorSettings& s);

// The integrator and camera settings of a loaded scene (after resolveAutoPmf, if it ran).
nlohmann::json resolvedSettings(const Scene& scene);

// Sets what resolvedSettings records (integrator; camera resolution, field of view and filter)
// from its JSON; keys that are missing keep their value. Throws InputError naming `source` and the
// key when a value has the wrong type or an unknown name.
void applySettings(Scene& scene, const nlohmann::json& settings, const std::string& source);

// The scene of a render, from what its outputs record: the scene document (after overrides), the
// file it came from (relative mesh paths) and the resolved settings.
Scene reproduceScene(const std::string& sceneDocument, const std::string& sceneFile, const std::string& settings);

}  // namespace telescope
