// Per-pixel sums on the host, in double precision: the estimate, its square, the base, the
// correction and its positive and negative parts of every pixel, and the sample count. A Film is
// the exact state of a render: means, variances and output images derive from it, and two films
// of one scene with different seeds merge by adding sums.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "shared/gpu_types.h"

namespace telescope {

// Samples in progress between two batches: a photon block of the uniform schedule that has run
// some of its passes, or the per-pixel blocks of the per_pixel schedule. The passes that wrote it
// read it back on resume (Renderer::resume), so an interrupted render continues its block where it
// stopped; nothing of it is in the film's sums. Empty for renders whose samples finish in one batch.
struct PendingSamples {
    uint32_t unitsDone = 0;        // units (photon passes) of the sample in progress
    uint32_t unitsTotal = 0;       // units that sample takes (m^k passes of its level-k block)
    uint32_t level = 0;            // its level (uniform schedule)
    std::vector<uint8_t> device;   // the integrator's per-pixel block state, as on the device
    bool empty() const { return unitsDone == 0 && device.empty(); }
};

class Film {
public:
    Film() = default;
    Film(uint32_t width, uint32_t height);

    uint32_t width() const { return width_; }
    uint32_t height() const { return height_; }
    size_t pixelCount() const { return size_t(width_) * height_; }
    uint64_t samplesPerPixel() const { return spp_; }
    void setSamplesPerPixel(uint64_t spp) { spp_ = spp; }

    // Raw sums of a channel (shader::kChannel*); w of the estimate channel counts dropped
    // non-finite samples.
    std::vector<glm::dvec4>& sums(uint32_t channel) { return sums_[channel]; }
    const std::vector<glm::dvec4>& sums(uint32_t channel) const { return sums_[channel]; }

    // Samples of a pixel: spp, or, when pixels complete samples at their own pace (photon mapping's
    // per_pixel schedule, setPerPixelCounts), the count the render kept in w of kChannelEstimateSq.
    // Checkpoints (version 2) record the flag.
    double samplesOf(size_t pixel) const;
    // Pixels keep their own sample counts (0 samples reads as 0, never as spp).
    void setPerPixelCounts(bool on) { perPixelCounts_ = on; }
    bool perPixelCounts() const { return perPixelCounts_; }

    glm::dvec3 mean(uint32_t channel, size_t pixel) const;
    // Sample variance of the pixel estimate divided by the sample count: the variance of the mean.
    glm::dvec3 varianceOfMean(size_t pixel) const;
    uint64_t nonFiniteSamples() const;

    // Adds another film's samples (same size). Samples in progress are not merged: the result has
    // none (a merge of shards is of completed samples; `merge` says when it leaves a block out).
    void merge(const Film& other);

    // The render's samples in progress (a checkpoint keeps them; images never show them).
    const PendingSamples& pending() const { return pending_; }
    void setPending(PendingSamples p) { pending_ = std::move(p); }

    // The sums as the device's accumulation holds them (shared/gpu_types.h): a (hi, lo) float
    // pair per channel and pixel, hi + lo the double sum to about 2^-48 of it.
    std::vector<glm::vec4> compensatedPairs() const;

private:
    uint32_t width_ = 0, height_ = 0;
    uint64_t spp_ = 0;
    bool perPixelCounts_ = false;
    std::array<std::vector<glm::dvec4>, shader::kChannelCount> sums_;
    PendingSamples pending_;
};

}  // namespace telescope
