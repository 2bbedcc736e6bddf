// Image files for bitmap textures (docs/SCENE-FORMAT.md, "Textures"), read with OpenImageIO.
// OpenImageIO pulls in about 260 shared libraries that cost every process about 0.6 s of CPU at
// start-up when linked in (docs/BENCHMARKS.md), so the renderer does not link it:
// `libtelescope_image.so` (src/image_plugin/) does, and readImageFile() loads it with dlopen the
// first time a scene names an image (as src/scene/vdb_file.h does for OpenVDB).
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
    kImageCannotRead = 2,  // opened but its pixels could not be read
    kImageTooLarge = 3,    // more pixels than the caller accepts
};

// The first subimage as floats, row-major from the top row, `channels` per pixel; integer formats
// are scaled to [0, 1] (OpenImageIO's conversion), floating-point ones are as stored.
struct TelescopeImageResult {
    int32_t status;
    int32_t width, height, channels;
    int32_t floatingPoint;  // the file stores half, float or double values
    float* pixels;
    char message[512];
};

typedef int32_t (*TelescopeImageReadFn)(const char* path, uint64_t maxPixels, TelescopeImageResult* result);
typedef void (*TelescopeImageFreeFn)(TelescopeImageResult* result);

}  // extern "C"

namespace telescope {

struct ImageFileData {
    uint32_t width = 0, height = 0, channels = 0;
    bool floatingPoint = false;
    std::vector<float> pixels;
};

// Throws std::runtime_error with the plugin's message (or why the plugin is unavailable);
// `status` says which TelescopeImageStatus it was.
ImageFileData readImageFile(const std::string& path, uint64_t maxPixels, int32_t& status);

}  // namespace telescope
