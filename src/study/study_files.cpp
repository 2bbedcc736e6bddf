#include "study/study_files.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

namespace telescope {

void writeTextAtomically(const std::string& path, const std::string& text) {
    const std::string tmp = path + ".partial";
    {
        std::ofstream f(tmp, std::ios::trunc);
        f << text;
        if (!f.flush()) throw std::runtime_error(fmt::format("{}: write failed", path));
    }
    std::filesystem::rename(tmp, path);
}

}  // namespace telescope
