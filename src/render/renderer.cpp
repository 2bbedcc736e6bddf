#include "render/renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <glm/gtc/constants.hpp>

#include "core/process_clock.h"

namespace telescope {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
constexpr uint32_t kMaxDispatchesPerBatch = 64;
}  // namespace

Renderer::Renderer(gpu::Context& context, const ResolvedScene& resolved, uint32_t seed, const PlanOptions& options)
    : context_(context), camera_(resolved.scene().camera), integrator_(resolved.scene().integrator), seed_(seed) {
    const Scene& scene = resolved.scene();
    auto start = Clock::now();
    gpuScene_ = buildGpuScene(scene);
    plan_ = makeRenderPlan(scene, gpuScene_.features, options);
    stats_.sceneSeconds = secondsSince(start);
    auto phase = Clock::now();

    // ---- Scene buffers ----
    auto makeBuffer = [&](const auto& v, const char* name, VkDeviceSize minBytes = 0) {
        gpu::Buffer b(context, std::max<VkDeviceSize>(v.size() * sizeof(v[0]), minBytes), name);
        b.upload(v);
        return b;
    };
    // Padded: the path tracer binds them as uniform buffers of this size too (gpu_types.h).
    prims_ = makeBuffer(gpuScene_.prims, "prims", shader::kUniformSceneBytes);
    nodes_ = makeBuffer(gpuScene_.nodes, "bvh nodes", shader::kUniformSceneBytes);
    materials_ = makeBuffer(gpuScene_.materials, "materials", shader::kUniformSceneBytes);
    lights_ = makeBuffer(gpuScene_.lights, "lights", shader::kUniformSceneBytes);
    media_ = makeBuffer(gpuScene_.media, "media", shader::kUniformSceneBytes);  // dummies without media
    gridData_ = makeBuffer(gpuScene_.gridData, "grid data");
    primMedia_ = makeBuffer(gpuScene_.primMedia, "prim media", shader::kUniformSceneBytes);
    textures_ = makeBuffer(gpuScene_.textureData, "textures");  // a dummy without textures
    environment_ = makeBuffer(gpuScene_.environment, "environment");
    shadingNormals_ = makeBuffer(gpuScene_.shadingNormals, "shading normals");  // a dummy without smooth meshes

    // ---- Accumulation: (hi, lo) vec4 pairs per channel and pixel ----
    const uint64_t pixels = uint64_t(scene.camera.width) * scene.camera.height;
    const uint64_t accumBytes = pixels * shader::kChannelCount * 2 * sizeof(glm::vec4);
    if (pixels * shader::kChannelCount * 2 >= (uint64_t(1) << 32))
        throw std::runtime_error(fmt::format("{}x{} pixels is too many for one render", scene.camera.width,
                                             scene.camera.height));
    accum_ = gpu::Buffer(context, accumBytes, "accumulation");
    accum_.fill(0);

    stats_.uploadSeconds = secondsSince(phase);
    phase = Clock::now();
    const RenderBuffers buffers{&prims_,    &nodes_,     &materials_, &lights_,   &accum_,      &media_,
                                &gridData_, &primMedia_, &textures_,  &environment_, &shadingNormals_};
    passes_ = usesPhotons(scene.integrator) ? makePhotonPasses(context, scene, plan_, buffers, seed)
                                            : makePathTracePasses(context, scene, plan_, buffers, seed);
    batch_ = std::make_unique<gpu::CommandBatch>(context, kMaxDispatchesPerBatch);
    stats_.pipelineSeconds = secondsSince(phase);
    phase = Clock::now();

    // Lavapipe compiles a pipeline at its first dispatch: empty dispatches (no samples) move that
    // cost into the setup time, out of the first batch's timing.
    batch_->begin();
    passes_->recordWarmUp(*batch_);
    batch_->submitAndWait();
    stats_.warmUpSeconds = secondsSince(phase);
    stats_.setupSeconds = secondsSince(start);
}

Renderer::~Renderer() = default;

void SamplePasses::setPilotLevel(uint32_t) {
    throw std::logic_error("this integrator has no pmf pilot");
}

PilotSums SamplePasses::pilotSums(uint64_t) const {
    throw std::logic_error("this integrator has no pmf pilot");
}

void SamplePasses::restorePending(const PendingSamples& p, uint64_t) {
    if (!p.empty()) throw std::invalid_argument("this integrator keeps no samples in progress between batches");
}

uint32_t Renderer::samplesPerUnit() const { return passes_->samplesPerUnit(); }

void Renderer::restartAtFixedLevel(uint32_t level) {
    passes_->setPilotLevel(level);
    accum_.fill(0);
    sampleIndex_ = 0;
    RenderStats kept = stats_;
    stats_ = RenderStats{};
    stats_.setupSeconds = kept.setupSeconds;
    stats_.sceneSeconds = kept.sceneSeconds;
    stats_.uploadSeconds = kept.uploadSeconds;
    stats_.pipelineSeconds = kept.pipelineSeconds;
    stats_.warmUpSeconds = kept.warmUpSeconds;
    stats_.firstSampleSeconds = kept.firstSampleSeconds;
}

bool Renderer::restartWithCamera(const Camera& camera) {
    const Camera& cam = camera_;
    if (camera.width != cam.width || camera.height != cam.height || camera.fovDegrees != cam.fovDegrees ||
        camera.medium != cam.medium || camera.filter != cam.filter)
        throw std::invalid_argument("Renderer::restartWithCamera: only the position and orientation may change");
    if (!passes_->setCamera(camera)) return false;
    camera_ = camera;
    accum_.fill(0);
    sampleIndex_ = 0;
    const double setup = stats_.setupSeconds;
    stats_ = RenderStats{};
    stats_.setupSeconds = setup;
    return true;
}

void Renderer::render(const RenderRequest& request) {
    const Camera& cam = camera_;
    const double pixels = double(cam.width) * cam.height;

    const bool timed = request.timeLimit > 0.0;
    const uint32_t perUnit = timed ? passes_->samplesPerTimedUnit() : passes_->samplesPerUnit();
    const auto start = Clock::now();
    uint64_t done = 0;
    uint32_t unitsPerBatch = 1;  // grows until a batch takes about a quarter second
    while (true) {
        double elapsed = secondsSince(start);
        // A time-limited render finishes a sample that takes several units (a block of passes).
        if (timed ? elapsed >= request.timeLimit &&
                        (!request.finishSampleAtTimeLimit || !passes_->sampleInProgress())
                  : done >= request.spp)
            break;
        if (request.stop && request.stop()) break;

        // ---- One batch: several units, one submit ----
        const uint32_t maxUnits = std::min(unitsPerBatch, passes_->maxUnitsPerBatch());
        batch_->reserve(maxUnits * passes_->dispatchesPerUnit());
        batch_->begin();
        uint64_t batchSamples = 0;
        uint32_t units = 0;
        for (; units < maxUnits; ++units) {
            uint64_t remaining = timed ? perUnit : request.spp - done - batchSamples;
            if (remaining == 0) break;
            uint32_t samples = uint32_t(std::min<uint64_t>(perUnit, remaining));
            batchSamples += passes_->recordUnit(*batch_, sampleIndex_ + batchSamples, samples);
        }
        auto batchStart = Clock::now();
        // The batch's dispatches, then those batchComplete runs itself (carried paths finished).
        std::vector<gpu::DispatchTiming> timings = batch_->submitAndWait();
        double batchSeconds = secondsSince(batchStart);
        if (stats_.firstSampleSeconds == 0.0) stats_.firstSampleSeconds = secondsSinceProcessStart();
        ++stats_.submits;
        const bool complete = passes_->batchComplete(timings);
        for (const auto& t : timings) {
            stats_.passes[t.name].dispatches++;
            stats_.passes[t.name].gpuMs += t.gpuMs;
        }
        stats_.loops = passes_->loopStats();
        if (!complete) continue;  // nothing was accumulated: run it again
        passes_->countBatch(stats_.integrator, units);
        done += batchSamples;
        sampleIndex_ += batchSamples;

        if (batchSeconds < 0.1 && unitsPerBatch < kMaxDispatchesPerBatch) unitsPerBatch *= 2;
        if (timed) {
            // Do not overshoot the time limit by more than about one unit.
            double left = request.timeLimit - secondsSince(start);
            double perUnitSeconds = batchSeconds / std::max<uint32_t>(units, 1);
            if (left > 0.0 && perUnitSeconds > 0.0)
                unitsPerBatch = std::clamp<uint32_t>(uint32_t(left / perUnitSeconds), 1, unitsPerBatch);
        }
        if (request.progress) request.progress(progressOf(request, done, secondsSince(start), pixels));
    }
    stats_.wallSeconds += secondsSince(start);
    stats_.samplesPerPixel = sampleIndex_;
}

void Renderer::setSceneVersion(const GpuScene& v, const Camera& camera) {
    const GpuScene& g = gpuScene_;
    auto put = [](gpu::Buffer& b, const auto& now, const auto& before, const char* what) {
        if (now.size() != before.size())
            throw std::invalid_argument(fmt::format("Renderer::setSceneVersion: {} differ in number", what));
        b.upload(now);
    };
    put(prims_, v.prims, g.prims, "primitives");
    put(nodes_, v.nodes, g.nodes, "BVH nodes");
    put(materials_, v.materials, g.materials, "materials");
    put(lights_, v.lights, g.lights, "lights");
    put(media_, v.media, g.media, "media");
    put(gridData_, v.gridData, g.gridData, "grid voxels");
    put(primMedia_, v.primMedia, g.primMedia, "primitive media");
    put(textures_, v.textureData, g.textureData, "texture texels");
    put(environment_, v.environment, g.environment, "environment texels");
    put(shadingNormals_, v.shadingNormals, g.shadingNormals, "shading normals");
    const Camera& cam = camera_;
    if (camera.width != cam.width || camera.height != cam.height || camera.fovDegrees != cam.fovDegrees ||
        camera.medium != cam.medium || camera.filter != cam.filter)
        throw std::invalid_argument("Renderer::setSceneVersion: only the camera's position and orientation may change");
    if (!passes_->setCamera(camera)) throw std::invalid_argument("Renderer::setSceneVersion: the passes cannot move the camera");
    camera_ = camera;
}

std::vector<glm::vec4> Renderer::renderSample(uint64_t index) {
    accum_.fill(0);
    sampleIndex_ = index;
    RenderRequest one;
    one.spp = 1;
    render(one);
    // Channel kChannelEstimate comes first: (hi, lo) pairs per pixel.
    const size_t pixels = size_t(camera_.width) * camera_.height;
    std::vector<glm::vec4> raw(pixels * 2);
    accum_.download(raw.data(), raw.size() * sizeof(glm::vec4));
    std::vector<glm::vec4> out(pixels);
    for (size_t i = 0; i < pixels; ++i) out[i] = raw[2 * i] + raw[2 * i + 1];
    return out;
}

void Renderer::resume(const Film& film) {
    const Camera& cam = camera_;
    if (sampleIndex_ != 0) throw std::logic_error("Renderer::resume after samples were rendered");
    if (film.width() != cam.width || film.height() != cam.height)
        throw std::invalid_argument(fmt::format("cannot resume a {}x{} render from a {}x{} film", cam.width,
                                                cam.height, film.width(), film.height()));
    if (film.samplesPerPixel() >= (uint64_t(1) << 32))
        throw std::invalid_argument("cannot resume: the sample index would overflow 32 bits");
    // Each double sum becomes a (hi, lo) float pair, as the compensated accumulation keeps it.
    passes_->restorePending(film.pending(), film.samplesPerPixel());
    accum_.upload(film.compensatedPairs());
    sampleIndex_ = film.samplesPerPixel();
    stats_.samplesPerPixel = sampleIndex_;
}

Film Renderer::film() const {
    const Camera& cam = camera_;
    Film film(cam.width, cam.height);
    film.setSamplesPerPixel(sampleIndex_);
    const DebiasSettings& d = integrator_.debias;
    film.setPerPixelCounts(usesPhotons(integrator_) && d.estimator != DebiasEstimator::None &&
                           d.schedule == LevelSchedule::PerPixel);
    accum_.readContents([&](const void* contents) {
        const glm::vec4* raw = static_cast<const glm::vec4*>(contents);
        for (uint32_t c = 0; c < shader::kChannelCount; ++c) {
            auto& sums = film.sums(c);
            for (size_t i = 0; i < film.pixelCount(); ++i) {
                size_t k = (c * film.pixelCount() + i) * 2;
                sums[i] = glm::dvec4(raw[k]) + glm::dvec4(raw[k + 1]);
            }
        }
    });
    film.setPending(passes_->pending());
    return film;
}

}  // namespace telescope
