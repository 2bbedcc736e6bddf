#include "viewer/screenshot.h"

#include <stdexcept>

#include <fmt/format.h>

#include "render/image_output.h"

namespace telescope::viewer {

// The swapchain's 8-bit RGBA as an RGB PNG (the PNG writer of `render`).
void writeScreenshotPng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    if (rgba.size() != size_t(width) * height * 4)
        throw std::logic_error(fmt::format("{}: {} bytes is not a {}x{} RGBA image", path, rgba.size(), width, height));
    std::vector<uint8_t> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba[i * 4 + c];
    writeRgb8Png(path, int(width), int(height), rgb);
}

}  // namespace telescope::viewer
