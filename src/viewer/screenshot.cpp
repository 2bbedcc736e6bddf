#include "viewer/screenshot.h"

#include <png.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

namespace telescope::viewer {

// The swapchain's 8-bit RGBA as an RGB PNG (libpng's simplified API), written to a temporary
// file and moved into place.
void writeScreenshotPng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    if (rgba.size() != size_t(width) * height * 4)
        throw std::logic_error(fmt::format("{}: {} bytes is not a {}x{} RGBA image", path, rgba.size(), width, height));
    std::vector<uint8_t> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba[i * 4 + c];

    std::filesystem::path p(path);
    const std::string tmp = (p.parent_path() / ("." + p.stem().string() + ".partial.png")).string();
    png_image image{};
    image.version = PNG_IMAGE_VERSION;
    image.width = png_uint_32(width);
    image.height = png_uint_32(height);
    image.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&image, tmp.c_str(), 0, rgb.data(), 0, nullptr)) {
        std::string err = image.message;
        png_image_free(&image);
        std::remove(tmp.c_str());
        throw std::runtime_error(fmt::format("{}: write failed: {}", path, err));
    }
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::remove(tmp.c_str());
        throw std::runtime_error(fmt::format("{}: cannot move the screenshot into place: {}", path, ec.message()));
    }
}

}  // namespace telescope::viewer
