#include <OpenImageIO/imageio.h>  // before anything that may pull in X11

#include "viewer/screenshot.h"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

namespace telescope::viewer {

void writeScreenshotPng(const std::string& path, uint32_t width, uint32_t height, const std::vector<uint8_t>& rgba) {
    if (rgba.size() != size_t(width) * height * 4)
        throw std::logic_error(fmt::format("{}: {} bytes is not a {}x{} RGBA image", path, rgba.size(), width, height));
    std::vector<uint8_t> rgb(size_t(width) * height * 3);
    for (size_t i = 0; i < size_t(width) * height; ++i)
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = rgba[i * 4 + c];

    std::filesystem::path p(path);
    const std::string tmp = (p.parent_path() / ("." + p.stem().string() + ".partial.png")).string();
    OIIO::ImageSpec spec(int(width), int(height), 3, OIIO::TypeDesc::UINT8);
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write PNG ({})", path, OIIO::geterror()));
    if (!(out->open(tmp, spec) && out->write_image(OIIO::TypeDesc::UINT8, rgb.data()) && out->close())) {
        std::string err = out->geterror();
        out.reset();
        std::remove(tmp.c_str());
        throw std::runtime_error(fmt::format("{}: write failed: {}", path, err));
    }
    out.reset();
    std::error_code ec;
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        std::remove(tmp.c_str());
        throw std::runtime_error(fmt::format("{}: cannot move the screenshot into place: {}", path, ec.message()));
    }
}

}  // namespace telescope::viewer
