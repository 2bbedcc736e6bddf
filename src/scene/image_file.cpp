// Loads libtelescope_image.so on first use (src/scene/image_file.h says why) and copies its result.
#include "scene/image_file.h"

#include <mutex>
#include <stdexcept>

#include <fmt/format.h>

#include "scene/plugin_loader.h"

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

const ImagePlugin& plugin() {
    static ImagePlugin p;
    static std::once_flag once;
    std::call_once(once, [] {
        const PluginHandle h = openPlugin(
            {"libtelescope_image.so", TELESCOPE_IMAGE_PLUGIN_PATH, "the image module", "read image files", "OpenImageIO"});
        if (!h.handle) {
            p.error = h.error;
            return;
        }
        p.read = pluginSymbol<TelescopeImageReadFn>(h, "telescopeImageRead");
        p.release = pluginSymbol<TelescopeImageFreeFn>(h, "telescopeImageFree");
        if (!p.read || !p.release) p.error = fmt::format("the image module {} lacks its entry points", h.path);
    });
    return p;
}

}  // namespace

ImageFileData readImageFile(const std::string& path, uint64_t maxPixels, int32_t& status) {
    const ImagePlugin& p = plugin();
    if (!p.read) {
        status = kImageCannotOpen;
        throw std::runtime_error(p.error);
    }
    TelescopeImageResult r{};
    status = p.read(path.c_str(), maxPixels, &r);
    if (status != kImageOk) {
        std::string message(r.message);
        p.release(&r);
        throw std::runtime_error(message);
    }
    ImageFileData d;
    d.width = uint32_t(r.width);
    d.height = uint32_t(r.height);
    d.channels = uint32_t(r.channels);
    d.floatingPoint = r.floatingPoint != 0;
    d.pixels.assign(r.pixels, r.pixels + size_t(d.width) * d.height * d.channels);
    p.release(&r);
    return d;
}

}  // namespace telescope
