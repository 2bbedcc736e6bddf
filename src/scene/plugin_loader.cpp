#include "scene/plugin_loader.h"

#include <filesystem>
#include <vector>

#include <fmt/format.h>

namespace telescope {

PluginHandle openPlugin(const PluginSpec& spec) {
    PluginHandle plugin;
    std::vector<std::string> candidates;
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) candidates.push_back((exe.parent_path() / spec.fileName).string());
    if (*spec.buildPath) candidates.push_back(spec.buildPath);
    std::string tried;
    for (const std::string& path : candidates) {
        if (!std::filesystem::exists(path, ec)) {
            tried += (tried.empty() ? "" : ", ") + path;
            continue;
        }
        plugin.path = path;
        plugin.handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
        if (!plugin.handle) {
            const char* why = dlerror();
            plugin.error = fmt::format("cannot load {} {}: {}", spec.moduleName, path, why ? why : "unknown error");
        }
        return plugin;
    }
    plugin.error = fmt::format("this build of Telescope cannot {}: its {} module {} was not found (looked for {})",
                               spec.capability, spec.libraryName, spec.fileName, tried);
    return plugin;
}

}  // namespace telescope
