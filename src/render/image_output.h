// Writes a Film as a float EXR (estimate, base, correction, variance, and the positive and negative
// parts of the correction (the paper's teaser decomposition), with the
// render's settings in the metadata) and a tone-mapped PNG preview. Files are written to a
// temporary name and renamed, so a failed write leaves no half-written output.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "render/film.h"

namespace telescope {

struct ImageMetadata {
    std::vector<std::pair<std::string, std::string>> entries;  // "telescope:key" -> value
};

void writeExr(const std::string& path, const Film& film, const ImageMetadata& metadata);
// sRGB preview of the estimate; negative and >1 values are clipped for display only.
void writePngPreview(const std::string& path, const Film& film);

// Signed false colour of the estimate's mean over the channels (derivative images): white at 0,
// red positive, blue negative, full colour at the 99th percentile of the nonzero |value|s.
void writeSignedPngPreview(const std::string& path, const Film& film);

// Linear RGB floats (row-major) to an 8-bit sRGB PNG, clipped to [0, 1] for display only.
void writeSrgbPng(const std::string& path, int width, int height, const std::vector<float>& rgb);
// 8-bit RGB bytes (row-major, already encoded) to a PNG, written to a temporary file and moved
// into place.
void writeRgb8Png(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb);

// Reads back the RGB estimate of an EXR written by writeExr (tests and tools).
struct RgbImage {
    int width = 0, height = 0;
    std::vector<float> pixels;  // rgb, row-major
    std::vector<std::string> channelNames;
};
RgbImage readExrChannels(const std::string& path, const std::vector<std::string>& channels);

}  // namespace telescope
