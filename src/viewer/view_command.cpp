#include "viewer/view_command.h"

#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include "session/interrupt.h"
#include "session/outputs.h"
#include "core/error.h"
#include "gpu/context.h"
#include "render/derivative.h"
#include "render/image_output.h"
#include "render/renderer.h"
#include "scene/settings_json.h"
#include "scene/scene_loader.h"
#include "shared/view_types.h"
#include "render/pmf_pilot.h"
#include "viewer/orbit_camera.h"
#include "viewer/presenter.h"
#include "viewer/screenshot.h"
#include "viewer/window.h"

namespace fs = std::filesystem;

namespace telescope::viewer {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

constexpr double kFrameBudgetSeconds = 0.08;  // rendering per frame; display and events add a few ms
constexpr uint32_t kMaxBatchSpp = 4096;

const char* kChannelNames[shader::kViewChannelCount] = {"estimate", "base", "correction", "correction_positive",
                                                        "correction_negative", "standard_error"};

// Derivative images are signed in their estimate and base too.
uint32_t channelMap(uint32_t channel, bool derivative = false) {
    if (derivative && (channel == shader::kViewEstimate || channel == shader::kViewBase)) return shader::kViewMapSigned;
    if (channel == shader::kViewCorrection) return shader::kViewMapSigned;
    if (channel == shader::kViewStandardError) return shader::kViewMapHeat;
    return shader::kViewMapTone;
}

const char* kHelp =
    "keys: 1 estimate, 2 base I(k), 3 correction (signed), 4 correction positive, 5 correction negative,\n"
    "      6 standard error, Tab next channel; + / - exposure (0.5 EV), 0 exposure 0 EV, f fit exposure;\n"
    "      Space pause/resume, r restart, s save EXR + PNG; arrows orbit, shift+arrows pan,\n"
    "      PageUp/PageDown zoom, Home the scene's camera; h help; q or Escape quit.\n"
    "mouse: left drag orbit, right drag (or shift+left) pan, wheel zoom. Moving the camera restarts the render.\n";

// The displayed quantity of a channel at a pixel, for fitting the exposure: the largest colour
// component (tone-mapped channels) or the luminance (false colour).
double displayValue(const Film& film, uint32_t channel, size_t i, bool derivative) {
    using namespace shader;
    glm::dvec3 v;
    switch (channel) {
        case kViewEstimate: v = film.mean(kChannelEstimate, i); break;
        case kViewBase: v = film.mean(kChannelBase, i); break;
        case kViewCorrection: v = film.mean(kChannelCorrection, i); break;
        case kViewCorrectionPositive: v = film.mean(kChannelCorrectionPositive, i); break;
        case kViewCorrectionNegative: v = -film.mean(kChannelCorrectionNegative, i); break;
        default: v = glm::sqrt(film.varianceOfMean(i)); break;
    }
    if (channelMap(channel, derivative) == kViewMapTone) return std::max({v.x, v.y, v.z});
    return std::abs(0.2126 * v.x + 0.7152 * v.y + 0.0722 * v.z);
}

// Distance from the camera to the point orbits turn about: the scene's look_at when it has one,
// else the centre of the scene's bounds, projected on the view direction.
float pivotDistance(const Scene& scene) {
    const auto& cam = scene.document.contains("camera") ? scene.document["camera"] : nlohmann::json();
    if (cam.is_object() && cam.contains("transform") && cam["transform"].is_object() &&
        cam["transform"].contains("look_at")) {
        const auto& l = cam["transform"]["look_at"];
        if (l.is_array() && l.size() == 3 && l[0].is_number())
            return glm::length(glm::vec3(l[0].get<float>(), l[1].get<float>(), l[2].get<float>()) - scene.camera.position);
    }
    glm::vec3 lo(3e38f), hi(-3e38f);
    for (const Geometry& g : scene.geometry) {
        const glm::vec3 r(g.radius);
        for (glm::vec3 p : {g.p0 - r, g.p0 + r}) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
        if (g.type == GeometryType::Triangle || g.type == GeometryType::Quad)
            for (glm::vec3 p : {g.p1, g.p2, g.p1 + g.p2 - g.p0}) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
    }
    if (lo.x > hi.x) return 1.0f;
    const float along = glm::dot(0.5f * (lo + hi) - scene.camera.position, scene.camera.forward);
    return std::max(along, 0.05f * glm::length(hi - lo));
}

// ---- The viewer: the Renderer, its camera, what is shown, the input ----
class Viewer {
public:
    Viewer(gpu::Context& context, Window& window, Presenter& presenter, const ResolvedScene& scene,
           const ViewOptions& options, bool quiet)
        : context_(context),
          window_(window),
          presenter_(presenter),
          sceneAsLoaded_(scene.scene()),
          options_(options),
          quiet_(quiet) {
        home_ = OrbitCamera::fromCamera(sceneAsLoaded_.camera, pivotDistance(sceneAsLoaded_));
        camera_ = home_;
        channel_ = uint32_t(channelFromName(options.channel));
        script_ = parseInputScript(options.keys);
        if (derivativeMode()) derivativeSettings_ = session::derivativeSettings(options.derivative);
        restart(false);
        if (!quiet_) {
            fmt::print("{}", describePlan(*scene_, derivative_ ? derivative_->renderer().plan() : renderer_->plan()));
            if (derivative_) fmt::print("{}", derivative_->planText());
            fmt::print(stderr, "{}", kHelp);
        }
    }

    int run() {
        while (!window_.shouldClose() && !session::InterruptGuard::requested() && (options_.frames == 0 || frame_ < options_.frames)) {
            ++frame_;
            const bool idle = paused_ || done();
            window_.poll(idle && !options_.frames ? 0.05 : 0.0);
            for (const auto& s : script_)
                if (s.frame == frame_) injectInput(s.token);
            for (const auto& e : window_.takeEvents()) handle(e);
            if (window_.shouldClose()) break;
            if (cameraMoved_) {
                restart(true);
                cameraMoved_ = false;
            }
            const auto frameStart = Clock::now();
            const bool rendered = renderBatch();
            autoFit();
            show(nullptr);
            if (rendered) frameSeconds_.push_back(secondsSince(frameStart));
            const std::string status = statusLine();
            window_.setTitle(fmt::format("telescope view - {} - {}", fs::path(scene_->path).filename().string(), status));
            if (options_.frames && !quiet_) fmt::print("frame {}: {}\n", frame_, status);
        }
        if (!options_.screenshot.empty()) screenshot(options_.screenshot);
        if (!quiet_) {
            // Frames that rendered samples: batch + display pass + present.
            std::string times;
            if (!frameSeconds_.empty()) {
                std::vector<double> t = frameSeconds_;
                std::sort(t.begin(), t.end());
                times = fmt::format(", rendering frames {:.1f} ms median, {:.1f} ms max", 1e3 * t[t.size() / 2], 1e3 * t.back());
            }
            fmt::print(stderr, "view: {} frames, {} spp{}{}\n", frame_, samples(), times,
                       session::InterruptGuard::requested() ? " (interrupted)" : "");
        }
        return 0;
    }

private:
    // Presents the current film again and writes what the swapchain image holds.
    void screenshot(const std::string& path) {
        std::vector<uint8_t> pixels;
        bool shown = false;
        for (int attempt = 0; attempt < 4 && !shown; ++attempt) shown = show(&pixels);
        if (!shown) throw std::runtime_error("view: the window could not be presented for the screenshot");
        const VkExtent2D e = presenter_.extent();
        writeScreenshotPng(path, e.width, e.height, pixels);
        if (!quiet_)
            fmt::print(stderr, "view: wrote {} ({}x{}, {}, {} spp)\n", path, e.width, e.height, channelName(channel_),
                       samples());
    }

    uint64_t samples() const {
        return derivative_ ? derivative_->film().samplesPerPixel() : renderer_->stats().samplesPerPixel;
    }
    bool derivativeMode() const { return !options_.derivative.key.empty(); }
    uint32_t map() const { return channelMap(channel_, derivativeMode()); }
    Film film() const { return derivative_ ? derivative_->film() : renderer_->film(); }
    bool done() const { return options_.spp && samples() >= options_.spp; }

    // Accumulation starts again for the current camera (an unbiased render never mixes samples
    // from two cameras): the Renderer changes its camera in place when the integrator can, else a
    // new Renderer is built. The scene document carries the camera, so a saved EXR's metadata
    // renders the same image with `telescope render`.
    void restart(bool cameraChanged) {
        moved_ = moved_ || cameraChanged;
        const Camera camera = moved_ ? camera_.apply(sceneAsLoaded_.camera) : sceneAsLoaded_.camera;
        const auto start = Clock::now();
        bool inPlace = !derivativeMode() && renderer_ && renderer_->restartWithCamera(camera);
        if (!inPlace) {
            renderer_.reset();
            scene_ = std::make_unique<Scene>(sceneAsLoaded_);
        }
        scene_->camera = camera;
        if (moved_) scene_->document["camera"]["transform"] = camera_.transformJson();
        if (derivativeMode()) {
            // A derivative render reads its versions from the document (the moved camera too):
            // a new one per camera, with its own Renderer.
            derivative_.reset();
            derivative_ = std::make_unique<DerivativeRenderer>(context_, resolved(), derivativeSettings_, options_.seed);
            derivativeAccum_ = gpu::Buffer(context_, derivative_->film().compensatedPairs().size() * sizeof(glm::vec4),
                                           "derivative display");
            derivativeAccum_.fill(0);
            inPlace = false;
        } else if (!inPlace) {
            renderer_ = std::make_unique<Renderer>(context_, resolved(), options_.seed);
        }
        restartTime_ = Clock::now();
        renderSeconds_ = 0.0;
        batchSpp_ = 1;
        if (!quiet_ && frame_ > 0)
            fmt::print(stderr, "view: restarted{} ({}, {:.0f} ms)\n", cameraChanged ? " for the new camera" : "",
                       inPlace ? "same pipelines" : "new renderer", secondsSince(start) * 1e3);
    }

    // ---- One batch of samples, sized so a frame takes about kFrameBudgetSeconds ----
    bool renderBatch() {
        if (paused_ || done()) return false;
        uint64_t n = batchSpp_;
        if (options_.spp) n = std::min<uint64_t>(n, options_.spp - samples());
        RenderRequest request;
        request.spp = n;
        const auto start = Clock::now();
        if (derivative_) {
            derivative_->render(request);
            derivativeAccum_.upload(derivative_->film().compensatedPairs());  // shown by the same display pass
        } else {
            renderer_->render(request);
        }
        const double seconds = secondsSince(start);
        renderSeconds_ += seconds;
        const double perSample = seconds / double(n);
        const double fit = perSample > 0.0 ? kFrameBudgetSeconds / perSample : double(kMaxBatchSpp);
        batchSpp_ = uint32_t(std::clamp(std::floor(fit), 1.0, std::min(2.0 * double(batchSpp_), double(kMaxBatchSpp))));
        return true;
    }

    // The false-colour channels fit their scale once, when first shown with samples.
    void autoFit() {
        if (map() != shader::kViewMapTone && !fitted_[channel_] && samples() > 0) fit();
    }

    bool show(std::vector<uint8_t>* capture) {
        const VkExtent2D win = window_.framebufferSize();
        const VkExtent2D e = presenter_.extent();
        const Camera& cam = scene_->camera;
        shader::ViewPush push{};
        push.filmWidth = cam.width;
        push.filmHeight = cam.height;
        // Fit the film into the window above the legend, centred.
        const double areaW = e.width, areaH = std::max<double>(double(e.height) - shader::kViewLegendHeight, 1.0);
        const double scale = std::min(areaW / cam.width, areaH / cam.height);
        push.pixelsPerWindowPixel = float(1.0 / scale);
        push.imageX = int(std::floor((areaW - cam.width * scale) / 2));
        push.imageY = int(std::floor((areaH - cam.height * scale) / 2));
        push.samples = uint32_t(samples());
        push.channel = channel_;
        push.map = map();
        push.scale = float(std::exp2(ev_[channel_]));
        const uint64_t accum = derivative_ ? derivativeAccum_.address() : renderer_->accumulation().address();
        return presenter_.present(push, accum, win, capture);
    }

    std::string statusLine() const {
        const double elapsed = secondsSince(restartTime_);
        const double sppPerSecond = renderSeconds_ > 0 ? double(samples()) / renderSeconds_ : 0.0;
        const double pixels = double(scene_->camera.width) * scene_->camera.height;
        std::string scale;
        const double fullScale = std::exp2(-ev_[channel_]);
        if (map() == shader::kViewMapSigned) scale = fmt::format("scale +-{:.3g} (red +, blue -)", fullScale);
        else if (map() == shader::kViewMapHeat) scale = fmt::format("scale 0..{:.3g}", fullScale);
        else scale = fmt::format("exposure {:+.1f} EV", ev_[channel_]);
        return fmt::format("{}, {} spp{}, {:.1f} spp/s ({:.2f} Mpaths/s), {:.1f} s, {}{}", channelName(channel_),
                           samples(), done() ? " (done)" : "", sppPerSecond, sppPerSecond * pixels * 1e-6, elapsed,
                           scale, paused_ ? ", paused" : "");
    }

    // ---- Input ----
    void injectInput(const std::string& token) {
        auto number = [&](const std::string& s) { return std::stod(s); };
        if (token == "shot") {
            screenshot(fmt::format("{}-{}.png", (fs::path(options_.screenshot).parent_path() /
                                                  fs::path(options_.screenshot).stem()).string(), frame_));
            return;
        }
        if (token == "interrupt") {
            raise(SIGINT);  // the handler Ctrl-C reaches
            return;
        }
        if (token.rfind("drag:", 0) == 0 || token.rfind("pan:", 0) == 0) {
            const bool pan = token[0] == 'p';
            const auto rest = token.substr(pan ? 4 : 5);
            const auto colon = rest.find(':');
            handle({InputEvent::Type::Drag, 0, 0, pan ? GLFW_MOUSE_BUTTON_RIGHT : GLFW_MOUSE_BUTTON_LEFT,
                    number(rest.substr(0, colon)), number(rest.substr(colon + 1))});
        } else if (token.rfind("resize:", 0) == 0) {
            const auto rest = token.substr(7);
            const auto colon = rest.find(':');
            window_.resize(int(number(rest.substr(0, colon))), int(number(rest.substr(colon + 1))));
        } else if (token.rfind("scroll:", 0) == 0) {
            handle({InputEvent::Type::Scroll, 0, 0, 0, 0.0, number(token.substr(7))});
        } else {
            int mods = 0;
            std::string key = token;
            if (key.rfind("shift+", 0) == 0) {
                mods = GLFW_MOD_SHIFT;
                key = key.substr(6);
            }
            handle({InputEvent::Type::Key, keyFromName(key), mods, 0, 0.0, 0.0});
        }
    }

    void handle(const InputEvent& e) {
        constexpr float kStep = 0.0872665f;  // 5 degrees
        if (e.type == InputEvent::Type::Drag) {
            const bool pan = e.button != GLFW_MOUSE_BUTTON_LEFT || (e.mods & GLFW_MOD_SHIFT);
            const float perPixel = 1.0f / float(std::max(presenter_.extent().height, 1u));
            if (pan) camera_.pan(-float(e.dx) * perPixel, float(e.dy) * perPixel);
            else camera_.orbit(-float(e.dx) * 3.0f * perPixel, float(e.dy) * 3.0f * perPixel);
            cameraMoved_ = true;
            return;
        }
        if (e.type == InputEvent::Type::Scroll) {
            camera_.zoom(std::pow(0.9f, float(e.dy)));
            cameraMoved_ = true;
            return;
        }
        const bool shift = e.mods & GLFW_MOD_SHIFT;
        switch (e.key) {
            case GLFW_KEY_1: case GLFW_KEY_2: case GLFW_KEY_3: case GLFW_KEY_4: case GLFW_KEY_5: case GLFW_KEY_6:
                channel_ = uint32_t(e.key - GLFW_KEY_1);
                break;
            case GLFW_KEY_TAB:
                channel_ = (channel_ + (shift ? shader::kViewChannelCount - 1 : 1)) % shader::kViewChannelCount;
                break;
            case GLFW_KEY_EQUAL: case GLFW_KEY_KP_ADD: ev_[channel_] += 0.5; break;
            case GLFW_KEY_MINUS: case GLFW_KEY_KP_SUBTRACT: ev_[channel_] -= 0.5; break;
            case GLFW_KEY_0: ev_[channel_] = 0.0; break;
            case GLFW_KEY_F: fit(); break;
            case GLFW_KEY_SPACE: case GLFW_KEY_P: paused_ = !paused_; break;
            case GLFW_KEY_R: restart(false); break;
            case GLFW_KEY_S: save(); break;
            case GLFW_KEY_LEFT: case GLFW_KEY_RIGHT: case GLFW_KEY_UP: case GLFW_KEY_DOWN: {
                const float sx = e.key == GLFW_KEY_LEFT ? -1.0f : e.key == GLFW_KEY_RIGHT ? 1.0f : 0.0f;
                const float sy = e.key == GLFW_KEY_DOWN ? -1.0f : e.key == GLFW_KEY_UP ? 1.0f : 0.0f;
                if (shift) camera_.pan(0.05f * sx, 0.05f * sy);
                else camera_.orbit(-kStep * sx, kStep * sy);
                cameraMoved_ = true;
                break;
            }
            case GLFW_KEY_PAGE_UP: camera_.zoom(0.9f); cameraMoved_ = true; break;
            case GLFW_KEY_PAGE_DOWN: camera_.zoom(1.0f / 0.9f); cameraMoved_ = true; break;
            case GLFW_KEY_HOME: camera_ = home_; cameraMoved_ = true; break;
            case GLFW_KEY_H: case GLFW_KEY_F1: fmt::print(stderr, "{}", kHelp); break;
            case GLFW_KEY_Q: case GLFW_KEY_ESCAPE: window_.requestClose(); break;
            default: break;
        }
    }

    // Exposure (tone-mapped channels) or scale (false colour) so the 99th percentile of the
    // displayed values maps to full brightness.
    void fit() {
        fitted_[channel_] = true;
        if (samples() == 0) return;
        const Film film = this->film();
        std::vector<double> values;
        values.reserve(film.pixelCount());
        for (size_t i = 0; i < film.pixelCount(); ++i) {
            double v = displayValue(film, channel_, i, derivativeMode());
            if (std::isfinite(v)) values.push_back(v);
        }
        if (values.empty()) return;
        auto at = values.begin() + std::ptrdiff_t(0.99 * double(values.size() - 1));
        std::nth_element(values.begin(), at, values.end());
        double top = *at > 0.0 ? *at : *std::max_element(values.begin(), values.end());
        if (top > 0.0) ev_[channel_] = -std::log2(top);
        else if (!quiet_) fmt::print(stderr, "view: {} is zero everywhere: nothing to fit\n", channelName(channel_));
    }

    // The EXR (and PNG, checkpoint) that `render` writes, with the samples shown.
    void save() {
        const Film film = this->film();
        session::OutputInfo info{scene_->path,         scene_->document.dump(),
                             derivative_ ? derivative_->description() : renderer_->plan().estimator,
                             context_.info().name,
                             derivative_ ? session::derivativeSettingsAsRun(*scene_, *derivative_) : resolvedSettings(*scene_).dump(),
                             options_.seed,        renderSeconds_};
        if (derivative_) {
            info.extra = session::derivativeMetadata(*derivative_);
            session::ImageOutputOptions exr = options_.output;
            exr.noPng = true;  // signed false colour instead
            session::writeImages(exr, film, info);
            if (!options_.output.noPng) writeSignedPngPreview(options_.output.pngPath, film);
        } else {
            session::writeImages(options_.output, film, info);
        }
        if (!quiet_) fmt::print(stderr, "view: saved {} ({} spp)\n", options_.output.exrPath, film.samplesPerPixel());
    }

    gpu::Context& context_;
    Window& window_;
    Presenter& presenter_;
    // The loaded scene with its pmfs resolved (session::resolve), and the one shown: the same with
    // the orbit's camera. A camera is not a pmf, so resolved() runs no pilot.
    const Scene sceneAsLoaded_;
    ResolvedScene resolved() const { return resolveScene(context_, *scene_, options_.seed).scene; }
    const ViewOptions options_;
    const bool quiet_;
    std::unique_ptr<Scene> scene_;
    std::unique_ptr<Renderer> renderer_;
    // --derivative: the derivative render, and its film in the accumulation's layout for display.
    DerivativeSettings derivativeSettings_;
    std::unique_ptr<DerivativeRenderer> derivative_;
    gpu::Buffer derivativeAccum_;
    std::vector<ScriptedInput> script_;
    OrbitCamera home_, camera_;
    bool moved_ = false, cameraMoved_ = false, paused_ = false;
    uint32_t channel_ = 0;
    double ev_[shader::kViewChannelCount] = {};
    bool fitted_[shader::kViewChannelCount] = {};
    uint64_t frame_ = 0;
    uint32_t batchSpp_ = 1;
    Clock::time_point restartTime_ = Clock::now();
    double renderSeconds_ = 0.0;
    std::vector<double> frameSeconds_;
};

}  // namespace

int channelFromName(const std::string& name) {
    for (uint32_t c = 0; c < shader::kViewChannelCount; ++c)
        if (name == kChannelNames[c]) return int(c);
    return -1;
}

const char* channelName(uint32_t channel) {
    return channel < shader::kViewChannelCount ? kChannelNames[channel] : "unknown";
}

std::vector<ScriptedInput> parseInputScript(const std::string& text) {
    std::vector<ScriptedInput> out;
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find(',', start);
        if (end == std::string::npos) end = text.size();
        const std::string entry = text.substr(start, end - start);
        start = end + 1;
        if (entry.empty()) continue;
        const size_t at = entry.rfind('@');
        auto bad = [&](const std::string& why) { return InputError("", "--keys", fmt::format("'{}': {}", entry, why)); };
        if (at == std::string::npos || at == 0 || at + 1 == entry.size()) throw bad("expected KEY@FRAME");
        ScriptedInput s;
        s.token = entry.substr(0, at);
        try {
            size_t used = 0;
            const long long frame = std::stoll(entry.substr(at + 1), &used);
            if (used != entry.size() - at - 1 || frame < 1) throw std::invalid_argument("frame");
            s.frame = uint64_t(frame);
        } catch (const std::exception&) {
            throw bad("the frame must be a positive integer");
        }
        const bool pointer = s.token.rfind("drag:", 0) == 0 || s.token.rfind("pan:", 0) == 0 ||
                             s.token.rfind("resize:", 0) == 0;
        if (s.token == "shot" || s.token == "interrupt") {
            // scripting only: a screenshot now (needs --screenshot), SIGINT to the viewer itself
        } else if (pointer || s.token.rfind("scroll:", 0) == 0) {
            std::string args = s.token.substr(s.token.find(':') + 1);
            const size_t colon = args.find(':');
            if (pointer == (colon == std::string::npos))
                throw bad(pointer ? "expected drag:DX:DY, pan:DX:DY or resize:W:H" : "expected scroll:N");
            for (const std::string& part : {args.substr(0, colon), colon == std::string::npos ? "0" : args.substr(colon + 1)}) {
                try {
                    size_t used = 0;
                    std::stod(part, &used);
                    if (used != part.size()) throw std::invalid_argument("number");
                } catch (const std::exception&) {
                    throw bad(fmt::format("'{}' is not a number", part));
                }
            }
        } else {
            std::string key = s.token.rfind("shift+", 0) == 0 ? s.token.substr(6) : s.token;
            if (keyFromName(key) < 0) throw bad(fmt::format("unknown key '{}'", key));
        }
        out.push_back(s);
    }
    return out;
}

namespace {

// A Context on a device that can present to the window, and the window's surface on it: the
// device asked for with --device, else the usual choice (a GPU first), else the first suitable
// device that presents (a compute-only GPU may not).
std::unique_ptr<gpu::Context> presentingContext(Window& window, gpu::ContextOptions options, VkSurfaceKHR& surface) {
    auto attempt = [&](int index) -> std::unique_ptr<gpu::Context> {
        options.deviceIndex = index;
        auto context = std::make_unique<gpu::Context>(options);
        VkSurfaceKHR s = window.createSurface(context->instance());
        VkBool32 supported = VK_FALSE;
        VkResult r = vkGetPhysicalDeviceSurfaceSupportKHR(context->physicalDevice(), context->queueFamily(), s, &supported);
        if (r == VK_SUCCESS && supported) {
            surface = s;
            return context;
        }
        vkDestroySurfaceKHR(context->instance(), s, nullptr);
        return nullptr;
    };
    if (options.deviceIndex >= 0) {
        if (auto context = attempt(options.deviceIndex)) return context;
        throw std::runtime_error(fmt::format("view: device {} cannot present to this window; choose another with "
                                             "--device (see 'telescope devices')",
                                             options.deviceIndex));
    }
    if (auto context = attempt(-1)) return context;
    for (const auto& d : gpu::Context::listDevices()) {
        if (!d.suitable) continue;
        try {
            if (auto context = attempt(int(d.index))) return context;
        } catch (const std::runtime_error&) {
            // no swapchain extension on this device: try the next
        }
    }
    throw std::runtime_error("view: no Vulkan device can present to this window; use 'telescope render' instead");
}

}  // namespace

int runView(const session::CommonOptions& common, const ViewOptions& optionsIn) {
    session::InterruptGuard interrupts;  // SIGINT / SIGTERM end the loop like closing the window
    ViewOptions o = optionsIn;

    // ---- Input first: bad input exits 2 before any window opens ----
    Scene scene = session::loadWithOverrides(common);
    if (channelFromName(o.channel) < 0)
        throw InputError("", "--channel",
                         fmt::format("unknown channel '{}' (estimate, base, correction, correction_positive, "
                                     "correction_negative, standard_error)",
                                     o.channel));
    if (!o.derivative.key.empty()) (void)session::derivativeSettings(o.derivative);  // options checked before the window
    if (o.output.exrPath.empty()) o.output.exrPath = fs::path(common.scenePath).stem().string() + "-view.exr";
    session::checkImageOutputs(o.output);
    if (!o.screenshot.empty()) session::checkOutputPath(o.screenshot, "--screenshot", ".png");
    for (const auto& s : parseInputScript(o.keys))
        if (s.token == "shot" && o.screenshot.empty())
            throw InputError("", "--keys", "'shot' writes next to the --screenshot file: give --screenshot");
    session::reportIgnoredKeys(scene, common.quiet);

    // ---- Window, then a device that presents to it ----
    const uint32_t legend = shader::kViewLegendHeight;
    Window window("telescope view", int(scene.camera.width), int(scene.camera.height + legend));
    gpu::ContextOptions contextOptions = session::contextOptions(common);
    contextOptions.instanceExtensions = Window::requiredInstanceExtensions();
    contextOptions.deviceExtensions = {VK_KHR_SWAPCHAIN_EXTENSION_NAME};
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    std::unique_ptr<gpu::Context> context = presentingContext(window, contextOptions, surface);
    Presenter presenter(*context, surface, window.framebufferSize());  // owns the surface from here
    {
        Viewer viewer(*context, window, presenter, session::resolve(*context, std::move(scene), o.seed, common.quiet), o,
                      common.quiet);
        viewer.run();
    }
    session::checkValidation(*context);
    return 0;
}

}  // namespace telescope::viewer
