// The level queue of kLevelScheduleQueued (see shared/gpu_types.h), reached by device address.
#extension GL_EXT_buffer_reference : require
#extension GL_EXT_buffer_reference_uvec2 : require

layout(buffer_reference, std430, buffer_reference_align = 16) buffer LevelQueueRef { uint u[]; };
layout(buffer_reference, std430, buffer_reference_align = 16) buffer LevelResultsRef { vec4 v[]; };

uint alignUints(uint n) { return (n + 3u) & ~3u; }  // 16-byte boundary
uint queueChunks() { return (pc.queueCapacity + kLevelChunk - 1u) / kLevelChunk; }
uint queueItemsOffset() { return alignUints(queueChunks() * kLevelBuckets); }  // in uints

LevelQueueRef levelQueue() { return LevelQueueRef(uvec2(pc.queueAddressLo, pc.queueAddressHi)); }

LevelResultsRef levelResults() {
    uint64_t base = packUint2x32(uvec2(pc.queueAddressLo, pc.queueAddressHi));
    return LevelResultsRef(base + uint64_t(queueItemsOffset() + alignUints(pc.queueCapacity)) * uint64_t(4));
}

// The level of sample s of a pixel exactly as startSample() draws it: two jitter numbers, then
// the level, from the sample's own random stream.
uint drawLevel(uint pixelIndex, uint s, LevelPmf pmf) {
    Rng rng = rngCreate(pixelIndex, pc.sampleBase + s, pc.seed);
    rngNext(rng);
    rngNext(rng);
    return levelSample(pmf, rngNext(rng));
}

uint levelBucket(uint level) { return min(level, kLevelBuckets - 1u); }
