// Random numbers: a PCG32 stream per (pixel, sample, seed), so any sample of any pixel can be
// regenerated independently (repeatable renders, resume, merging renders with distinct seeds).
#ifndef TELESCOPE_RNG_H
#define TELESCOPE_RNG_H

#include "shared/lang.h"

SHADER_NAMESPACE_BEGIN

// Jarzynski & Olano 2020, "Hash Functions for GPU Rendering": PCG-based 32-bit hash.
FN uint pcgHash(uint v) {
    uint state = v * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng {
    uint state;
    uint inc;  // odd: selects one of 2^31 PCG streams
};

FN uint rngNextUint(INOUT(Rng) rng) {
    uint s = rng.state;
    rng.state = s * 747796405u + rng.inc;
    uint word = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (word >> 22u) ^ word;
}

// Uniform in [0, 1): 24 random bits, never 1.0 (so -log(1 - u) is finite).
FN float rngNext(INOUT(Rng) rng) {
    return float(rngNextUint(rng) >> 8u) * (1.0f / 16777216.0f);
}

FN Rng rngCreate(uint pixel, uint sampleIndex, uint seed) {
    Rng rng;
    rng.state = pcgHash(pixel ^ pcgHash(seed + 0x9e3779b9u));
    rng.inc = (pcgHash(sampleIndex ^ pcgHash(seed ^ 0x85ebca6bu)) << 1u) | 1u;
    rngNextUint(rng);
    return rng;
}

SHADER_NAMESPACE_END

#endif
