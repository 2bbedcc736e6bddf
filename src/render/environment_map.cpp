#include "render/environment_map.h"

#include <algorithm>
#include <cmath>

#include "shared/environment_map.h"

namespace telescope {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

std::vector<double> environmentSamplingWeights(const EnvironmentImage& image) {
    const int w = int(image.width), h = int(image.height);
    std::vector<double> weights(size_t(w) * h);
    for (int y = 0; y < h; ++y) {
        const double rowWeight = std::sin(y * kPi / h);
        for (int x = 0; x < w; ++x) {
            const float* t = &image.rgb[(size_t(y) * w + x) * 3];
            weights[size_t(y) * w + x] = double(std::max({std::abs(t[0]), std::abs(t[1]), std::abs(t[2])})) * image.scale * rowWeight;
        }
    }
    // Tungsten's dilation: a running max forward, the wrap (unless clamped), a running max back;
    // the same along columns.
    auto at = [&](int x, int y) -> double& { return weights[size_t(y) * w + x]; };
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w - 1; ++x) at(x, y) = std::max(at(x, y), at(x + 1, y));
        if (!image.clamp) at(0, y) = at(w - 1, y) = std::max(at(w - 1, y), at(0, y));
        for (int x = w - 1; x > 0; --x) at(x, y) = std::max(at(x, y), at(x - 1, y));
    }
    for (int x = 0; x < w; ++x) {
        for (int y = 0; y < h - 1; ++y) at(x, y) = std::max(at(x, y), at(x, y + 1));
        if (!image.clamp) at(x, 0) = at(x, h - 1) = std::max(at(x, 0), at(x, h - 1));
        for (int y = h - 1; y > 0; --y) at(x, y) = std::max(at(x, y), at(x, y - 1));
    }
    return weights;
}

std::vector<float> buildEnvironmentBuffer(const EnvironmentImage& image, const glm::mat3& rotation) {
    const uint32_t w = image.width, h = image.height;
    std::vector<float> out(shader::envBufferFloats(w, h), 0.0f);
    out[0] = float(w);
    out[1] = float(h);
    out[3] = environmentTestPdfScale;
    out[2] = float((image.interpolate ? shader::kEnvInterpolate : 0u) | (image.clamp ? shader::kEnvClamp : 0u));
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) out[4 + 3 * r + c] = rotation[c][r];  // glm: [column][row]
    for (size_t i = 0; i < size_t(w) * h * 3; ++i) out[shader::kEnvHeaderFloats + i] = image.rgb[i] * image.scale;

    // Sampling tables: rows by their total weight, columns within each row by theirs (a row or an
    // image of zero weight falls back to uniform).
    const std::vector<double> weights = environmentSamplingWeights(image);
    const size_t rowCdf = shader::kEnvHeaderFloats + size_t(w) * h * 3, columnCdf = rowCdf + h;
    std::vector<double> rowTotal(h, 0.0);
    double total = 0.0;
    for (uint32_t y = 0; y < h; ++y) {
        for (uint32_t x = 0; x < w; ++x) rowTotal[y] += weights[size_t(y) * w + x];
        total += rowTotal[y];
        double running = 0.0;
        for (uint32_t x = 0; x < w; ++x) {
            running += rowTotal[y] > 0.0 ? weights[size_t(y) * w + x] : 1.0;
            out[columnCdf + size_t(y) * w + x] = float(running / (rowTotal[y] > 0.0 ? rowTotal[y] : double(w)));
        }
        out[columnCdf + size_t(y) * w + w - 1] = 1.0f;
    }
    double running = 0.0;
    for (uint32_t y = 0; y < h; ++y) {
        running += total > 0.0 ? rowTotal[y] : 1.0;
        out[rowCdf + y] = float(running / (total > 0.0 ? total : double(h)));
    }
    out[rowCdf + h - 1] = 1.0f;
    return out;
}

glm::vec3 environmentMeanRadiance(const EnvironmentImage& image) {
    const uint32_t w = image.width, h = image.height;
    glm::dvec3 sum(0.0);
    double solidAngle = 0.0;
    for (uint32_t y = 0; y < h; ++y) {
        const double s = std::sin((y + 0.5) * kPi / h);
        for (uint32_t x = 0; x < w; ++x) {
            const float* t = &image.rgb[(size_t(y) * w + x) * 3];
            sum += glm::dvec3(t[0], t[1], t[2]) * s;
        }
        solidAngle += s * w;
    }
    return solidAngle > 0.0 ? glm::vec3(sum / solidAngle) * image.scale : glm::vec3(0.0f);
}

}  // namespace telescope
