#include "render/derivative.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "core/error.h"
#include "render/pmf_pilot.h"
#include "render/render_plan.h"
#include "scene/scene_loader.h"
#include "scene/scene_overrides.h"

namespace telescope {

namespace {
using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A 64-bit mix (splitmix64's finaliser): the level of a sample index from the seed.
uint64_t mix64(uint64_t z) {
    z += 0x9e3779b97f4a7c15ull;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

// Byte equality of two vectors of plain device records.
template <class T>
bool sameBytes(const std::vector<T>& a, const std::vector<T>& b) {
    return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

std::string numberText(double v) { return fmt::format("{:.17g}", v); }

// The untruncated pmf's tail P(J >= j) (scene.h's PmfSettings conventions).
double untruncatedTail(const PmfSettings& p, uint32_t j) {
    if (p.type == PmfType::Geometric) return std::pow(1.0 - double(p.r), double(j));
    return std::pow(double(j) + 1.0, double(p.alpha) - 1.0);
}

// Independent random numbers (control only): version number v renders sample s at this index.
constexpr uint64_t kIndependentStride = uint64_t(1) << 30;
}  // namespace

PmfSettings DerivativeSettings::defaultDerivativePmf() {
    PmfSettings p;
    p.type = PmfType::Geometric;
    p.r = 0.5f;
    p.origin = "default for derivatives: the recipe's p(j) ~ sqrt(V_j + E[D_j]^2) ~ 2^-j for a smooth parameter "
               "(geometric, r = 0.5)";
    return p;
}

const char* derivativeEstimatorName(DerivativeEstimator e) { return nameOf(kDerivativeEstimatorNames, e); }

DerivativeEstimator parseDerivativeEstimator(const std::string& name, const std::string& option) {
    if (const auto e = valueOf(kDerivativeEstimatorNames, name)) return *e;
    throw InputError("", option, fmt::format("unknown derivative estimator '{}' (expected {})", name,
                                             expectedNames(kDerivativeEstimatorNames)));
}

double defaultDerivativeStep(double theta, const std::string& key, double size) {
    if (key.find("position") != std::string::npos) return size / 16.0;
    if (theta != 0.0) return std::abs(theta) / 16.0;
    return 1.0 / 16.0;
}

struct DerivativeRenderer::Version {
    GpuScene gpu;
    Camera camera;
};

DerivativeRenderer::DerivativeRenderer(gpu::Context& context, const ResolvedScene& resolved,
                                       const DerivativeSettings& settings, uint32_t seed)
    : context_(context), scene_(resolved.scene()), settings_(settings), seed_(seed) {
    const Scene& scene = resolved.scene();
    const std::string& file = scene.path;
    const std::string& key = settings.key;
    parameter_.key = key;
    if (usesPhotons(scene.integrator))
        throw InputError(file, "integrator.type",
                         "derivative images need the path tracer (photon mapping's photon pass would have to be "
                         "repeated per parameter value with the same photons: not supported)");
    if (key.rfind("integrator", 0) == 0 || key.rfind("renderer", 0) == 0)
        throw InputError(file, key, "is a setting of the estimator, not a value of the scene: it has no derivative image");
    if (settings.step < 0.0 || !std::isfinite(settings.step))
        throw InputError("", "--step", fmt::format("h_0 must be a positive number, not {}", settings.step));
    if (settings.levels < 1 || settings.levels > 24)
        throw InputError("", "--derivative-levels", "expected 1 to 24 levels");

    // ---- The parameter ----
    const nlohmann::json::json_pointer pointer = overridePointer(key, file);
    if (!scene.document.contains(pointer))
        throw InputError(file, key, "no such value in the scene (a derivative needs a numeric value the scene states)");
    const nlohmann::json& v = scene.document[pointer];
    if (v.is_boolean() || !v.is_number())
        throw InputError(file, key, fmt::format("is not a number ({}): it has no derivative", v.type_name()));
    parameter_.value = v.get<double>();

    // ---- The base: roulette off ----
    scene_.integrator.russianRoulette = false;
    renderer_ = std::make_unique<Renderer>(context, resolveScene(context, scene_, seed).scene, seed);  // no pilot: explicit pmfs
    film_ = Film(scene.camera.width, scene.camera.height);

    if (settings.step > 0.0) {
        parameter_.step = settings.step;
        parameter_.stepOrigin = "given (--step)";
    } else {
        // A position's scale: the moved object's own size where its transform states a scale,
        // else the scene's extent.
        double size = renderer_->gpuScene().features.sceneExtent;
        std::string sizeOrigin = fmt::format("the scene's extent {:.4g}", size);
        if (parameter_.value != 0.0 && std::abs(parameter_.value) < size) {
            size = std::abs(parameter_.value);
            sizeOrigin = "|theta| (smaller than the scene's extent)";
        }
        if (const size_t at = key.rfind(".position"); at != std::string::npos) {
            const std::string scaleKey = key.substr(0, at) + ".scale";
            const nlohmann::json::json_pointer sp = overridePointer(scaleKey, file);
            if (scene.document.contains(sp)) {
                const nlohmann::json& sv = scene.document[sp];
                // The smallest: a step small against the object's thinnest side.
                double smallest = 0.0;
                if (sv.is_number()) smallest = std::abs(sv.get<double>());
                if (sv.is_array())
                    for (const auto& c : sv)
                        if (c.is_number() && c.get<double>() != 0.0)
                            smallest = smallest == 0.0 ? std::abs(c.get<double>()) : std::min(smallest, std::abs(c.get<double>()));
                if (smallest > 0.0) {
                    size = smallest;
                    sizeOrigin = fmt::format("the object's smallest scale {:.4g} ({})", size, scaleKey);
                }
            }
        }
        parameter_.step = defaultDerivativeStep(parameter_.value, key, size);
        parameter_.stepOrigin = key.find("position") != std::string::npos ? "default for a position: " + sizeOrigin + " / 16"
                                : parameter_.value != 0.0                   ? "default: |theta| / 16"
                                                                            : "default: 1 / 16 (theta is 0)";
    }

    // Discrete values: an integer in the document that the scene refuses half-way to the next.
    if (v.is_number_integer()) {
        try {
            (void)version(0.5);
        } catch (const InputError& e) {
            if (std::string(e.what()).find("integer") != std::string::npos)
                throw InputError(file, key, "is discrete (the scene takes only integers here): it has no derivative");
        }
        versions_.erase(0.5);
    }
    // Every offset the estimator can use must be a valid value of the scene (checked now, not
    // half-way through a render).
    (void)version(0.0);
    (void)version(parameter_.step);
    const bool symmetric = settings.estimator == DerivativeEstimator::Central ||
                           settings.estimator == DerivativeEstimator::Progressive;
    if (symmetric) (void)version(-parameter_.step);
    // theta + h must differ from theta in single precision at the finest level used.
    const double finest = parameter_.step * std::ldexp(1.0, -int(settings.levels));
    if (float(parameter_.value + finest) == float(parameter_.value))
        throw InputError(file, key,
                         fmt::format("h_0 / 2^{} = {:.3g} does not change theta = {:.9g} in single precision: give a "
                                     "larger --step or fewer --derivative-levels",
                                     settings.levels, finest, parameter_.value));
    const Version& base = version(0.0);
    const Version& up = version(parameter_.step);
    const GpuScene& a = base.gpu;
    const GpuScene& b = up.gpu;
    if (sameBytes(a.prims, b.prims) && sameBytes(a.materials, b.materials) && sameBytes(a.lights, b.lights) &&
        sameBytes(a.media, b.media) && sameBytes(a.gridData, b.gridData) && sameBytes(a.nodes, b.nodes) &&
        sameBytes(a.textureData, b.textureData) && sameBytes(a.environment, b.environment) &&
        sameBytes(a.shadingNormals, b.shadingNormals) && base.camera.position == up.camera.position &&
        base.camera.forward == up.camera.forward && base.camera.up == up.camera.up)
        throw InputError(file, key, "changing it changes nothing the renderer uses (an ignored or unused key): its "
                                    "derivative image would be 0");
    if (settings.autoPmf &&
        (settings.estimator == DerivativeEstimator::SingleTerm || settings.estimator == DerivativeEstimator::Sum))
        runPilot();
}

void DerivativeRenderer::runPilot() {
    // Every level's D_j = I(j+1) - I(j) from the same pilot samples: f(0) and f(h_k), k <= levels.
    // The pilot's sample indices lie past every render's (kIndependentStride x 3.5): its numbers
    // are independent of the render's.
    const auto start = Clock::now();
    const uint32_t J = settings_.levels;
    const double h0 = parameter_.step;
    auto h = [&](uint32_t k) { return std::ldexp(h0, -int(k)); };
    std::vector<double> offsets{0.0};
    for (uint32_t k = 0; k <= J; ++k) offsets.push_back(h(k));
    const uint64_t base = 3 * kIndependentStride + kIndependentStride / 2;
    std::vector<std::map<double, std::vector<glm::vec4>>> images(settings_.pilotSpp);
    for (double d : offsets) {
        const Version& v = version(d);
        renderer_->setSceneVersion(v.gpu, v.camera);
        current_ = d;
        for (uint32_t s = 0; s < settings_.pilotSpp; ++s) images[s][d] = renderer_->renderSample(base + s);
    }
    pilotMoments_.assign(J, 0.0);
    const size_t pixels = film_.pixelCount();
    for (uint32_t s = 0; s < settings_.pilotSpp; ++s)
        for (size_t p = 0; p < pixels; ++p) {
            auto f = [&](double d) { return glm::dvec3(images[s].at(d)[p]); };
            auto I = [&](uint32_t k) { return (f(h(k)) - f(0.0)) / h(k); };
            for (uint32_t j = 0; j < J; ++j) {
                const glm::dvec3 dj = I(j + 1) - I(j);
                const double m = glm::dot(dj, dj) / 3.0;
                if (std::isfinite(m)) pilotMoments_[j] += m / double(settings_.pilotSpp);
            }
        }
    // The recipe: p(j) ~ sqrt(M_j); a level the pilot saw no difference at keeps a floor of 1e-3
    // of the largest weight, so that every level stays possible (unbiased).
    table_.assign(J, 0.0);
    double largest = 0.0, total = 0.0;
    for (uint32_t j = 0; j < J; ++j) largest = std::max(largest, std::sqrt(pilotMoments_[j]));
    for (uint32_t j = 0; j < J; ++j) {
        table_[j] = largest > 0.0 ? std::max(std::sqrt(pilotMoments_[j]), 1e-3 * largest) : 1.0;
        total += table_[j];
    }
    for (double& t : table_) t /= total;
    pilotSeconds_ = secondsSince(start);
}

double DerivativeRenderer::predictedSecondMoment(bool defaultPmf) const {
    if (pilotMoments_.empty()) return 0.0;
    const PmfSettings def = DerivativeSettings::defaultDerivativePmf();
    const double below = 1.0 - untruncatedTail(def, settings_.levels);
    double sum = 0.0;
    for (uint32_t j = 0; j < pilotMoments_.size(); ++j) {
        const double p = defaultPmf ? (untruncatedTail(def, j) - untruncatedTail(def, j + 1)) / below : levelProbability(j);
        sum += pilotMoments_[j] / p;
    }
    return sum;
}

DerivativeRenderer::~DerivativeRenderer() = default;

const DerivativeRenderer::Version& DerivativeRenderer::version(double delta) {
    if (auto it = versions_.find(delta); it != versions_.end()) return *it->second;
    const auto start = Clock::now();
    const std::string& file = scene_.path;
    const std::string& key = settings_.key;
    const double value = parameter_.value + delta;
    Scene s;
    try {
        const std::string dir = std::filesystem::path(file).parent_path().string();
        s = loadSceneFromString(scene_.document.dump(), file, dir.empty() ? "." : dir, {{key, numberText(value)}});
    } catch (const InputError& e) {
        throw InputError(file, key,
                         fmt::format("the scene refuses the value {:.9g} = theta {} {:.3g} ({}); give a smaller --step",
                                     value, delta < 0 ? "-" : "+", std::abs(delta), e.what()));
    }
    s.integrator = scene_.integrator;
    auto out = std::make_unique<Version>();
    out->gpu = buildGpuScene(s);
    out->camera = s.camera;

    // ---- Same plan, same buffers, same discrete decisions ----
    const GpuScene& base = renderer_->gpuScene();
    const RenderPlan plan = makeRenderPlan(s, out->gpu.features);
    const RenderPlan& basePlan = renderer_->plan();
    auto refuse = [&](const std::string& what) {
        throw InputError(file, key, fmt::format("theta {} {:.3g} changes {}: the versions of a derivative render share one "
                                                "plan and buffer layout",
                                                delta < 0 ? "-" : "+", std::abs(delta), what));
    };
    if (plannedEntry(plan, PassKind::PathTrace).shader != plannedEntry(basePlan, PassKind::PathTrace).shader)
        refuse("the path tracer's shader");
    for (size_t i = 0; i < plan.pathTraceSpec.size() && i < basePlan.pathTraceSpec.size(); ++i) {
        const auto& a = plan.pathTraceSpec[i];
        const auto& b = basePlan.pathTraceSpec[i];
        // The ray offset follows the scene's extent: the base's serves every version.
        if (a.id == shader::kSpecRayEpsilon) continue;
        if (a.id != b.id || a.value != b.value) refuse(fmt::format("the render plan (specialisation constant {})", a.id));
    }
    const GpuScene& g = out->gpu;
    if (g.prims.size() != base.prims.size() || g.nodes.size() != base.nodes.size() ||
        g.materials.size() != base.materials.size() || g.lights.size() != base.lights.size() ||
        g.media.size() != base.media.size() || g.gridData.size() != base.gridData.size() ||
        g.primMedia.size() != base.primMedia.size() || g.textureData.size() != base.textureData.size() ||
        g.environment.size() != base.environment.size() || g.shadingNormals.size() != base.shadingNormals.size())
        refuse("the size of the scene's buffers");
    const Camera& c = scene_.camera;
    if (s.camera.width != c.width || s.camera.height != c.height || s.camera.fovDegrees != c.fovDegrees ||
        s.camera.medium != c.medium || s.camera.filter != c.filter)
        refuse("the camera's resolution, field of view, medium or filter (only its position and orientation may vary)");
    // Lights are picked with the base's probabilities in every version (a light's power may be the
    // parameter): the same random number picks the same light.
    for (size_t i = 0; i < g.lights.size(); ++i) {
        out->gpu.lights[i].pmf = base.lights[i].pmf;
        out->gpu.lights[i].cdf = base.lights[i].cdf;
    }
    versionSeconds_ += secondsSince(start);
    return *versions_.emplace(delta, std::move(out)).first->second;
}

double DerivativeRenderer::levelTail(uint32_t j) const {
    if (!table_.empty()) {
        double tail = 0.0;
        for (uint32_t i = j; i < table_.size(); ++i) tail += table_[i];
        return tail;
    }
    const double below = 1.0 - untruncatedTail(settings_.pmf, settings_.levels);
    return (untruncatedTail(settings_.pmf, j) - untruncatedTail(settings_.pmf, settings_.levels)) / below;
}

double DerivativeRenderer::levelProbability(uint32_t j) const {
    if (j >= settings_.levels) return 0.0;
    if (!table_.empty()) return table_[j];
    return levelTail(j) - levelTail(j + 1);
}

uint32_t DerivativeRenderer::drawLevel(uint64_t sample) const {
    const double u = double(mix64((uint64_t(seed_) << 32) ^ sample ^ 0xD1FFull << 48) >> 11) * 0x1.0p-53;
    uint32_t j = 0;
    double tail = 1.0;  // P(J >= j+1) of the truncated pmf, falling
    while (j + 1 < settings_.levels) {
        tail = levelTail(j + 1);
        if (u >= tail) break;
        ++j;
    }
    return j;
}

std::vector<double> DerivativeRenderer::offsetsOf(uint64_t sample, uint32_t* level) const {
    const double h0 = parameter_.step;
    auto h = [&](uint32_t k) { return std::ldexp(h0, -int(k)); };
    uint32_t j = 0;
    std::vector<double> out;
    switch (settings_.estimator) {
    case DerivativeEstimator::Forward: out = {0.0, h0}; break;
    case DerivativeEstimator::Central: out = {-h0, h0}; break;
    case DerivativeEstimator::SingleTerm:
        j = drawLevel(sample);
        out = {0.0, h0, h(j), h(j + 1)};
        break;
    case DerivativeEstimator::Sum:
        j = drawLevel(sample);
        out = {0.0};
        for (uint32_t i = 0; i <= j + 1; ++i) out.push_back(h(i));
        break;
    case DerivativeEstimator::Progressive:
        j = std::min<uint32_t>(uint32_t(std::floor(std::log2(double(sample) + 1.0) / 3.0)), settings_.levels);
        out = {-h(j), h(j)};
        break;
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    if (level) *level = j;
    return out;
}

void DerivativeRenderer::addSample(uint64_t sample, const std::map<double, std::vector<glm::vec4>>& images) {
    uint32_t j = 0;
    (void)offsetsOf(sample, &j);
    const double h0 = parameter_.step;
    auto h = [&](uint32_t k) { return std::ldexp(h0, -int(k)); };
    const size_t pixels = film_.pixelCount();
    auto& est = film_.sums(shader::kChannelEstimate);
    auto& sq = film_.sums(shader::kChannelEstimateSq);
    auto& baseSum = film_.sums(shader::kChannelBase);
    auto& corr = film_.sums(shader::kChannelCorrection);
    auto& pos = film_.sums(shader::kChannelCorrectionPositive);
    auto& neg = film_.sums(shader::kChannelCorrectionNegative);
    const bool shifted = settings_.control == DerivativeControl::ShiftedPmf;
    for (size_t p = 0; p < pixels; ++p) {
        bool dropped = false;
        auto f = [&](double delta) {
            const glm::vec4 v = images.at(delta)[p];
            if (v.w != 0.0f) dropped = true;
            return glm::dvec3(v);
        };
        auto I = [&](uint32_t k) { return (f(h(k)) - f(0.0)) / h(k); };
        glm::dvec3 base(0.0), c(0.0);
        switch (settings_.estimator) {
        case DerivativeEstimator::Forward: base = I(0); break;
        case DerivativeEstimator::Central: base = (f(h0) - f(-h0)) / (2.0 * h0); break;
        case DerivativeEstimator::SingleTerm:
            base = I(0);
            c = (I(j + 1) - I(j)) / levelProbability(shifted ? j + 1 : j);
            break;
        case DerivativeEstimator::Sum:
            base = I(0);
            for (uint32_t i = 0; i <= j; ++i) c += (I(i + 1) - I(i)) / levelTail(shifted ? i + 1 : i);
            break;
        case DerivativeEstimator::Progressive: base = (f(h(j)) - f(-h(j))) / (2.0 * h(j)); break;
        }
        const glm::dvec3 z = base + c;
        if (dropped || !std::isfinite(z.x) || !std::isfinite(z.y) || !std::isfinite(z.z)) {
            est[p].w += 1.0;
            continue;
        }
        est[p] += glm::dvec4(z, 0.0);
        sq[p] += glm::dvec4(z * z, 0.0);
        baseSum[p] += glm::dvec4(base, 0.0);
        corr[p] += glm::dvec4(c, 0.0);
        pos[p] += glm::dvec4(glm::max(c, glm::dvec3(0.0)), 0.0);
        neg[p] += glm::dvec4(glm::min(c, glm::dvec3(0.0)), 0.0);
    }
}

void DerivativeRenderer::resume(const Film& film) {
    if (nextSample_ != 0) throw std::logic_error("DerivativeRenderer::resume after samples were rendered");
    if (film.width() != film_.width() || film.height() != film_.height())
        throw std::invalid_argument(fmt::format("cannot resume a {}x{} derivative render from a {}x{} film", film_.width(),
                                                film_.height(), film.width(), film.height()));
    film_ = film;
    nextSample_ = film.samplesPerPixel();
}

void DerivativeRenderer::restart(DerivativeControl control) {
    settings_.control = control;
    film_ = Film(film_.width(), film_.height());
    nextSample_ = 0;
}

void DerivativeRenderer::render(const RenderRequest& request) {
    const auto start = Clock::now();
    const bool timed = request.timeLimit > 0.0;
    const size_t pixels = film_.pixelCount();
    // Samples evaluated together: each version is uploaded once per batch; their images are kept
    // (at most ~64 MiB of them).
    const uint64_t batchMax = std::clamp<uint64_t>((uint64_t(64) << 20) / (pixels * sizeof(glm::vec4) * 4), 1, 32);
    uint64_t done = 0;
    uint64_t timedBatch = 1;  // a timed render's batch doubles while a batch takes under 0.1 s
    while (timed ? secondsSince(start) < request.timeLimit : done < request.spp) {
        if (request.stop && request.stop()) break;
        const auto batchStart = Clock::now();
        const uint64_t n = timed ? timedBatch : std::min(batchMax, request.spp - done);
        if (nextSample_ + n >= kIndependentStride) throw std::runtime_error("derivative render: too many samples");
        // Which samples need which version.
        std::map<double, std::vector<uint64_t>> needs;
        for (uint64_t s = nextSample_; s < nextSample_ + n; ++s)
            for (double d : offsetsOf(s)) needs[d].push_back(s);
        std::vector<std::map<double, std::vector<glm::vec4>>> images(n);
        uint64_t ordinal = 0;
        for (const auto& [delta, samples] : needs) {
            if (delta != current_) {
                const Version& v = version(delta);
                const auto up = Clock::now();
                renderer_->setSceneVersion(v.gpu, v.camera);
                versionSeconds_ += secondsSince(up);
                current_ = delta;
            }
            const uint64_t offset =
                settings_.control == DerivativeControl::IndependentNumbers ? (ordinal % 3 + 1) * kIndependentStride : 0;
            for (uint64_t s : samples) {
                images[s - nextSample_][delta] = renderer_->renderSample(s + offset);
                ++evaluations_;
            }
            ++ordinal;
        }
        for (uint64_t i = 0; i < n; ++i) addSample(nextSample_ + i, images[i]);
        if (timed && secondsSince(batchStart) < 0.1) timedBatch = std::min(batchMax, timedBatch * 2);
        nextSample_ += n;
        done += n;
        film_.setSamplesPerPixel(nextSample_);
        if (request.progress) request.progress(progressOf(request, done, secondsSince(start), double(pixels)));
    }
    seconds_ += secondsSince(start);
}

std::string DerivativeRenderer::pmfText() const {
    if (table_.empty()) return pmfDescription(settings_.pmf);
    std::string t;
    for (double p : table_) t += fmt::format("{}{:.4g}", t.empty() ? "" : " ", p);
    return fmt::format("pmf \"auto\" (the recipe p(j) ~ sqrt(E[D_j^2]) from a {}-spp pilot): p = {}", settings_.pilotSpp, t);
}

std::string DerivativeRenderer::description() const {
    const DerivativeParameter& p = parameter_;
    std::string how;
    switch (settings_.estimator) {
    case DerivativeEstimator::Forward: how = "forward difference (f(h_0) - f(0)) / h_0, biased"; break;
    case DerivativeEstimator::Central: how = "central difference (f(h_0) - f(-h_0)) / (2 h_0), biased"; break;
    case DerivativeEstimator::SingleTerm:
        how = fmt::format("single-term I(0) + (I(j+1) - I(j)) / p(j), I(k) the forward difference at h_0 2^-k, levels "
                          "0..{}, {}", settings_.levels - 1, pmfText());
        break;
    case DerivativeEstimator::Sum:
        how = fmt::format("Russian-roulette sum I(0) + sum_(i<=j) (I(i+1) - I(i)) / P(J >= i), levels 0..{}, {}",
                          settings_.levels - 1, pmfText());
        break;
    case DerivativeEstimator::Progressive:
        how = fmt::format("progressive central differences at h_0 2^-k, k = floor(log2(s+1) / 3) at sample s (h ~ "
                          "s^-1/3), at most {}: consistent", settings_.levels);
        break;
    }
    if (settings_.control == DerivativeControl::ShiftedPmf) how += " (TEST ONLY: 1 / p(j+1) where 1 / p(j) belongs)";
    if (settings_.control == DerivativeControl::IndependentNumbers) how += " (TEST ONLY: independent random numbers)";
    return fmt::format("derivative d/d({}) at theta = {:.9g}, h_0 = {:.6g}: {}; each evaluation: {}", p.key, p.value,
                       p.step, how, renderer_->plan().estimator);
}

std::string DerivativeRenderer::planText() const {
    const DerivativeParameter& p = parameter_;
    std::string s = fmt::format("derivative:\n  parameter   {} = {:.9g}\n  h_0         {:.6g} ({})\n  estimator   {}\n",
                                p.key, p.value, p.step, p.stepOrigin, derivativeEstimatorName(settings_.estimator));
    double evals = 0.0;
    switch (settings_.estimator) {
    case DerivativeEstimator::Forward:
    case DerivativeEstimator::Central:
    case DerivativeEstimator::Progressive: evals = 2.0; break;
    case DerivativeEstimator::SingleTerm:
        evals = 2.0 + 2.0 * (1.0 - levelProbability(0)) + levelProbability(0);
        break;
    case DerivativeEstimator::Sum:
        for (uint32_t j = 0; j < settings_.levels; ++j) evals += levelProbability(j) * (j + 3.0);
        break;
    }
    if (settings_.estimator == DerivativeEstimator::SingleTerm || settings_.estimator == DerivativeEstimator::Sum)
        s += fmt::format("  pmf         {}, truncated to levels 0..{} (unbiased for the forward difference at "
                         "h_0 / 2^{} = {:.3g})\n",
                         pmfText(), settings_.levels - 1, settings_.levels, std::ldexp(p.step, -int(settings_.levels)));
    if (!pilotMoments_.empty()) {
        std::string moments;
        for (double m : pilotMoments_) moments += fmt::format("{}{:.3g}", moments.empty() ? "" : " ", m);
        s += fmt::format("  pilot       {} spp x {} renders in {:.2f} s; E[D_j^2] summed over pixels, j = 0..{}: {}\n",
                         settings_.pilotSpp, settings_.levels + 2, pilotSeconds_, settings_.levels - 1, moments);
        const double chosen = predictedSecondMoment(false), geometric = predictedSecondMoment(true);
        s += fmt::format("  predicted   correction's second moment sum_j E[D_j^2] / p(j): {:.4g} with this pmf, {:.4g} "
                         "with geometric r = 0.5 (equal work per sample)\n",
                         chosen, geometric);
        // Growth from the first levels on (visibility: E[D_j^2] ~ 2^j) means infinite variance; growth
        // after a fall is single-precision rounding (E[D_j^2] ~ 4^j eps^2 / h_0^2).
        const std::vector<double>& m = pilotMoments_;
        if (m.size() >= 3 && m[1] > 1.5 * m[0] && m[2] > 1.5 * m[1]) {
            s += "  warning     E[D_j^2] grows from the first levels on (an edge of visibility moves?): the unbiased "
                 "forms have infinite variance here; use the progressive estimator\n";
        } else if (m.size() >= 3) {
            const size_t low = size_t(std::min_element(m.begin(), m.end()) - m.begin());
            if (low + 1 < m.size() && m.back() > 4.0 * m[low])
                s += fmt::format("  note        E[D_j^2] is smallest at level {} and grows beyond it (single-precision "
                                 "rounding): --derivative-levels {} would cut the variance, at a bias O(h_0 / 2^{})\n",
                                 low, low + 1, low + 1);
        }
    }
    if (settings_.estimator == DerivativeEstimator::Progressive)
        s += fmt::format("  schedule    h = h_0 2^-floor(log2(s+1)/3) at sample s, down to h_0 / 2^{}\n", settings_.levels);
    s += fmt::format("  passes      {:.2f} path_trace evaluations per sample (expected), each with the same random "
                     "numbers; the level is drawn per sample index, shared by all pixels\n",
                     evals);
    s += "  decisions   Russian roulette off; lights picked with the base scene's probabilities\n";
    return s;
}

}  // namespace telescope
