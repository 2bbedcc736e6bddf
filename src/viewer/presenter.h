// Presents a channel of the Renderer's film in the window through a Vulkan swapchain.
//
// Each frame: the display pass (shaders/view_display.comp) maps the accumulation to 8-bit colour
// in a buffer of window size, the buffer is copied into the acquired swapchain image, and the
// image is presented. On request the presented image is also copied back to the host (the
// screenshot). Presentation uses the compute queue of the Context (lavapipe: its one queue).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <vulkan/vulkan.h>

#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/pipeline.h"
#include "shared/view_types.h"

namespace telescope::viewer {

class Presenter {
public:
    // Takes ownership of the surface. Throws when the device cannot present to it.
    Presenter(gpu::Context& context, VkSurfaceKHR surface, VkExtent2D windowSize);
    ~Presenter();
    Presenter(const Presenter&) = delete;
    Presenter& operator=(const Presenter&) = delete;

    // Runs the display pass over the accumulation at accumAddress and presents the result.
    // push: everything but the accumulation address, the output size and the flags, which the
    // presenter fills in; outWidth/outHeight of the frame are those of extent(). When capture is
    // given it receives the presented image as RGBA bytes, row-major. Returns false (and shows
    // nothing) when the swapchain had to be rebuilt first; call again.
    bool present(shader::ViewPush push, VkDeviceAddress accumAddress, VkExtent2D windowSize,
                 std::vector<uint8_t>* capture = nullptr);

    VkExtent2D extent() const { return extent_; }
    // Seconds of the last present() (display pass, copy, present and wait).
    double lastSeconds() const { return lastSeconds_; }

private:
    void release();  // destroys every handle; safe on a partly built Presenter
    void createSwapchain(VkExtent2D windowSize);
    void destroySwapchainResources();

    gpu::Context& context_;
    VkSurfaceKHR surface_ = VK_NULL_HANDLE;
    VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
    VkSurfaceFormatKHR format_{};
    uint32_t flags_ = 0;  // kViewFlag*
    VkExtent2D extent_{};     // of the swapchain images
    VkExtent2D requested_{};  // the window size the swapchain was made for
    std::vector<VkImage> images_;
    std::vector<VkSemaphore> renderDone_;  // one per swapchain image
    VkSemaphore acquired_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    bool canReadBack_ = false;
    gpu::Buffer pixels_;    // the display pass's output, one packed pixel per window pixel
    gpu::Buffer readback_;  // the presented image, on request
    std::unique_ptr<gpu::ComputePipeline> display_;
    double lastSeconds_ = 0.0;
};

}  // namespace telescope::viewer
