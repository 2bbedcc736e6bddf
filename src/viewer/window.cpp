#include "viewer/window.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>
#include <stdexcept>

#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#include <fmt/format.h>

#include "gpu/vk_check.h"

namespace telescope::viewer {

namespace {
std::string lastGlfwError;
void onGlfwError(int, const char* description) { lastGlfwError = description ? description : "unknown error"; }

Window* owner(GLFWwindow* w) { return static_cast<Window*>(glfwGetWindowUserPointer(w)); }
}  // namespace

Window::Window(const std::string& title, int width, int height) {
    glfwSetErrorCallback(onGlfwError);  // errors become exceptions, never lines on stderr
    if (!glfwInit()) {
        const char* display = std::getenv("DISPLAY");
        std::string where = display && *display ? fmt::format("cannot open display '{}' ({})", display, lastGlfwError)
                                                : std::string("no display (DISPLAY is not set)");
        throw std::runtime_error(fmt::format(
            "view: {}; use 'telescope render' for headless output, or run the viewer under xvfb-run", where));
    }
    if (!glfwVulkanSupported()) {
        glfwTerminate();
        throw std::runtime_error("view: GLFW finds no Vulkan loader that can present to this display");
    }
    // Shrunk (keeping its shape) when the screen is smaller; the image is scaled to fit.
    const VkExtent2D screen = maxWindowSize();
    const double shrink = std::min({1.0, double(screen.width) / width, double(screen.height) / height});
    width = std::max(1, int(width * shrink));
    height = std::max(1, int(height * shrink));
    glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
    window_ = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window_) {
        std::string why = lastGlfwError;
        glfwTerminate();
        throw std::runtime_error(fmt::format("view: cannot create a {}x{} window: {}", width, height, why));
    }
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, onKey);
    glfwSetMouseButtonCallback(window_, onButton);
    glfwSetCursorPosCallback(window_, onCursor);
    glfwSetScrollCallback(window_, onScroll);
}

Window::~Window() {
    if (window_) glfwDestroyWindow(window_);
    glfwTerminate();
}

std::vector<std::string> Window::requiredInstanceExtensions() {
    uint32_t count = 0;
    const char** names = glfwGetRequiredInstanceExtensions(&count);
    if (!names) throw std::runtime_error(fmt::format("view: no Vulkan surface for this display ({})", lastGlfwError));
    return std::vector<std::string>(names, names + count);
}

VkSurfaceKHR Window::createSurface(VkInstance instance) const {
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    VK_CHECK(glfwCreateWindowSurface(instance, window_, nullptr, &surface));
    return surface;
}

bool Window::shouldClose() const { return glfwWindowShouldClose(window_); }
void Window::requestClose() { glfwSetWindowShouldClose(window_, GLFW_TRUE); }
void Window::setTitle(const std::string& title) { glfwSetWindowTitle(window_, title.c_str()); }
void Window::resize(int width, int height) {
    glfwSetWindowSize(window_, width, height);
    glfwPollEvents();  // the window system reports the new size
}

VkExtent2D Window::framebufferSize() const {
    int w = 0, h = 0;
    glfwGetFramebufferSize(window_, &w, &h);
    return {uint32_t(std::max(w, 0)), uint32_t(std::max(h, 0))};
}

VkExtent2D Window::maxWindowSize() {
    int x = 0, y = 0, w = 0, h = 0;
    if (GLFWmonitor* m = glfwGetPrimaryMonitor()) glfwGetMonitorWorkarea(m, &x, &y, &w, &h);
    if (w <= 0 || h <= 0) return {1920, 1080};
    return {uint32_t(w), uint32_t(std::max(h - 40, 64))};
}

void Window::poll(double timeout) {
    if (timeout > 0.0) glfwWaitEventsTimeout(timeout);
    else glfwPollEvents();
}

std::vector<InputEvent> Window::takeEvents() {
    std::vector<InputEvent> out(events_.begin(), events_.end());
    events_.clear();
    return out;
}

// ---- GLFW callbacks: input becomes events ----

void Window::onKey(GLFWwindow* w, int key, int, int action, int mods) {
    if (action == GLFW_PRESS || action == GLFW_REPEAT) owner(w)->push({InputEvent::Type::Key, key, mods, 0, 0.0, 0.0});
}

void Window::onButton(GLFWwindow* w, int button, int action, int mods) {
    Window* self = owner(w);
    if (action == GLFW_PRESS) {
        self->dragButton_ = button;
        self->dragMods_ = mods;
        glfwGetCursorPos(w, &self->lastX_, &self->lastY_);
    } else if (button == self->dragButton_) {
        self->dragButton_ = -1;
    }
}

void Window::onCursor(GLFWwindow* w, double x, double y) {
    Window* self = owner(w);
    if (self->dragButton_ >= 0)
        self->push({InputEvent::Type::Drag, 0, self->dragMods_, self->dragButton_, x - self->lastX_, y - self->lastY_});
    self->lastX_ = x;
    self->lastY_ = y;
}

void Window::onScroll(GLFWwindow* w, double, double dy) { owner(w)->push({InputEvent::Type::Scroll, 0, 0, 0, 0.0, dy}); }

int keyFromName(const std::string& name) {
    static const std::map<std::string, int> named = {
        {"Left", GLFW_KEY_LEFT},       {"Right", GLFW_KEY_RIGHT},      {"Up", GLFW_KEY_UP},
        {"Down", GLFW_KEY_DOWN},       {"PageUp", GLFW_KEY_PAGE_UP},   {"PageDown", GLFW_KEY_PAGE_DOWN},
        {"Home", GLFW_KEY_HOME},       {"Space", GLFW_KEY_SPACE},      {"Escape", GLFW_KEY_ESCAPE},
        {"Tab", GLFW_KEY_TAB},         {"+", GLFW_KEY_KP_ADD},         {"-", GLFW_KEY_MINUS},
        {"=", GLFW_KEY_EQUAL},         {"F1", GLFW_KEY_F1}};
    if (auto it = named.find(name); it != named.end()) return it->second;
    if (name.size() == 1) {
        char c = char(std::toupper(static_cast<unsigned char>(name[0])));
        if (c >= 'A' && c <= 'Z') return GLFW_KEY_A + (c - 'A');
        if (c >= '0' && c <= '9') return GLFW_KEY_0 + (c - '0');
    }
    return -1;
}

}  // namespace telescope::viewer
