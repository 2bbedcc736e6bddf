// libtelescope_image.so: the only code that links OpenImageIO (src/scene/image_file.h says why).
#include "scene/image_file.h"

#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include <OpenImageIO/imageio.h>

namespace {

int32_t failWith(TelescopeImageResult* r, int32_t status, const char* format, ...) {
    va_list args;
    va_start(args, format);
    std::vsnprintf(r->message, sizeof(r->message), format, args);
    va_end(args);
    r->status = status;
    return status;
}

}  // namespace

extern "C" __attribute__((visibility("default"))) int32_t telescopeImageRead(const TelescopeImageRequest* q,
                                                                           TelescopeImageResult* r) {
    std::memset(r, 0, sizeof(*r));
    try {
        auto in = OIIO::ImageInput::open(q->path);
        if (!in) {
            std::string why = OIIO::geterror();
            return failWith(r, kImageCannotOpen, "cannot read image '%s': %s", q->path, why.c_str());
        }
        const OIIO::ImageSpec& spec = in->spec();
        const uint64_t w = uint64_t(std::max(spec.width, 0)), h = uint64_t(std::max(spec.height, 0));
        const int channels = spec.nchannels;
        if (w == 0 || h == 0 || channels <= 0)
            return failWith(r, kImageCannotOpen, "image '%s' has no pixels (%llux%llu, %d channels)", q->path,
                            (unsigned long long)w, (unsigned long long)h, channels);
        if (w * h > q->maxPixels)
            return failWith(r, kImageTooLarge, "image '%s' has %llux%llu pixels, more than the %llu accepted", q->path,
                            (unsigned long long)w, (unsigned long long)h, (unsigned long long)q->maxPixels);
        std::vector<float> all(size_t(w * h) * channels);
        if (!in->read_image(0, 0, 0, channels, OIIO::TypeDesc::FLOAT, all.data())) {
            std::string why = in->geterror();
            return failWith(r, kImageReadFailed, "cannot read the pixels of image '%s': %s", q->path, why.c_str());
        }
        const OIIO::TypeDesc::BASETYPE base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
        r->hdr = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
        r->rgb = static_cast<float*>(std::malloc(size_t(w * h) * 3 * sizeof(float)));
        if (!r->rgb) return failWith(r, kImageTooLarge, "out of memory reading image '%s'", q->path);
        for (size_t i = 0; i < w * h; ++i)
            for (int c = 0; c < 3; ++c) r->rgb[i * 3 + c] = all[i * channels + (channels >= 3 ? c : 0)];
        r->width = uint32_t(w);
        r->height = uint32_t(h);
        r->channels = channels;
        return kImageOk;
    } catch (const std::exception& e) {
        return failWith(r, kImageCannotOpen, "cannot read image '%s': %s", q->path, e.what());
    }
}

extern "C" __attribute__((visibility("default"))) void telescopeImageFree(TelescopeImageResult* r) {
    std::free(r->rgb);
    r->rgb = nullptr;
}
