// The viewer's window: GLFW (X11) set up for Vulkan presentation, and its input as a queue of
// events. Scripted events (--keys) enter the same queue, so tests drive the viewer through the
// code path a user's keys and mouse take.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

struct GLFWwindow;

namespace telescope::viewer {

struct InputEvent {
    enum class Type { Key, Drag, Scroll };
    Type type = Type::Key;
    int key = 0;     // GLFW_KEY_* (Key)
    int mods = 0;    // GLFW_MOD_* (Key, Drag)
    int button = 0;  // GLFW_MOUSE_BUTTON_* (Drag)
    double dx = 0.0, dy = 0.0;  // pixels (Drag), wheel steps in dy (Scroll)
};

// One window per process: the constructor initialises GLFW, the destructor terminates it.
class Window {
public:
    // Throws std::runtime_error with a one-line message when there is no display.
    Window(const std::string& title, int width, int height);
    ~Window();
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;

    // The instance extensions presenting to this window needs (VK_KHR_surface and the platform's).
    static std::vector<std::string> requiredInstanceExtensions();
    // A surface for the window; the caller destroys it (vkDestroySurfaceKHR) before the instance.
    VkSurfaceKHR createSurface(VkInstance instance) const;

    bool shouldClose() const;
    void requestClose();  // what the window's close button does
    void setTitle(const std::string& title);
    void resize(int width, int height);  // as a user dragging the border would
    VkExtent2D framebufferSize() const;
    // Largest window that fits the screen's work area (leaving room for decorations).
    static VkExtent2D maxWindowSize();

    // Processes window-system events, waiting up to `timeout` seconds for one when timeout > 0.
    void poll(double timeout = 0.0);
    void push(const InputEvent& e) { events_.push_back(e); }
    std::vector<InputEvent> takeEvents();

private:
    static void onKey(GLFWwindow* w, int key, int scancode, int action, int mods);
    static void onButton(GLFWwindow* w, int button, int action, int mods);
    static void onCursor(GLFWwindow* w, double x, double y);
    static void onScroll(GLFWwindow* w, double dx, double dy);

    GLFWwindow* window_ = nullptr;
    std::deque<InputEvent> events_;
    int dragButton_ = -1, dragMods_ = 0;
    double lastX_ = 0.0, lastY_ = 0.0;
};

// GLFW key code of a key name as --keys spells it ("s", "3", "Left", "PageUp", "Space", "+"),
// or -1 when there is no such key.
int keyFromName(const std::string& name);

}  // namespace telescope::viewer
