// The options every front end of a render shares (the telescope subcommands in src/cli, the
// viewer in src/viewer): the scene and its overrides, the device, image outputs and derivative
// renders. The session layer (session/outputs.h) turns them into a loaded scene, a device and
// written files.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace telescope::session {

constexpr uint32_t kDefaultSeed = 0xBA5EBA11u;  // Tungsten's default seed

struct CommonOptions {
    std::string scenePath;
    std::vector<std::string> sets;
    int device = -1;
    bool validation = false;
    bool quiet = false;
};

struct ImageOutputOptions {
    std::string exrPath;
    std::string pngPath;  // default: the EXR path with .png
    bool noPng = false;
    std::string checkpointPath;  // written at the end (and during long renders) when not empty
};

// --derivative KEY and its options (render, plan): render/derivative.h.
struct DerivativeOptions {
    std::string key;             // empty: a radiance render
    double step = std::numeric_limits<double>::quiet_NaN();  // --step (NaN: not given, the default)
    std::string estimator = "single_term";
    uint32_t levels = 8;
    std::string pmf;             // JSON text of a pmf ({"type": "geometric", "r": 0.5}); empty: default
};

}  // namespace telescope::session
