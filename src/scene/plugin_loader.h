// Optional modules loaded with dlopen on first use (libtelescope_image.so, libtelescope_vdb.so):
// their libraries (OpenImageIO, OpenVDB and what they pull in) would cost every process start
// tenths of a second if linked into telescope (docs/BENCHMARKS.md), and most scenes never use them.
#pragma once

#include <dlfcn.h>

#include <string>

namespace telescope {

struct PluginSpec {
    const char* fileName;     // "libtelescope_image.so"
    const char* buildPath;    // where the build put it (a compile definition), or ""
    const char* moduleName;   // in messages: "the image module"
    const char* capability;   // in messages: "read image files"
    const char* libraryName;  // in messages: "OpenImageIO"
};

struct PluginHandle {
    void* handle = nullptr;  // null on failure
    std::string path;        // the file loaded
    std::string error;       // why it failed
};

// Looks next to the executable (an installed telescope), then at spec.buildPath, and dlopens the
// first file that exists. The handle is never closed: the module lives as long as the process.
PluginHandle openPlugin(const PluginSpec& spec);

template <typename Fn>
Fn pluginSymbol(const PluginHandle& plugin, const char* name) {
    return reinterpret_cast<Fn>(dlsym(plugin.handle, name));
}

}  // namespace telescope
