// telescope view: the interactive front end. It renders with the same Renderer as `render` and
// shows the film's channels (estimate, base, correction and its parts, standard error) in a GLFW
// window while samples arrive.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "session/options.h"

namespace telescope::viewer {

struct ViewOptions {
    session::ImageOutputOptions output;  // where the save key writes (default: SCENE-view.exr)
    uint32_t seed = session::kDefaultSeed;
    uint64_t spp = 0;          // stop adding samples at this count; 0: never stop
    uint64_t frames = 0;       // scripting: exit after this many frames; 0: until the window closes
    std::string screenshot;    // scripting: PNG of the window as presented last
    std::string keys;          // scripting: input events, "KEY@FRAME,..." (see parseInputScript)
    std::string channel = "estimate";  // the channel shown first
    session::DerivativeOptions derivative;     // --derivative KEY: show the derivative image (docs/DERIVATIVES.md)
};

// A scripted input event: at the start of frame `frame` (1-based), before it renders.
struct ScriptedInput {
    uint64_t frame = 0;
    // A key ("s", "3", "Left", "shift+Left"); drag:DX:DY, pan:DX:DY (mouse drags in pixels),
    // scroll:N; resize:W:H (the window); "shot" (a screenshot now, to SHOT-FRAME.png for --screenshot SHOT.png);
    // "interrupt" (raises SIGINT, as Ctrl-C does).
    std::string token;
};

// Parses --keys; throws InputError naming --keys on a malformed entry or an unknown key.
std::vector<ScriptedInput> parseInputScript(const std::string& text);

// Index (shader::kView*) of a channel name, or -1.
int channelFromName(const std::string& name);
const char* channelName(uint32_t channel);

// Returns the exit code: 0 after the window closed, the frames ran out or SIGINT/SIGTERM arrived.
int runView(const session::CommonOptions& common, const ViewOptions& options);

}  // namespace telescope::viewer
