#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>

namespace telescope {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
constexpr uint32_t kMaxDispatchesPerBatch = 64;
}  // namespace

Renderer::Renderer(gpu::Context& context, const Scene& scene, uint32_t seed)
    : context_(context), scene_(scene), seed_(seed) {
    auto start = Clock::now();
    if (scene.integrator.debias.estimator != DebiasEstimator::None && scene.integrator.debias.pmf.type == PmfType::Auto)
        throw std::logic_error("the auto pmf must be resolved by a pilot (resolveAutoPmf) before rendering");
    gpuScene_ = buildGpuScene(scene);
    plan_ = makeRenderPlan(scene, gpuScene_.features);

    // ---- Scene buffers ----
    auto makeBuffer = [&](const auto& v, const char* name) {
        gpu::Buffer b(context, v.size() * sizeof(v[0]), name);
        b.upload(v);
        return b;
    };
    prims_ = makeBuffer(gpuScene_.prims, "prims");
    nodes_ = makeBuffer(gpuScene_.nodes, "bvh nodes");
    materials_ = makeBuffer(gpuScene_.materials, "materials");
    lights_ = makeBuffer(gpuScene_.lights, "lights");
    media_ = makeBuffer(gpuScene_.media, "media");
    gridData_ = makeBuffer(gpuScene_.gridData, "grid data");
    primMedia_ = makeBuffer(gpuScene_.primMedia, "prim media");

    // ---- Accumulation: (hi, lo) vec4 pairs per channel and pixel ----
    const uint64_t pixels = uint64_t(scene.camera.width) * scene.camera.height;
    const uint64_t accumBytes = pixels * shader::kChannelCount * 2 * sizeof(glm::vec4);
    if (pixels * shader::kChannelCount * 2 >= (uint64_t(1) << 32))
        throw std::runtime_error(fmt::format("{}x{} pixels is too many for one render", scene.camera.width,
                                             scene.camera.height));
    accum_ = gpu::Buffer(context, accumBytes, "accumulation");
    accum_.fill(0);

    pathTrace_ = std::make_unique<gpu::ComputePipeline>(context, "path_trace", shader::kPathTraceBindingCount,
                                                        uint32_t(sizeof(shader::PathTracePush)), plan_.pathTraceSpec);
    pathTrace_->bindBuffers({&prims_, &nodes_, &materials_, &lights_, &media_, &gridData_, &primMedia_});
    if (plan_.levelSchedule == LevelSchedule::Queued) {
        // ---- Level queue: header, items, two vec4 results per item (see gpu_types.h) ----
        const uint64_t capacity = pixels * samplesPerDispatch();
        if (capacity >= (uint64_t(1) << 27))
            throw std::runtime_error(fmt::format("{}x{} pixels is too many for the queued level schedule",
                                                 scene.camera.width, scene.camera.height));
        queueCapacity_ = uint32_t(capacity);
        auto align4 = [](uint64_t n) { return (n + 3) / 4 * 4; };
        const uint64_t chunks = (capacity + shader::kLevelChunk - 1) / shader::kLevelChunk;
        const uint64_t bytes = (align4(chunks * shader::kLevelBuckets) + align4(capacity)) * 4 + capacity * 32;
        levelQueue_ = gpu::Buffer(context, bytes, "level queue");
        levelQueue_.fill(0);
        const uint32_t pushBytes = uint32_t(sizeof(shader::PathTracePush));
        levelCount_ = std::make_unique<gpu::ComputePipeline>(context, "level_count", 0, pushBytes, plan_.pathTraceSpec);
        levelScan_ = std::make_unique<gpu::ComputePipeline>(context, "level_scan", 0, pushBytes, plan_.pathTraceSpec);
        levelScatter_ =
            std::make_unique<gpu::ComputePipeline>(context, "level_scatter", 0, pushBytes, plan_.pathTraceSpec);
        pathResolve_ = std::make_unique<gpu::ComputePipeline>(context, "path_resolve", 0, pushBytes, plan_.pathTraceSpec);
    }
    batch_ = std::make_unique<gpu::CommandBatch>(context, kMaxDispatchesPerBatch * passesPerStep());

    // Lavapipe compiles a pipeline at its first dispatch: an empty dispatch (no samples) moves
    // that cost into the setup time, out of the first batch's timing.
    shader::PathTracePush warm{};
    warm.width = scene.camera.width;
    warm.height = scene.camera.height;
    warm.accumAddressLo = uint32_t(accum_.address());
    warm.accumAddressHi = uint32_t(accum_.address() >> 32);
    if (levelCount_) {
        warm.queueAddressLo = uint32_t(levelQueue_.address());
        warm.queueAddressHi = uint32_t(levelQueue_.address() >> 32);
        warm.queueCapacity = queueCapacity_;
    }
    batch_->begin();
    recordStep(warm, 1, 1);
    batch_->submitAndWait();
    stats_.setupSeconds = secondsSince(start);
}

Renderer::~Renderer() = default;

void Renderer::recordStep(const shader::PathTracePush& push, uint32_t groupsX, uint32_t groupsY) {
    const char* name = push.sampleCount ? "path_trace" : "warm-up";
    if (!levelCount_) {
        batch_->dispatch(*pathTrace_, &push, sizeof(push), groupsX, groupsY, 1, name);
        return;
    }
    // ---- Queued schedule: sort this step's (pixel, sample) items by level, trace, resolve ----
    const uint64_t items = uint64_t(push.width) * push.height * push.sampleCount;
    const uint64_t chunks = (items + shader::kLevelChunk - 1) / shader::kLevelChunk;
    const uint32_t itemGroups =
        uint32_t(std::max<uint64_t>((chunks + shader::kLevelQueueGroupSize - 1) / shader::kLevelQueueGroupSize, 1));
    const bool warm = push.sampleCount == 0;
    batch_->dispatch(*levelCount_, &push, sizeof(push), itemGroups, 1, 1, warm ? "warm-up" : "level_count");
    batch_->dispatch(*levelScan_, &push, sizeof(push), 1, 1, 1, warm ? "warm-up" : "level_scan");
    batch_->dispatch(*levelScatter_, &push, sizeof(push), itemGroups, 1, 1, warm ? "warm-up" : "level_scatter");
    batch_->dispatch(*pathTrace_, &push, sizeof(push), groupsX, groupsY, 1, name);
    batch_->dispatch(*pathResolve_, &push, sizeof(push), groupsX, groupsY, 1, warm ? "warm-up" : "path_resolve");
}

uint32_t Renderer::samplesPerDispatch() const {
    // About a million paths per dispatch, at most 16 samples per pixel in one thread.
    uint64_t pixels = uint64_t(scene_.camera.width) * scene_.camera.height;
    return uint32_t(std::clamp<uint64_t>((1u << 20) / std::max<uint64_t>(pixels, 1), 1, 16));
}

void Renderer::render(const RenderRequest& request) {
    const Camera& cam = scene_.camera;
    shader::PathTracePush push{};
    push.cameraPosition = cam.position;
    push.cameraRight = cam.right;
    push.cameraUp = cam.up;
    push.cameraForward = cam.forward;
    push.planeDistance = 1.0f / std::tan(0.5f * glm::radians(cam.fovDegrees));
    push.width = cam.width;
    push.height = cam.height;
    push.seed = seed_;
    push.pilotLevel = scene_.integrator.pilotLevel;
    push.accumAddressLo = uint32_t(accum_.address());
    push.accumAddressHi = uint32_t(accum_.address() >> 32);
    if (levelCount_) {
        push.queueAddressLo = uint32_t(levelQueue_.address());
        push.queueAddressHi = uint32_t(levelQueue_.address() >> 32);
        push.queueCapacity = queueCapacity_;
    }
    const uint32_t groupsX = (cam.width + shader::kPathTraceGroupSize - 1) / shader::kPathTraceGroupSize;
    const uint32_t groupsY = (cam.height + shader::kPathTraceGroupSize - 1) / shader::kPathTraceGroupSize;
    const uint32_t perDispatch = samplesPerDispatch();
    const double pixels = double(cam.width) * cam.height;

    const bool timed = request.timeLimit > 0.0;
    const auto start = Clock::now();
    uint64_t done = 0;
    uint32_t dispatchesPerBatch = 1;  // grows until a batch takes about a quarter second
    while (true) {
        double elapsed = secondsSince(start);
        if (timed ? elapsed >= request.timeLimit : done >= request.spp) break;

        // ---- One batch: several dispatches, one submit ----
        batch_->begin();
        uint64_t batchSamples = 0;
        for (uint32_t d = 0; d < dispatchesPerBatch; ++d) {
            uint64_t remaining = timed ? perDispatch : request.spp - done - batchSamples;
            if (remaining == 0) break;
            push.sampleBase = uint32_t(sampleIndex_ + batchSamples);
            push.sampleCount = uint32_t(std::min<uint64_t>(perDispatch, remaining));
            recordStep(push, groupsX, groupsY);
            batchSamples += push.sampleCount;
        }
        auto batchStart = Clock::now();
        auto timings = batch_->submitAndWait();
        double batchSeconds = secondsSince(batchStart);
        ++stats_.submits;
        for (const auto& t : timings) {
            stats_.passes[t.name].dispatches++;
            stats_.passes[t.name].gpuMs += t.gpuMs;
        }
        done += batchSamples;
        sampleIndex_ += batchSamples;

        if (batchSeconds < 0.1 && dispatchesPerBatch < kMaxDispatchesPerBatch) dispatchesPerBatch *= 2;
        if (timed) {
            // Do not overshoot the time limit by more than about one batch.
            double left = request.timeLimit - secondsSince(start);
            double perDispatchSeconds = batchSeconds / std::max<size_t>(timings.size() / passesPerStep(), 1);
            if (left > 0.0 && perDispatchSeconds > 0.0)
                dispatchesPerBatch = std::clamp<uint32_t>(uint32_t(left / perDispatchSeconds), 1, dispatchesPerBatch);
        }
        if (request.progress) {
            RenderProgress p;
            p.samplesDone = done;
            p.samplesTarget = timed ? 0 : request.spp;
            p.seconds = secondsSince(start);
            p.timeLimit = request.timeLimit;
            p.pathsPerSecond = p.seconds > 0.0 ? double(done) * pixels / p.seconds : 0.0;
            request.progress(p);
        }
    }
    stats_.wallSeconds += secondsSince(start);
    stats_.samplesPerPixel = sampleIndex_;
}

void Renderer::resume(const Film& film) {
    const Camera& cam = scene_.camera;
    if (sampleIndex_ != 0) throw std::logic_error("Renderer::resume after samples were rendered");
    if (film.width() != cam.width || film.height() != cam.height)
        throw std::invalid_argument(fmt::format("cannot resume a {}x{} render from a {}x{} film", cam.width,
                                                cam.height, film.width(), film.height()));
    if (film.samplesPerPixel() >= (uint64_t(1) << 32))
        throw std::invalid_argument("cannot resume: the sample index would overflow 32 bits");
    // Each double sum becomes a (hi, lo) float pair, as the compensated accumulation keeps it.
    std::vector<glm::vec4> raw(film.pixelCount() * shader::kChannelCount * 2);
    for (uint32_t c = 0; c < shader::kChannelCount; ++c) {
        const auto& sums = film.sums(c);
        for (size_t i = 0; i < film.pixelCount(); ++i) {
            size_t k = (c * film.pixelCount() + i) * 2;
            raw[k] = glm::vec4(sums[i]);
            raw[k + 1] = glm::vec4(sums[i] - glm::dvec4(raw[k]));
        }
    }
    accum_.upload(raw);
    sampleIndex_ = film.samplesPerPixel();
    stats_.samplesPerPixel = sampleIndex_;
}

Film Renderer::film() const {
    const Camera& cam = scene_.camera;
    Film film(cam.width, cam.height);
    film.setSamplesPerPixel(sampleIndex_);
    std::vector<glm::vec4> raw(film.pixelCount() * shader::kChannelCount * 2);
    accum_.download(raw.data(), raw.size() * sizeof(glm::vec4));
    for (uint32_t c = 0; c < shader::kChannelCount; ++c) {
        auto& sums = film.sums(c);
        for (size_t i = 0; i < film.pixelCount(); ++i) {
            size_t k = (c * film.pixelCount() + i) * 2;
            sums[i] = glm::dvec4(raw[k]) + glm::dvec4(raw[k + 1]);
        }
    }
    return film;
}

}  // namespace telescope
