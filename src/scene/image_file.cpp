// Loads libtelescope_image.so on first use (src/scene/image_file.h says why) and copies its result.
#include "scene/image_file.h"

#include <dlfcn.h>

#include <filesystem>
#include <mutex>
#include <stdexcept>

#include <fmt/format.h>

#ifndef TELESCOPE_IMAGE_PLUGIN_PATH
#define TELESCOPE_IMAGE_PLUGIN_PATH ""
#endif

namespace telescope {

namespace {

struct ImagePlugin {
    TelescopeImageReadFn read = nullptr;
    TelescopeImageFreeFn release = nullptr;
    std::string error;
};

// Next to the executable (an installed telescope), then where the build put it.
const ImagePlugin& plugin() {
    static ImagePlugin p;
    static std::once_flag once;
    std::call_once(once, [] {
        std::vector<std::string> candidates;
        std::error_code ec;
        const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
        if (!ec) candidates.push_back((exe.parent_path() / "libtelescope_image.so").string());
        if (*TELESCOPE_IMAGE_PLUGIN_PATH) candidates.push_back(TELESCOPE_IMAGE_PLUGIN_PATH);
        std::string tried;
        for (const std::string& path : candidates) {
            if (!std::filesystem::exists(path, ec)) {
                tried += (tried.empty() ? "" : ", ") + path;
                continue;
            }
            void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
            if (!handle) {
                const char* why = dlerror();
                p.error = fmt::format("cannot load the image module {}: {}", path, why ? why : "unknown error");
                return;
            }
            p.read = reinterpret_cast<TelescopeImageReadFn>(dlsym(handle, "telescopeImageRead"));
            p.release = reinterpret_cast<TelescopeImageFreeFn>(dlsym(handle, "telescopeImageFree"));
            if (!p.read || !p.release) p.error = fmt::format("the image module {} lacks its entry points", path);
            return;
        }
        p.error = fmt::format("this build of Telescope cannot read images: its OpenImageIO module "
                              "libtelescope_image.so was not found (looked for {})", tried);
    });
    return p;
}

}  // namespace

ImageFileData readImageFile(const std::string& path, uint64_t maxPixels) {
    const ImagePlugin& p = plugin();
    if (!p.read) throw std::runtime_error(p.error);
    const TelescopeImageRequest request{path.c_str(), maxPixels};
    TelescopeImageResult r{};
    if (p.read(&request, &r) != kImageOk) {
        std::string message(r.message);
        p.release(&r);
        throw std::runtime_error(message);
    }
    ImageFileData d;
    d.width = r.width;
    d.height = r.height;
    d.hdr = r.hdr != 0;
    d.rgb.assign(r.rgb, r.rgb + size_t(r.width) * r.height * 3);
    p.release(&r);
    return d;
}

}  // namespace telescope
