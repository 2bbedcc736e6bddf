#include "study/error_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace telescope {

ErrorMetrics compareToReference(const Film& film, const RgbImage& ref, const PixelRegion& region) {
    if (ref.width != int(film.width()) || ref.height != int(film.height()) ||
        ref.pixels.size() != film.pixelCount() * 3)
        throw std::invalid_argument(fmt::format("reference is {}x{}, the render {}x{}", ref.width, ref.height,
                                                film.width(), film.height()));
    double se = 0.0, rel = 0.0, err = 0.0, sumRef = 0.0;
    size_t pixels = 0;
    for (size_t i = 0; i < film.pixelCount(); ++i) {
        const int px = int(i % film.width()), py = int(i / film.width());
        if (region.w > 0 && (px < region.x || px >= region.x + region.w || py < region.y || py >= region.y + region.h))
            continue;
        ++pixels;
        glm::dvec3 x = film.mean(shader::kChannelEstimate, i);
        for (int c = 0; c < 3; ++c) {
            double r = ref.pixels[i * 3 + c], d = x[c] - r;
            se += d * d;
            rel += d * d / (r * r + kRelMseEpsilon);
            err += d;
            sumRef += r;
        }
    }
    const double n = double(std::max<size_t>(pixels, 1)) * 3.0;
    ErrorMetrics m;
    m.rmse = std::sqrt(se / n);
    m.relMse = rel / n;
    m.meanError = err / n;
    m.relMeanError = sumRef != 0.0 ? err / sumRef : 0.0;
    return m;
}

double logLogSlope(const std::vector<double>& x, const std::vector<double>& y) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    size_t n = 0;
    for (size_t i = 0; i < x.size() && i < y.size(); ++i) {
        if (!(x[i] > 0.0) || !(y[i] > 0.0)) continue;
        double lx = std::log(x[i]), ly = std::log(y[i]);
        sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
        ++n;
    }
    double den = double(n) * sxx - sx * sx;
    if (n < 2 || !(std::abs(den) > 0.0)) return std::nan("");
    return (double(n) * sxy - sx * sy) / den;
}

double timeToReach(const std::vector<double>& x, const std::vector<double>& y, double target) {
    for (size_t i = 0; i < x.size() && i < y.size(); ++i) {
        if (!(y[i] <= target)) continue;
        if (i == 0 || !(x[i - 1] > 0.0) || !(y[i - 1] > 0.0) || !(y[i] > 0.0)) return x[i];
        double t = (std::log(target) - std::log(y[i - 1])) / (std::log(y[i]) - std::log(y[i - 1]));
        return std::exp(std::log(x[i - 1]) + t * (std::log(x[i]) - std::log(x[i - 1])));
    }
    return -1.0;
}

}  // namespace telescope
