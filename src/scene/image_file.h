// Image files read through OpenImageIO (environment maps: .exr, .hdr, ...). OpenImageIO and the
// ~260 libraries it pulls in cost every process about 0.6 s of CPU at start-up when linked
// (docs/BENCHMARKS.md), so the renderer does not link it: `libtelescope_image.so`
// (src/image_plugin/) does, and readImageFile() loads it with dlopen the first time a scene asks
// for an image, as vdb_file.h does for OpenVDB.
//
// The plugin's C interface is below; both sides are built from this header.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

extern "C" {

enum TelescopeImageStatus : int32_t {
    kImageOk = 0,
    kImageCannotOpen = 1,  // missing, unreadable or not an image OpenImageIO knows
    kImageTooLarge = 2,    // more pixels than the request accepts
    kImageReadFailed = 3,  // opened, but its pixels could not be read
};

struct TelescopeImageRequest {
    const char* path;
    uint64_t maxPixels;
};

// RGB floats, row-major, row 0 the top of the image (one channel: grey; more than three: the first
// three). hdr: the file stores floating-point pixels (half, float, double).
struct TelescopeImageResult {
    int32_t status;
    uint32_t width, height;
    int32_t hdr;
    int32_t channels;  // in the file
    float* rgb;
    char message[512];
};

typedef int32_t (*TelescopeImageReadFn)(const TelescopeImageRequest* request, TelescopeImageResult* result);
typedef void (*TelescopeImageFreeFn)(TelescopeImageResult* result);

}  // extern "C"

namespace telescope {

struct ImageFileData {
    uint32_t width = 0, height = 0;
    bool hdr = false;
    std::vector<float> rgb;  // 3 floats a pixel, row 0 at the top
};

// Reads through the plugin; throws std::runtime_error with its message (the caller adds the scene
// file and key).
ImageFileData readImageFile(const std::string& path, uint64_t maxPixels);

}  // namespace telescope
