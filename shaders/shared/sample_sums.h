// What a pixel keeps of its samples: the six film channels (kChannel*, shared/gpu_types.h) summed
// in registers, and the compensated addition that carries them into the film. One source for the
// passes that add samples (path_trace, path_resolve, gather) and for the CPU tests
// (tests/unit/sample_sums_test.cpp).
#ifndef TELESCOPE_SAMPLE_SUMS_H
#define TELESCOPE_SAMPLE_SUMS_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

struct SampleSums {
    vec3 z;              // sum of Z = base + correction
    vec3 z2;             // sum of Z^2
    vec3 base;           // sum of the base I(k)
    vec3 correction;     // sum of the correction
    vec3 correctionPos;  // sum of max(correction, 0)
    vec3 correctionNeg;  // sum of min(correction, 0)
    float dropped;       // non-finite samples, left out of every sum
    float count;         // samples of this pixel where pixels differ (photon per_pixel blocks), else 0
};

FN SampleSums sampleSumsZero() {
    SampleSums s;
    s.z = vec3(0.0f);
    s.z2 = vec3(0.0f);
    s.base = vec3(0.0f);
    s.correction = vec3(0.0f);
    s.correctionPos = vec3(0.0f);
    s.correctionNeg = vec3(0.0f);
    s.dropped = 0.0f;
    s.count = 0.0f;
    return s;
}

FN bool isFiniteVec(vec3 v) { return !(any(isnan(v)) || any(isinf(v))); }

// Adds the sample Z = base + correction; a non-finite sample (NaN or infinity in any channel of Z,
// which a non-finite base or correction makes) is counted as dropped and added to nothing.
FN void sampleSumsAdd(INOUT(SampleSums) s, vec3 base, vec3 correction) {
    vec3 z = base + correction;
    if (!isFiniteVec(z)) {
        s.dropped += 1.0f;
        return;
    }
    s.z += z;
    s.z2 += z * z;
    s.base += base;
    s.correction += correction;
    s.correctionPos += max(correction, vec3(0.0f));
    s.correctionNeg += min(correction, vec3(0.0f));
}

// Knuth's TwoSum: sum = fl(a + b) and the exact rounding error, a + b = sum + error. Film sums are
// (hi, lo) pairs updated with it, so sums of 10^6 and more samples keep ~40 significant bits.
FN vec4 twoSum(vec4 a, vec4 b, OUT(vec4) error) {
    PRECISE vec4 sum = a + b;
    PRECISE vec4 bp = sum - a;
    PRECISE vec4 e = (a - (sum - bp)) + (b - bp);
    error = e;
    return sum;
}

SHADER_NAMESPACE_END

#endif
