// Layout shared by `telescope study transmittance` (src/study/transmittance_study.cpp) and its
// pass (shaders/transmittance_study.comp): one dispatch runs one estimator on one 1-D problem,
// every thread `samplesPerThread` independent estimates of T over a unit segment.
#ifndef TELESCOPE_TRANSMITTANCE_STUDY_H
#define TELESCOPE_TRANSMITTANCE_STUDY_H

#include "shared/density_profiles.h"
#include "shared/transmittance.h"

SHADER_NAMESPACE_BEGIN

CONST uint kTrStudyBindingResults = 0u;  // vec4 per thread: sum Z, sum Z^2, sum lookups, max |Z|
CONST uint kTrStudyBindingCount = 1u;
CONST uint kTrStudyGroupSize = 64u;

struct TrStudyPush {
    TrModel model;
    DensityProfile profile;
    uint estimator; uint level; float pmfR; uint seed;
    float densityMin; float densityMax; uint threads; uint samplesPerThread;
    uint outputOffset; uint terms; uint pad1; uint pad2;
};

SHADER_NAMESPACE_END

#ifdef __cplusplus
static_assert(sizeof(telescope::shader::TrStudyPush) == 112);
#endif

#endif
