// Tungsten scene loader: parse, apply --set overrides (scene_overrides.h), then interpret with
// Tungsten's conventions into the world-space model of scene.h (scene_reader.h and its parts).
#include "scene/scene_loader.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "core/error.h"
#include "scene/scene_reader.h"

namespace telescope {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

// Line and column (1-based) of a byte offset, for parse errors.
std::pair<size_t, size_t> lineColumn(const std::string& text, size_t byte) {
    byte = std::min(byte, text.size());
    size_t line = 1, column = 1;
    for (size_t i = 0; i < byte; ++i) {
        if (text[i] == '\n') { ++line; column = 1; }
        else ++column;
    }
    return {line, column};
}

}  // namespace

Scene loadSceneFromString(const std::string& text, const std::string& displayName, const std::string& baseDir,
                          const std::vector<SceneOverride>& overrides) {
    Scene scene;
    scene.path = displayName;
    try {
        scene.document = json::parse(text);
    } catch (const json::parse_error& e) {
        // nlohmann's byte is the 1-based index of the last character read
        const auto [line, column] = lineColumn(text, e.byte > 0 ? e.byte - 1 : 0);
        std::string reason = e.what();
        if (const size_t colon = reason.find(": "); colon != std::string::npos) reason = reason.substr(colon + 2);
        throw InputError(displayName, "", fmt::format("invalid JSON at line {}, column {}: {}", line, column, reason));
    } catch (const json::exception& e) {
        // Number overflow and the like carry no position
        std::string reason = e.what();
        if (const size_t bracket = reason.find("] "); bracket != std::string::npos) reason = reason.substr(bracket + 2);
        throw InputError(displayName, "", "invalid JSON: " + reason);
    }
    for (const SceneOverride& o : overrides) applyOverride(scene.document, o, displayName);
    scene_reader::SceneReader(displayName, baseDir, scene).read(scene.document);
    return scene;
}

Scene loadScene(const std::string& path, const std::vector<SceneOverride>& overrides) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", fmt::format("cannot open scene file: {}", std::strerror(errno)));
    std::ostringstream text;
    text << in.rdbuf();
    if (in.bad()) throw InputError(path, "", "cannot read scene file");
    return loadSceneFromString(text.str(), path, fs::path(path).parent_path().string(), overrides);
}

std::string ignoredKeyReason(const std::string& key) {
    static const std::pair<const char*, const char*> kReasons[] = {
        {"renderer.output_file", "an output name: Telescope writes where -o says"},
        {"renderer.hdr_output_file", "an output name: Telescope writes where -o says"},
        {"renderer.resume_render_file", "an output name (resume files are --checkpoint's)"},
        {"renderer.output_directory", "an output name: Telescope writes where -o says"},
        {"renderer.overwrite_output_files", "output handling: Telescope writes a temporary file and renames it"},
        {"renderer.output_buffers", "Tungsten's extra feature images: the EXR holds Telescope's channels"},
        {"renderer.scene_bvh", "an acceleration choice: no pixel depends on it"},
        {"renderer.spp_step", "Tungsten's progressive display step: the image at a given spp does not depend on it"},
        {"camera.tonemap", "the display tone map: the EXR is linear (the PNG preview is clipped sRGB)"},
        {"integrator.volume_photon_count", "volume photons: photon mapping scenes have no media (refused)"},
        {"integrator.volume_gather_radius", "volume photons: photon mapping scenes have no media (refused)"},
        {"integrator.fixed_volume_radius", "volume photons: photon mapping scenes have no media (refused)"},
    };
    for (const auto& [name, why] : kReasons)
        if (key == name) return why;
    return {};
}

}  // namespace telescope
