// transmittance_study: one estimator on one 1-D problem (`telescope study transmittance`). Each
// thread draws samplesPerThread independent estimates of T on the unit segment and writes their
// sum, sum of squares, the density lookups they took (the work) and the largest |Z|.
#version 460
#extension GL_GOOGLE_include_directive : require

#include "shared/transmittance_study.h"
#include "shared/transmittance_estimators.h"

layout(local_size_x = kTrStudyGroupSize) in;
layout(std430, binding = kTrStudyBindingResults) writeonly buffer Results { vec4 results[]; };
layout(push_constant) uniform Push { TrStudyPush pc; };

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.threads) return;
    TrSegment s;
    s.profile = pc.profile;
    s.sigmaT = vec3(1.0);
    s.len = 1.0;
    s.origin = vec3(0.0);
    s.dir = vec3(0.0, 0.0, 1.0);
    s.densityMin = pc.densityMin;
    s.densityMax = pc.densityMax;
    s.medium = 0u; s.pad0 = 0u; s.pad1 = 0u; s.pad2 = 0u;
    TrEstimator e = TrEstimator(pc.estimator, pc.level, LevelPmf(kPmfGeometric, pc.pmfR, 0.0), pc.terms, 0u);
    vec4 sums = vec4(0.0);
    for (uint i = 0u; i < pc.samplesPerThread; ++i) {
        Rng rng = rngCreate(id, i, pc.seed);
        uint lookups = 0u;
        float z = trEstimate(e, pc.model, kFormSurfaceSurface, s, rng, lookups).x;
        sums += vec4(z, z * z, float(lookups), 0.0);
        sums.w = max(sums.w, abs(z));
    }
    results[pc.outputOffset + id] = sums;
}
