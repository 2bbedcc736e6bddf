// `telescope study transmittance`: the paper's canonical 1-D study (Misso et al. 2022, section 4;
// docs/ESTIMATORS.md section 4). Every transmittance estimator runs on the device over a grid of 1-D
// problems (density profile constant / sine / Gaussian, target transmittance 0.01 to 0.99,
// majorant looseness 1 to 2, exponential and Davis transmittance at three tails) and the work x MSE of each is
// written as a CSV, one heat-map PNG per estimator (gnuplot) and a summary table.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "gpu/context.h"

namespace telescope {

struct TransmittanceStudyOptions {
    std::string outDir;
    uint32_t samples = 16384;   // estimates per problem and estimator
    uint32_t level = 1;         // base level of ray marching (2^k points) and debiased marching
    float pmfR = 0.65f;         // geometric pmf of debiased marching
    uint32_t taylorTerms = 1;   // taylor: terms before the roulette (TransmittanceEstimatorSettings::terms)
    uint32_t seed = 1;
    std::function<void(const std::string&)> log;
};

struct TransmittanceStudyRow {
    std::string estimator, model, profile;
    double target = 0, looseness = 0;
    double mean = 0, variance = 0, mse = 0, lookups = 0, maxAbs = 0;
    double workTimesRelMse() const { return lookups * mse / (target * target); }
};

struct TransmittanceStudyReport {
    std::vector<TransmittanceStudyRow> rows;
    std::vector<std::string> files;
};

TransmittanceStudyReport runTransmittanceStudy(gpu::Context& context, const TransmittanceStudyOptions& options);

}  // namespace telescope
