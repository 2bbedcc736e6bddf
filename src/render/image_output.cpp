// OpenImageIO first: it must come before any X11 header.
#include <OpenImageIO/imageio.h>

#include "render/image_output.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

namespace telescope {

namespace {

// Temporary file next to the target, with the same extension so OIIO picks the same format.
std::string temporaryPath(const std::string& path) {
    std::filesystem::path p(path);
    return (p.parent_path() / ("." + p.stem().string() + ".partial" + p.extension().string())).string();
}

void writeImage(const std::string& path, const OIIO::ImageSpec& spec, OIIO::TypeDesc format, const void* data) {
    std::string tmp = temporaryPath(path);
    auto out = OIIO::ImageOutput::create(tmp);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot write this image format ({})", path, OIIO::geterror()));
    bool ok = out->open(tmp, spec) && out->write_image(format, data) && out->close();
    if (!ok) {
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
        throw std::runtime_error(fmt::format("{}: cannot move the finished image into place: {}", path, ec.message()));
    }
}

float srgbEncode(float linear) {
    float c = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

void writeExr(const std::string& path, const Film& film, const ImageMetadata& metadata) {
    using namespace shader;
    const int channels = 18;
    OIIO::ImageSpec spec(int(film.width()), int(film.height()), channels, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"R", "G", "B", "base.R", "base.G", "base.B",
                         "correction.R", "correction.G", "correction.B", "variance.R", "variance.G", "variance.B",
                         "correction_positive.R", "correction_positive.G", "correction_positive.B",
                         "correction_negative.R", "correction_negative.G", "correction_negative.B"};
    spec.attribute("compression", "zip");
    for (const auto& [key, value] : metadata.entries) spec.attribute(key, value);

    std::vector<float> data(film.pixelCount() * channels);
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        glm::dvec3 base = film.mean(kChannelBase, i);
        glm::dvec3 corr = film.mean(kChannelCorrection, i);
        glm::dvec3 est = film.mean(kChannelEstimate, i);
        glm::dvec3 var = film.varianceOfMean(i);
        glm::dvec3 pos = film.mean(kChannelCorrectionPositive, i);
        glm::dvec3 neg = film.mean(kChannelCorrectionNegative, i);
        float* px = &data[i * channels];
        for (int c = 0; c < 3; ++c) {
            px[c] = float(est[c]);
            px[3 + c] = float(base[c]);
            px[6 + c] = float(corr[c]);
            px[9 + c] = float(var[c]);
            px[12 + c] = float(pos[c]);
            px[15 + c] = float(neg[c]);
        }
    }
    writeImage(path, spec, OIIO::TypeDesc::FLOAT, data.data());
}

void writeSrgbPng(const std::string& path, int width, int height, const std::vector<float>& rgb) {
    if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height) * 3)
        throw std::invalid_argument(fmt::format("{}: {} floats is not a {}x{} RGB image", path, rgb.size(), width, height));
    OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    std::vector<uint8_t> data(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) data[i] = uint8_t(std::lround(255.0f * srgbEncode(rgb[i])));
    writeImage(path, spec, OIIO::TypeDesc::UINT8, data.data());
}

void writePngPreview(const std::string& path, const Film& film) {
    std::vector<float> rgb(film.pixelCount() * 3);
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        glm::dvec3 est = film.mean(shader::kChannelEstimate, i);
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = float(est[c]);
    }
    writeSrgbPng(path, int(film.width()), int(film.height()), rgb);
}

RgbImage readExrChannels(const std::string& path, const std::vector<std::string>& channels) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw std::runtime_error(fmt::format("{}: cannot open ({})", path, OIIO::geterror()));
    const OIIO::ImageSpec& spec = in->spec();
    std::vector<float> all(size_t(spec.width) * spec.height * spec.nchannels);
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, all.data()))
        throw std::runtime_error(fmt::format("{}: read failed: {}", path, in->geterror()));
    RgbImage img;
    img.width = spec.width;
    img.height = spec.height;
    img.channelNames = spec.channelnames;
    std::vector<int> index;
    for (const auto& name : channels) {
        auto it = std::find(spec.channelnames.begin(), spec.channelnames.end(), name);
        if (it == spec.channelnames.end()) throw std::runtime_error(fmt::format("{}: no channel {}", path, name));
        index.push_back(int(it - spec.channelnames.begin()));
    }
    img.pixels.resize(size_t(spec.width) * spec.height * channels.size());
    for (size_t p = 0; p < size_t(spec.width) * spec.height; ++p)
        for (size_t c = 0; c < channels.size(); ++c)
            img.pixels[p * channels.size() + c] = all[p * spec.nchannels + index[c]];
    return img;
}

}  // namespace telescope
