// Statistics over image regions for render tests (docs/ESTIMATORS.md section 6, docs/TESTING.md):
// block means with the variance of the mean taken from the estimator's own per-pixel sample
// variance, Z-scores against an analytic value or an independent render, Sidak-corrected
// thresholds (normal, or Student t for a few batch means).
//
// A Z-test is valid only for an estimator with finite variance and enough samples per region for
// the central limit theorem; each test states why its estimator has finite variance.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "render/film.h"

namespace telescope::test {

struct RegionMean {
    glm::dvec3 mean{0.0};
    glm::dvec3 variance{0.0};  // variance of the mean
};

// Means of the estimate over square blocks of `block` x `block` pixels (row-major blocks).
std::vector<RegionMean> blockMeans(const Film& film, uint32_t block, uint32_t channel = 0);

// The mean of the whole image (one region).
RegionMean imageMean(const Film& film, uint32_t channel = 0);

// Two-sided normal quantile for a family of `tests` tests at overall false-alarm rate `alpha`.
double sidakThreshold(double alpha, size_t tests);
// The same with Student's t with `dof` degrees of freedom (means of a few batches).
double sidakThresholdT(double alpha, size_t tests, double dof);

struct ZSummary {
    double maxAbsZ = 0.0;
    size_t failing = 0;   // tests above the threshold
    size_t tests = 0;
    std::string worst;    // description of the worst test
    double threshold = 0.0;  // set by compareBlocksAndImage
};

// Z = (a - b) / sqrt(var_a + var_b) per block and colour channel. Noiseless blocks must agree
// exactly (identical black regions are skipped).
ZSummary compareRegions(const std::vector<RegionMean>& a, const std::vector<RegionMean>& b, double threshold);
// Against a known value per channel; a noiseless block must equal it to 1e-6.
ZSummary compareToValue(const std::vector<RegionMean>& a, glm::dvec3 value, double threshold);

// The unbiasedness test of a render against a reference (an independent render or a closed form
// with its own variance): every block of `block` x `block` pixels and the whole image, three
// channels each, one Sidak family at false-alarm rate `alpha`. The image mean catches a small
// bias spread over the image that no single block resolves.
ZSummary compareBlocksAndImage(const Film& film, const std::vector<RegionMean>& referenceBlocks,
                               const RegionMean& referenceImage, uint32_t block, double alpha = 1e-3);

}  // namespace telescope::test

namespace telescope::test {

// Smallest number k such that a sign test on n batch means (each above the answer with
// probability 1/2) rejects when fewer than k or more than n - k are above, for a family of
// `tests` tests at overall false-alarm rate alpha (Sidak). Also returns the rate each test has.
struct SignTestBounds {
    uint32_t k = 0;
    double rate = 0.0;  // exact false-alarm rate of one test: 2 P(Binomial(n, 1/2) < k)
};
SignTestBounds sidakSignTest(double alpha, size_t tests, uint32_t n);

// Per region and channel (the first `channels` of R, G, B): a t-test of the batch means
// ([region][batch], render_harness.h regionBatchMeans) against the reference's mean, with the
// batch means' own spread plus the reference's variance of the mean (Student quantile with
// B - 1 degrees of freedom), Sidak-corrected over regions x channels at false-alarm rate alpha.
// Valid for heavy-tailed estimators too (unbiased photon mapping: tail index 1.45,
// docs/PHOTON-MAPPING.md): their large deviations inflate the batch spread, which makes the test
// conservative rather than liberal. Prints every region under `label`.
struct BatchVerdict {
    size_t failures = 0;  // region-channel tests beyond the limit
    size_t tests = 0;
    double worstT = 0.0;
    double limit = 0.0;
};
BatchVerdict compareBatchMeans(const std::vector<std::vector<glm::dvec3>>& batches,
                               const std::vector<RegionMean>& reference, uint32_t channels, double alpha,
                               const char* label);

}  // namespace telescope::test
