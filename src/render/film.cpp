#include "render/film.h"

#include <stdexcept>

namespace telescope {

Film::Film(uint32_t width, uint32_t height) : width_(width), height_(height) {
    for (auto& s : sums_) s.assign(pixelCount(), glm::dvec4(0.0));
}

double Film::samplesOf(size_t pixel) const {
    return perPixelCounts_ ? sums_[shader::kChannelEstimateSq][pixel].w : double(spp_);
}

glm::dvec3 Film::mean(uint32_t channel, size_t pixel) const {
    const double n = samplesOf(pixel);
    if (n == 0.0) return glm::dvec3(0.0);
    return glm::dvec3(sums_[channel][pixel]) / n;
}

glm::dvec3 Film::varianceOfMean(size_t pixel) const {
    const double n = samplesOf(pixel);
    if (n < 2.0) return glm::dvec3(0.0);
    glm::dvec3 s1 = glm::dvec3(sums_[shader::kChannelEstimate][pixel]);
    glm::dvec3 s2 = glm::dvec3(sums_[shader::kChannelEstimateSq][pixel]);
    glm::dvec3 var = (s2 - s1 * s1 / n) / (n - 1.0);
    return glm::max(var, glm::dvec3(0.0)) / n;
}

uint64_t Film::nonFiniteSamples() const {
    double total = 0.0;
    for (const auto& v : sums_[shader::kChannelEstimate]) total += v.w;
    return uint64_t(total + 0.5);
}

void Film::merge(const Film& other) {
    if (other.width_ != width_ || other.height_ != height_)
        throw std::invalid_argument("cannot merge films of different sizes");
    for (uint32_t c = 0; c < shader::kChannelCount; ++c)
        for (size_t i = 0; i < pixelCount(); ++i) sums_[c][i] += other.sums_[c][i];
    spp_ += other.spp_;
    pending_ = {};
}

}  // namespace telescope

namespace telescope {

std::vector<glm::vec4> Film::compensatedPairs() const {
    std::vector<glm::vec4> raw(pixelCount() * shader::kChannelCount * 2);
    for (uint32_t c = 0; c < shader::kChannelCount; ++c)
        for (size_t i = 0; i < pixelCount(); ++i) {
            const size_t k = (c * pixelCount() + i) * 2;
            raw[k] = glm::vec4(sums_[c][i]);
            raw[k + 1] = glm::vec4(sums_[c][i] - glm::dvec4(raw[k]));
        }
    return raw;
}

}  // namespace telescope
