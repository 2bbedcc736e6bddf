// EXR through OpenEXR and PNG through libpng: both light to load. (OpenImageIO pulled in about 260
// shared libraries, whose relocation cost every process, test and render about 0.6 s of CPU at
// start-up; docs/BENCHMARKS.md.)
#include "render/image_output.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <stdexcept>
#include <thread>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>
#include <fmt/format.h>
#include <png.h>

#include "core/atomic_file.h"

namespace telescope {

namespace {

float srgbEncode(float linear) {
    float c = std::clamp(std::isfinite(linear) ? linear : 0.0f, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

}  // namespace

void writeExr(const std::string& path, const Film& film, const ImageMetadata& metadata) {
    using namespace shader;
    const int channels = 18;
    static const char* const names[channels] = {
        "R", "G", "B", "base.R", "base.G", "base.B",
        "correction.R", "correction.G", "correction.B", "variance.R", "variance.G", "variance.B",
        "correction_positive.R", "correction_positive.G", "correction_positive.B",
        "correction_negative.R", "correction_negative.G", "correction_negative.B"};
    const int width = int(film.width()), height = int(film.height());

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
    writeFileAtomically(path, [&](const std::string& tmp) {
        Imf::Header header(width, height);
        header.compression() = Imf::ZIP_COMPRESSION;
        // zlib's fastest level: half the time of OpenEXR's default (4) for 2-3% more bytes (a
        // 256x256 render's 18 channels: 17 against 33 ms, 519 against 505 KB; docs/BENCHMARKS.md).
        header.zipCompressionLevel() = 1;
        for (const auto& [key, value] : metadata.entries) header.insert(key, Imf::StringAttribute(value));
        Imf::FrameBuffer frame;
        const size_t xStride = sizeof(float) * channels, yStride = xStride * size_t(width);
        for (int c = 0; c < channels; ++c) {
            header.channels().insert(names[c], Imf::Channel(Imf::FLOAT));
            frame.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(data.data() + c), xStride, yStride));
        }
        // ZIP compresses blocks of 16 scanlines independently: OpenEXR's thread pool, one thread per
        // core, compresses them side by side (the same bytes; 1.7x faster on 2 cores).
        static const int threads = [] {
            const int n = int(std::max(1u, std::thread::hardware_concurrency()));
            Imf::setGlobalThreadCount(n);
            return n;
        }();
        Imf::OutputFile file(tmp.c_str(), header, threads);
        file.setFrameBuffer(frame);
        file.writePixels(height);
    });
}

void writeSrgbPng(const std::string& path, int width, int height, const std::vector<float>& rgb) {
    if (width <= 0 || height <= 0 || rgb.size() != size_t(width) * size_t(height) * 3)
        throw std::invalid_argument(fmt::format("{}: {} floats is not a {}x{} RGB image", path, rgb.size(), width, height));
    std::vector<uint8_t> data(rgb.size());
    for (size_t i = 0; i < rgb.size(); ++i) data[i] = uint8_t(std::lround(255.0f * srgbEncode(rgb[i])));
    writeRgb8Png(path, width, height, data);
}

void writeRgb8Png(const std::string& path, int width, int height, const std::vector<uint8_t>& data) {
    if (width <= 0 || height <= 0 || data.size() != size_t(width) * size_t(height) * 3)
        throw std::invalid_argument(fmt::format("{}: {} bytes is not a {}x{} RGB image", path, data.size(), width, height));
    writeFileAtomically(path, [&](const std::string& tmp) {
        png_image image{};
        image.version = PNG_IMAGE_VERSION;
        image.width = png_uint_32(width);
        image.height = png_uint_32(height);
        image.format = PNG_FORMAT_RGB;
        if (!png_image_write_to_file(&image, tmp.c_str(), 0, data.data(), 0, nullptr)) {
            std::string err = image.message;
            png_image_free(&image);
            throw std::runtime_error(err);
        }
    });
}

void writePngPreview(const std::string& path, const Film& film) {
    std::vector<float> rgb(film.pixelCount() * 3);
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        glm::dvec3 est = film.mean(shader::kChannelEstimate, i);
        for (int c = 0; c < 3; ++c) rgb[i * 3 + c] = float(est[c]);
    }
    writeSrgbPng(path, int(film.width()), int(film.height()), rgb);
}

void writeSignedPngPreview(const std::string& path, const Film& film) {
    // The scale: the 99th percentile of the nonzero |luminance|s (a few outliers do not wash out
    // the rest; derivatives are often 0 almost everywhere).
    std::vector<double> lum(film.pixelCount()), mags;
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        const glm::dvec3 e = film.mean(shader::kChannelEstimate, i);
        lum[i] = (e.x + e.y + e.z) / 3.0;
        if (lum[i] != 0.0 && std::isfinite(lum[i])) mags.push_back(std::abs(lum[i]));
    }
    double scale = 0.0;
    if (!mags.empty()) {
        const size_t k = std::min(mags.size() - 1, size_t(0.99 * double(mags.size())));
        std::nth_element(mags.begin(), mags.begin() + ptrdiff_t(k), mags.end());
        scale = mags[k];
    }
    std::vector<uint8_t> rgb(film.pixelCount() * 3);
    for (size_t i = 0; i < lum.size(); ++i) {
        const double t = scale > 0.0 && std::isfinite(lum[i]) ? std::clamp(lum[i] / scale, -1.0, 1.0) : 0.0;
        // White at 0, red for positive, blue for negative (display only: the EXR keeps the values).
        const double fade = 1.0 - std::abs(t);
        const glm::dvec3 c = t >= 0.0 ? glm::dvec3(1.0, fade, fade) : glm::dvec3(fade, fade, 1.0);
        for (int ch = 0; ch < 3; ++ch) rgb[i * 3 + ch] = uint8_t(std::lround(255.0 * c[ch]));
    }
    writeRgb8Png(path, int(film.width()), int(film.height()), rgb);
}

RgbImage readExrChannels(const std::string& path, const std::vector<std::string>& channels) {
    RgbImage img;
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it)
            img.channelNames.push_back(it.name());
        for (const auto& name : channels)
            if (!header.channels().findChannel(name)) throw std::runtime_error(fmt::format("no channel {}", name));
        const Imath::Box2i window = header.dataWindow();
        img.width = window.max.x - window.min.x + 1;
        img.height = window.max.y - window.min.y + 1;
        const size_t n = channels.size();
        img.pixels.assign(size_t(img.width) * size_t(img.height) * n, 0.0f);
        const size_t xStride = sizeof(float) * n, yStride = xStride * size_t(img.width);
        // The slices' base is the address of pixel (0, 0), which may lie outside the data window.
        char* origin = reinterpret_cast<char*>(img.pixels.data()) - ptrdiff_t(window.min.x) * ptrdiff_t(xStride) -
                       ptrdiff_t(window.min.y) * ptrdiff_t(yStride);
        Imf::FrameBuffer frame;
        for (size_t c = 0; c < n; ++c)
            frame.insert(channels[c], Imf::Slice(Imf::FLOAT, origin + c * sizeof(float), xStride, yStride));
        file.setFrameBuffer(frame);
        file.readPixels(window.min.y, window.max.y);
    } catch (const std::exception& e) {
        throw std::runtime_error(fmt::format("{}: cannot read: {}", path, e.what()));
    }
    return img;
}

}  // namespace telescope
