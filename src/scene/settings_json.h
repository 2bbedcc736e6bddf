// The settings of a render as JSON: every default filled in, an "auto" pmf replaced by the pmf its
// pilot chose, and the reason for each pmf. The EXR metadata ("telescope:settings"), --stats-json
// ("settings") and the viewer's screenshots record this next to the scene as given, and a render
// is reproduced from the two (reproduceScene): the settings win over the document wherever they
// differ (a pilot's pmf, a typed patch such as `reference`'s).
//
// The keys are the scene file's (docs/SCENE-FORMAT.md, "origin" in each pmf included); photon
// mapping's settings and block parameters sit in "integrator" and "integrator.debias" as in the
// file. There is one reader of them, the scene file's (scene/settings_reader.cpp): reproduceScene
// puts the recorded settings into the document and loads it, so a recorded value is checked
// exactly as the same value in a scene file.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "scene/scene.h"

namespace telescope {

void to_json(nlohmann::json& j, const PmfSettings& p);
void to_json(nlohmann::json& j, const DebiasSettings& d);  // null when there is no debiasing
void to_json(nlohmann::json& j, const TransmittanceEstimatorSettings& t);
void to_json(nlohmann::json& j, const PhotonSettings& p);
// The photon and transmittance parts are written only where the integrator uses them (photon
// mapping; a scene with media: withTransmittance).
nlohmann::json integratorJson(const IntegratorSettings& s, bool withTransmittance);

// The integrator and camera settings of a scene (resolved: every pmf as run, render/resolved_scene.h).
nlohmann::json resolvedSettings(const Scene& scene);

// The scene of a render, from what its outputs record: the scene document (after overrides), the
// file it came from (relative mesh paths) and the resolved settings, which replace the document's
// integrator and the camera keys they name. Bad settings are bad input: InputError naming
// sceneFile and the key (integrator.kernel), as the scene file's reader words it.
Scene reproduceScene(const std::string& sceneDocument, const std::string& sceneFile, const std::string& settings);

}  // namespace telescope
