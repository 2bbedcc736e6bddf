// Fuzz target: the scene loader (Tungsten JSON) and the --set override parser.
//
// Input: the lines before the first NUL byte are --set arguments ("key.path=value", one per
// line); the bytes after it (or the whole input, when it has no NUL) are the scene file. Mesh
// files resolve against scenes/ of the source tree, so corpus entries may name the shipped meshes.
//
// The contract under test: loading returns a scene or throws InputError (exit 2 with one line
// naming the file and the key). Any other exception, a crash, a sanitizer report, a leak or a
// hang is a finding.
//
// Built two ways (fuzz/README.md):
//  - with clang -fsanitize=fuzzer,address,undefined (fuzz/run): libFuzzer drives it;
//  - with the normal compiler (TELESCOPE_FUZZ_REPLAY, part of the normal build): a driver that
//    replays files and directories (the seed corpus, fuzz/regressions/) once each; the suite
//    runs it, so every finding stays a regression test.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "scene/scene_loader.h"
#include "scene/settings_json.h"

namespace {

void loadOne(const uint8_t* data, size_t size) {
    std::string_view in(reinterpret_cast<const char*>(data), size);
    std::string_view sets, scene = in;
    if (size_t nul = in.find('\0'); nul != std::string_view::npos) {
        sets = in.substr(0, nul);
        scene = in.substr(nul + 1);
    }
    try {
        std::vector<telescope::SceneOverride> overrides;
        while (!sets.empty()) {
            size_t nl = sets.find('\n');
            std::string line(sets.substr(0, nl));
            sets = nl == std::string_view::npos ? std::string_view() : sets.substr(nl + 1);
            if (!line.empty()) overrides.push_back(telescope::parseOverride(line));
        }
        telescope::Scene s = telescope::loadSceneFromString(std::string(scene), "fuzz.json",
                                                            TELESCOPE_SOURCE_DIR "/scenes", overrides);
        // The settings every output records: must serialise for any scene that loads.
        (void)telescope::resolvedSettings(s).dump();
    } catch (const telescope::InputError&) {
        // The contract: bad input is an InputError.
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    loadOne(data, size);
    return 0;
}

#ifdef TELESCOPE_FUZZ_REPLAY
// ---- Replay driver: every file given, and every file under the directories given ----
int main(int argc, char** argv) {
    namespace fs = std::filesystem;
    std::vector<fs::path> files;
    for (int i = 1; i < argc; ++i) {
        fs::path p(argv[i]);
        if (fs::is_directory(p)) {
            for (const auto& e : fs::recursive_directory_iterator(p))
                if (e.is_regular_file()) files.push_back(e.path());
        } else if (fs::is_regular_file(p)) {
            files.push_back(p);
        } else {
            std::cerr << p.string() << ": no such file or directory\n";
            return 2;
        }
    }
    int failures = 0;
    for (const auto& f : files) {
        std::ifstream in(f, std::ios::binary);
        std::stringstream ss;
        ss << in.rdbuf();
        const std::string bytes = ss.str();
        try {
            loadOne(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
        } catch (const std::exception& e) {
            std::cerr << f.string() << ": FINDING: an exception other than InputError: " << e.what() << "\n";
            ++failures;
        }
    }
    std::cout << "replayed " << files.size() << " inputs, " << failures << " findings\n";
    return failures == 0 && !files.empty() ? 0 : 1;
}
#endif
