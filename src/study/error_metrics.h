// Error of a render against a reference image, over all pixels and the three colour channels.
#pragma once

#include <vector>

#include "render/film.h"
#include "render/image_output.h"

namespace telescope {

struct ErrorMetrics {
    double rmse = 0.0;          // sqrt(mean (x - ref)^2)
    double relMse = 0.0;        // mean (x - ref)^2 / (ref^2 + kRelMseEpsilon)
    double meanError = 0.0;     // mean (x - ref): the bias, plus noise that averages out
    double relMeanError = 0.0;  // meanError / mean ref
};

// Keeps near-black reference pixels from dominating the relative MSE (the usual 1e-2).
constexpr double kRelMseEpsilon = 1e-2;

// A rectangle of pixels; w = 0 means the whole image.
struct PixelRegion {
    int x = 0, y = 0, w = 0, h = 0;
};

// The reference must be an RGB image of the film's size. Throws std::invalid_argument otherwise.
// Over the region's pixels only when one is given.
ErrorMetrics compareToReference(const Film& film, const RgbImage& reference, const PixelRegion& region = {});

// Least-squares slope of log(y) against log(x) over the points with x > 0 and y > 0 (NaN when
// fewer than two such points).
double logLogSlope(const std::vector<double>& x, const std::vector<double>& y);

// First x at which y falls to the target, interpolating linearly in log-log between points;
// negative when y never reaches it.
double timeToReach(const std::vector<double>& x, const std::vector<double>& y, double target);

}  // namespace telescope
