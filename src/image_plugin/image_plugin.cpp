// libtelescope_image.so: reads images with OpenImageIO for src/scene/image_file.cpp (which loads
// this module with dlopen, so that only scenes with bitmap textures pay for OpenImageIO's
// libraries). C interface: src/scene/image_file.h.
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>

#include "scene/image_file.h"

namespace {

int32_t failWith(TelescopeImageResult* r, int32_t status, const std::string& what) {
    r->status = status;
    std::snprintf(r->message, sizeof(r->message), "%s", what.c_str());
    return status;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) int32_t telescopeImageRead(const char* path, uint64_t maxPixels,
                                                                           TelescopeImageResult* r) {
    std::memset(r, 0, sizeof(*r));
    try {
        auto in = OIIO::ImageInput::open(path);
        if (!in) {
            std::string why = OIIO::geterror();
            while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
            return failWith(r, kImageCannotOpen, "cannot read image '" + std::string(path) + "'" +
                                                     (why.empty() ? std::string() : ": " + why));
        }
        const OIIO::ImageSpec& spec = in->spec();
        if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0 || spec.depth != 1)
            return failWith(r, kImageCannotRead, "image '" + std::string(path) + "' is not a 2D image with pixels");
        const uint64_t pixels = uint64_t(spec.width) * uint64_t(spec.height);
        if (pixels > maxPixels)
            return failWith(r, kImageTooLarge, "image '" + std::string(path) + "' has " + std::to_string(spec.width) +
                                                   "x" + std::to_string(spec.height) + " pixels, more than the " +
                                                   std::to_string(maxPixels) + " a texture binding holds");
        r->width = spec.width;
        r->height = spec.height;
        r->channels = spec.nchannels;
        const OIIO::TypeDesc f = spec.format;
        r->floatingPoint = f.basetype == OIIO::TypeDesc::HALF || f.basetype == OIIO::TypeDesc::FLOAT ||
                           f.basetype == OIIO::TypeDesc::DOUBLE;
        r->pixels = static_cast<float*>(std::malloc(sizeof(float) * pixels * uint64_t(spec.nchannels)));
        if (!r->pixels) return failWith(r, kImageTooLarge, "out of memory reading image '" + std::string(path) + "'");
        if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, r->pixels))
            return failWith(r, kImageCannotRead, "cannot read the pixels of image '" + std::string(path) + "': " +
                                                     in->geterror());
        r->status = kImageOk;
        return kImageOk;
    } catch (const std::exception& e) {
        return failWith(r, kImageCannotRead, "cannot read image '" + std::string(path) + "': " + e.what());
    }
}

extern "C" __attribute__((visibility("default"))) void telescopeImageFree(TelescopeImageResult* r) {
    std::free(r->pixels);
    r->pixels = nullptr;
}
