// The photon map of one pass on the device: the photon buffer, the hash grid (per-bucket counts,
// bucket ends after the scatter, a copy of the photons in bucket order), the prefix-sum scratch
// and the header through which the shaders reach all of them by device address (the photon
// arrays also through texel buffers while they fit one: docs/PHOTON-MAPPING.md). Owns the
// hash_grid_build pipelines (one per stage of shaders/hash_grid_build.comp).
//
// Memory per photon of capacity: 32 bytes (Photon) + 32 (its copy in bucket order) + 8 per hash
// bucket, with tableSize = the power of two at least half the capacity (at most 2^24 buckets).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "shared/gpu_types.h"

namespace telescope {

class PhotonMap {
public:
    PhotonMap(gpu::Context& context, uint64_t capacity);

    gpu::Context& context() const { return context_; }
    uint64_t capacity() const { return capacity_; }
    uint32_t tableSize() const { return tableSize_; }
    VkDeviceAddress headerAddress() const { return header_.address(); }
    // What a gather binds as its sorted-photon texels (photon_gather.glsl): the photons in bucket
    // order when they fit the device's texel-buffer limit (texelsFit, the kSpecSortedTexels value
    // of the gather's pipeline), else a stand-in, and the gather reads them by address.
    // generation() changes whenever the buffers are reallocated, and with it the binding.
    bool texelsFit() const;
    const gpu::Buffer& gatherTexels() const { return texelsFit() ? sorted_ : header_; }
    uint64_t generation() const { return generation_; }
    uint64_t deviceBytes() const;

    // Grows the buffers to hold at least `photons` photons (contents are lost).
    void reserve(uint64_t photons);
    // Reallocates for `photons` photons when the capacity is over 1.5 times that (contents lost).
    void shrinkTo(uint64_t photons);
    // Writes the header for the next pass: no photons stored, the given cell size. powerPaths: the
    // paths photon_trace divides the powers by when it may trace fewer (0: exactly that many).
    void beginPass(float cellSize, uint32_t powerPaths = 0);
    // Photons the last pass tried to store (more than capacity() when it overflowed).
    uint64_t storedCount() const;
    // Photons in the fullest bucket of the last build (the scan records it).
    uint32_t maxBucket() const;
    // The whole header of this pass in one read (storedCount, maxBucket, loopCapHits: the lanes of
    // photon_trace and gather that reached lavapipe's loop cap, gpu_types.h).
    shader::PhotonMapHeader header() const;
    // Gather slices (dispatches of kGatherSlicePhotons photons per bucket) for a bucket this full.
    // (gatherCount: a k-nearest gather's k, whose slices are smaller; 0 for every photon within r.)
    static uint32_t slicesFor(uint32_t photonsInBucket, uint32_t gatherCount = 0);
    // Photons of each bucket a slice reads: shader::gatherSlicePhotons, or fewer where
    // $TELESCOPE_GATHER_SLICE asks (tests: many slices in small scenes).
    static uint32_t sliceLength(uint32_t gatherCount = 0);

    // Records the hash-grid build over the stored photons: clear, count, scan, scatter.
    void recordBuild(gpu::CommandBatch& batch);
    void recordWarmUp(gpu::CommandBatch& batch);

    // Tests: uploads photons directly (position, power, incoming direction).
    void uploadPhotons(const std::vector<shader::Photon>& photons, float cellSize);
    // Tests: gatherPhotons() at each query (position, normal), with kernel sums at radius and
    // the difference between the levels given by logRadius2 and logStep2 (power.x only).
    // Returns (base, difference, found, 0) per query. byAddress: read the sorted photons by address,
    // as a gather does when they exceed the texel limit.
    std::vector<glm::vec4> query(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                 float radius, float logRadius2, float logStep2, uint32_t kernel,
                                 bool byAddress = false);
    // Tests: the k-nearest gather (nearestSearch / nearestSums) at each query within `radius`:
    // (base, 0, found, 0) per query, base = sum over the k nearest of power.x W_{r_k}.
    std::vector<glm::vec4> queryNearest(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                        float radius, uint32_t k, uint32_t kernel, bool byAddress = false);

private:
    void allocate(uint64_t capacity);
    void recordStage(gpu::CommandBatch& batch, uint32_t stage, const shader::HashGridPush& push, uint64_t threads);
    shader::HashGridPush basePush() const;
    static gpu::PipelineDesc stageDesc(uint32_t stage, bool texels, uint32_t kernel = 0, uint32_t gatherCount = 0);
    std::vector<glm::vec4> runQuery(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                    shader::HashGridPush p, uint32_t kernel, uint32_t gatherCount, bool byAddress);
    void bindStage(gpu::ComputePipeline& pipeline, bool texels) const;

    gpu::Context& context_;
    uint64_t capacity_ = 0;
    uint32_t tableSize_ = 0;
    float cellSize_ = 1.0f;
    uint64_t generation_ = 0;
    bool stagesTexels_ = false;  // the stages' kSpecSortedTexels
    gpu::Buffer header_, photons_, sorted_, cellCount_, cellStart_, scanScratch_;
    std::vector<uint64_t> scanLevelOffsets_;  // element offset of each block-total level in scanScratch_
    std::vector<uint32_t> scanLevelCounts_;   // elements of level 0 (the table), 1, 2, ...
    std::vector<std::unique_ptr<gpu::ComputePipeline>> stages_;  // indexed by kGridStage*
};

}  // namespace telescope
