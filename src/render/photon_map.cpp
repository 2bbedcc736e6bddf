#include "render/photon_map.h"

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

#include <fmt/format.h>

#include "render/render_plan.h"

namespace telescope {

namespace {
constexpr uint32_t kMaxTableSize = 1u << 24;
// The block totals of the largest table fit one block: the scan has at most two levels.
static_assert(uint64_t(kMaxTableSize) <= uint64_t(shader::kScanBlock) * shader::kScanBlock);
constexpr uint64_t kMaxGroups = 4096;  // grid-stride loops cover the rest

// Buckets hold cells, and cells hold several photons: half a bucket per photon of capacity, so
// that few buckets hold two cells (4-7% of the buckets hold photons on the benchmark's plane and
// the caustic Cornell box). Smaller tables made the scan cheaper but the gather slower, by more
// than the grid gained (1/8 of a bucket per photon: the caustic box's gather 15-20% slower;
// docs/BENCHMARKS.photon-notes.md).
// (gridHash keeps the cells around a query in distinct buckets in tables of 512 or more.)
static_assert(shader::kScanBlock >= 512 && shader::kNearestCellsPerAxis <= 8);
uint32_t tableSizeFor(uint64_t capacity) {
    uint32_t t = shader::kScanBlock;
    while (t < capacity / 2 && t < kMaxTableSize) t <<= 1;
    return t;
}
uint32_t lo(VkDeviceAddress a) { return uint32_t(a); }
uint32_t hi(VkDeviceAddress a) { return uint32_t(a >> 32); }
}  // namespace

PhotonMap::PhotonMap(gpu::Context& context, uint64_t capacity) : context_(context) {
    header_ = gpu::Buffer(context, sizeof(shader::PhotonMapHeader), "photon map header");
    allocate(std::max<uint64_t>(capacity, 1));
}

// hash_grid_build's bindings (kGridBinding*, shared/gpu_types.h): the photon arrays as texels and
// storage texels. kSpecSortedTexels says whether the stages use them or reach the arrays by address.
gpu::PipelineDesc PhotonMap::stageDesc(uint32_t stage, bool texels, uint32_t kernel, uint32_t gatherCount) {
    using namespace shader;
    constexpr uint32_t kTexels = (1u << kGridBindingSortedTexels) | (1u << kGridBindingPhotonTexels);
    constexpr uint32_t kStorageTexels =
        (1u << kGridBindingSortedImage) | (1u << kGridBindingCountImage) | (1u << kGridBindingStartImage);
    return {stage == kGridStageQuery ? passInfo(PassKind::GridQuery).shader : passInfo(PassKind::HashGridBuild).shader,
            kGridBindingCount, uint32_t(sizeof(HashGridPush)),
            {{kSpecGridStage, stage}, {kSpecPhotonKernel, kernel}, {kSpecSortedTexels, texels},
             {kSpecPhotonGatherCount, gatherCount}, {kSpecGatherSliceLength, sliceLength(gatherCount)}},
            0, kTexels, kStorageTexels};
}

void PhotonMap::bindStage(gpu::ComputePipeline& pipeline, bool texels) const {
    using namespace shader;
    // Stages without texels read no binding: every slot then holds the header, some valid buffer.
    std::vector<const gpu::Buffer*> list(kGridBindingCount, &header_);
    if (texels) {
        list[kGridBindingSortedTexels] = &sorted_;
        list[kGridBindingPhotonTexels] = &photons_;
        list[kGridBindingSortedImage] = &sorted_;
        list[kGridBindingCountImage] = &cellCount_;
        list[kGridBindingStartImage] = &cellStart_;
    }
    pipeline.bindBuffers(list);
}

void PhotonMap::allocate(uint64_t capacity) {
    if (capacity > (uint64_t(1) << 31))
        throw std::runtime_error(fmt::format("{} photons in one pass is more than the photon map holds (2^31)", capacity));
    capacity_ = capacity;
    tableSize_ = tableSizeFor(capacity);
    photons_ = gpu::Buffer(context_, capacity * sizeof(shader::Photon), "photons");
    sorted_ = gpu::Buffer(context_, capacity * sizeof(shader::Photon), "photons in bucket order");
    cellCount_ = gpu::Buffer(context_, uint64_t(tableSize_) * 4, "hash grid bucket counts");
    cellCount_.fill(0);  // once: after that the scan zeroes each count as it reads it
    cellStart_ = gpu::Buffer(context_, uint64_t(tableSize_) * 4, "hash grid bucket ends (after the scatter)");
    // Block totals of every scan level above the table.
    scanLevelCounts_ = {tableSize_};
    scanLevelOffsets_ = {0};
    uint64_t scratch = 0;
    while (scanLevelCounts_.back() > shader::kScanBlock) {
        uint32_t n = (scanLevelCounts_.back() + shader::kScanBlock - 1) / shader::kScanBlock;
        scanLevelOffsets_.push_back(scratch);
        scanLevelCounts_.push_back(n);
        scratch += n;
    }
    scanScratch_ = gpu::Buffer(context_, std::max<uint64_t>(scratch, 1) * 4, "hash grid scan block totals");
    ++generation_;
    // The stages are built for texels or addresses: again when the map crosses the texel limit.
    if (stages_.empty() || stagesTexels_ != texelsFit()) {
        stagesTexels_ = texelsFit();
        std::vector<gpu::PipelineDesc> stages;
        for (uint32_t stage = shader::kGridStageCount; stage <= shader::kGridStageScatter; ++stage)
            stages.push_back(stageDesc(stage, stagesTexels_));
        stages_ = gpu::createComputePipelines(context_, stages);
    }
    for (auto& stage : stages_) bindStage(*stage, stagesTexels_);
}

bool PhotonMap::texelsFit() const {
    for (const gpu::Buffer* b : {&photons_, &sorted_, &cellCount_, &cellStart_})
        if (!gpu::Buffer::texelViewFits(context_, b->size())) return false;
    return true;
}

uint64_t PhotonMap::deviceBytes() const {
    return photons_.size() + sorted_.size() + cellCount_.size() + cellStart_.size() + scanScratch_.size() + header_.size();
}

void PhotonMap::reserve(uint64_t photons) {
    if (photons > capacity_) allocate(photons);
}

void PhotonMap::shrinkTo(uint64_t photons) {
    if (photons * 3 < capacity_ * 2) allocate(std::max<uint64_t>(photons, 1));
}

void PhotonMap::beginPass(float cellSize, uint32_t powerPaths) {
    cellSize_ = cellSize;
    shader::PhotonMapHeader h{};
    h.storedCount = 0;
    h.powerPaths = powerPaths;
    h.cappedAtRound = 0xffffffffu;
    h.capacity = uint32_t(capacity_);
    h.tableSize = tableSize_;
    h.cellSize = cellSize;
    h.photonsLo = lo(photons_.address());
    h.photonsHi = hi(photons_.address());
    h.sortedLo = lo(sorted_.address());
    h.sortedHi = hi(sorted_.address());
    h.cellCountLo = lo(cellCount_.address());
    h.cellCountHi = hi(cellCount_.address());
    h.cellStartLo = lo(cellStart_.address());
    h.cellStartHi = hi(cellStart_.address());
    header_.upload(&h, sizeof(h));
}

uint64_t PhotonMap::storedCount() const {
    shader::PhotonMapHeader h{};
    header_.download(&h, sizeof(h));
    return h.storedCount;
}

shader::PhotonMapHeader PhotonMap::header() const {
    shader::PhotonMapHeader h{};
    header_.download(&h, sizeof(h));
    return h;
}

uint32_t PhotonMap::maxBucket() const {
    shader::PhotonMapHeader h{};
    header_.download(&h, sizeof(h));
    return h.maxBucket;
}

uint32_t PhotonMap::sliceLength(uint32_t gatherCount) {
    uint32_t length = shader::gatherSlicePhotons(gatherCount);
    // Test aid: TELESCOPE_GATHER_SLICE lowers it, so that small scenes gather in many slices.
    if (const char* v = std::getenv("TELESCOPE_GATHER_SLICE"); v && *v)
        length = std::clamp<uint32_t>(uint32_t(std::strtoul(v, nullptr, 10)), 1u, length);
    return length;
}

uint32_t PhotonMap::slicesFor(uint32_t photonsInBucket, uint32_t gatherCount) {
    const uint32_t slice = sliceLength(gatherCount);
    return std::max<uint32_t>(1, (photonsInBucket + slice - 1) / slice);
}

shader::HashGridPush PhotonMap::basePush() const {
    shader::HashGridPush p{};
    p.headerLo = lo(header_.address());
    p.headerHi = hi(header_.address());
    return p;
}

void PhotonMap::recordStage(gpu::CommandBatch& batch, uint32_t stage, const shader::HashGridPush& push,
                            uint64_t threads) {
    uint64_t groups = std::clamp<uint64_t>((threads + shader::kGridGroupSize - 1) / shader::kGridGroupSize, 1, kMaxGroups);
    batch.dispatch(*stages_[stage], &push, sizeof(push), uint32_t(groups), 1, 1, passName(PassKind::HashGridBuild));
}

void PhotonMap::recordBuild(gpu::CommandBatch& batch) {
    using namespace shader;
    shader::HashGridPush push = basePush();
    recordStage(batch, kGridStageCount, push, capacity_);

    // ---- Exclusive scan of the bucket counts: block scans up the levels, then adds down ----
    const VkDeviceAddress scratch = scanScratch_.address();
    auto levelAddress = [&](size_t level) {
        return level == 0 ? cellStart_.address() : scratch + scanLevelOffsets_[level] * 4;
    };
    for (size_t level = 0; level < scanLevelCounts_.size(); ++level) {
        shader::HashGridPush p = push;
        VkDeviceAddress src = level == 0 ? cellCount_.address() : levelAddress(level);
        VkDeviceAddress dst = levelAddress(level);
        VkDeviceAddress sums = level + 1 < scanLevelCounts_.size() ? levelAddress(level + 1) : 0;
        p.srcLo = lo(src), p.srcHi = hi(src), p.dstLo = lo(dst), p.dstHi = hi(dst);
        p.sumsLo = lo(sums), p.sumsHi = hi(sums);
        p.count = scanLevelCounts_[level];
        p.tableLevel = level == 0 ? 1u : 0u;
        uint32_t blocks = (p.count + kScanBlock - 1) / kScanBlock;
        batch.dispatch(*stages_[kGridStageScan], &p, sizeof(p), blocks, 1, 1, passName(PassKind::HashGridBuild));
    }
    for (size_t level = scanLevelCounts_.size() - 1; level-- > 0;) {
        shader::HashGridPush p = push;
        VkDeviceAddress dst = levelAddress(level), sums = levelAddress(level + 1);
        p.dstLo = lo(dst), p.dstHi = hi(dst), p.sumsLo = lo(sums), p.sumsHi = hi(sums);
        p.count = scanLevelCounts_[level];
        p.tableLevel = level == 0 ? 1u : 0u;
        recordStage(batch, kGridStageAdd, p, level == 0 ? p.count / 4 : p.count);
    }
    recordStage(batch, kGridStageScatter, push, capacity_);
}

void PhotonMap::recordWarmUp(gpu::CommandBatch& batch) {
    beginPass(1.0f);
    shader::HashGridPush p = basePush();
    for (uint32_t stage = shader::kGridStageCount; stage <= shader::kGridStageScatter; ++stage) {
        p.count = 0;
        batch.dispatch(*stages_[stage], &p, sizeof(p), 1, 1, 1, "warm-up");
    }
}

void PhotonMap::uploadPhotons(const std::vector<shader::Photon>& photons, float cellSize) {
    reserve(photons.size());
    beginPass(cellSize);
    photons_.upload(photons);
    shader::PhotonMapHeader h{};
    header_.download(&h, sizeof(h));
    h.storedCount = uint32_t(photons.size());
    header_.upload(&h, sizeof(h));
}

std::vector<glm::vec4> PhotonMap::query(const std::vector<glm::vec3>& positions, const std::vector<glm::vec3>& normals,
                                        float radius, float logRadius2, float logStep2, uint32_t kernel,
                                        bool byAddress) {
    shader::HashGridPush p = basePush();
    p.radius = radius;
    p.logRadius2 = logRadius2;
    p.logStep2 = logStep2;
    return runQuery(positions, normals, p, kernel, 0, byAddress);
}

std::vector<glm::vec4> PhotonMap::queryNearest(const std::vector<glm::vec3>& positions,
                                               const std::vector<glm::vec3>& normals, float radius, uint32_t k,
                                               uint32_t kernel, bool byAddress) {
    if (k == 0 || k > shader::kMaxGatherCount) throw std::invalid_argument("k nearest: k out of range");
    shader::HashGridPush p = basePush();
    p.radius = radius;
    std::vector<glm::vec4> all = runQuery(positions, normals, p, kernel, k, byAddress);
    const size_t stride = 1 + (k + 1) / 2;
    std::vector<glm::vec4> out(positions.size());
    for (size_t i = 0; i < out.size(); ++i) out[i] = all[i * stride];
    return out;
}

std::vector<glm::vec4> PhotonMap::runQuery(const std::vector<glm::vec3>& positions,
                                           const std::vector<glm::vec3>& normals, shader::HashGridPush p,
                                           uint32_t kernel, uint32_t gatherCount, bool byAddress) {
    using namespace shader;
    const bool texels = texelsFit() && !byAddress;
    const gpu::PipelineDesc d = stageDesc(kGridStageQuery, texels, kernel, gatherCount);
    gpu::ComputePipeline pipeline(context_, d.shaderName, d.bufferCount, d.pushConstantBytes, d.spec, d.uniformBindings,
                                  d.texelBindings, d.storageTexelBindings);
    bindStage(pipeline, texels);
    std::vector<glm::vec4> in(positions.size() * 2);
    for (size_t i = 0; i < positions.size(); ++i) {
        in[2 * i] = glm::vec4(positions[i], 0.0f);
        in[2 * i + 1] = glm::vec4(normals[i], 0.0f);
    }
    const size_t stride = gatherCount > 0 ? 1 + (gatherCount + 1) / 2 : 1;
    gpu::Buffer queries(context_, in.size() * sizeof(glm::vec4), "photon queries");
    gpu::Buffer results(context_, positions.size() * stride * sizeof(glm::vec4), "photon query results");
    queries.upload(in);
    p.srcLo = lo(queries.address()), p.srcHi = hi(queries.address());
    p.dstLo = lo(results.address()), p.dstHi = hi(results.address());
    p.count = uint32_t(positions.size());
    if (p.count > kMaxGroups * kGridGroupSize) throw std::invalid_argument("too many photon map queries");
    const uint32_t groups = std::max<uint32_t>(1, (p.count + kGridGroupSize - 1) / kGridGroupSize);
    {
        gpu::CommandBatch batch(context_, 32);
        batch.begin();
        recordBuild(batch);
        batch.submitAndWait();
    }
    // As many slices as the fullest bucket needs (each dispatch reads kGatherSlicePhotons photons
    // of every bucket), one submit each.
    const uint32_t slices = slicesFor(maxBucket(), gatherCount);
    for (uint32_t slice = 0; slice < slices; ++slice) {
        gpu::CommandBatch batch(context_, 1);
        batch.begin();
        p.sliceBegin = slice * sliceLength(gatherCount);
        batch.dispatch(pipeline, &p, sizeof(p), groups, 1, 1, passName(PassKind::GridQuery));
        batch.submitAndWait();
    }
    return results.downloadAll<glm::vec4>();
}

}  // namespace telescope
