#include "viewer/presenter.h"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include <fmt/format.h>

#include "gpu/vk_check.h"

namespace telescope::viewer {

namespace {

// UNORM formats get sRGB encoding in the shader; SRGB formats encode on write.
bool chooseFormat(const std::vector<VkSurfaceFormatKHR>& formats, VkSurfaceFormatKHR& out, uint32_t& flags) {
    const VkFormat preferred[] = {VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_SRGB,
                                  VK_FORMAT_R8G8B8A8_SRGB};
    for (VkFormat f : preferred)
        for (const auto& s : formats)
            if (s.format == f && s.colorSpace == VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) {
                out = s;
                flags = 0;
                if (f == VK_FORMAT_B8G8R8A8_UNORM || f == VK_FORMAT_R8G8B8A8_UNORM) flags |= shader::kViewFlagEncodeSrgb;
                if (f == VK_FORMAT_B8G8R8A8_UNORM || f == VK_FORMAT_B8G8R8A8_SRGB) flags |= shader::kViewFlagBgra;
                return true;
            }
    return false;
}

void imageBarrier(VkCommandBuffer cmd, VkImage image, VkImageLayout from, VkImageLayout to, VkAccessFlags srcAccess,
                  VkAccessFlags dstAccess, VkPipelineStageFlags srcStage, VkPipelineStageFlags dstStage) {
    VkImageMemoryBarrier b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER};
    b.srcAccessMask = srcAccess;
    b.dstAccessMask = dstAccess;
    b.oldLayout = from;
    b.newLayout = to;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.image = image;
    b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
    vkCmdPipelineBarrier(cmd, srcStage, dstStage, 0, 0, nullptr, 0, nullptr, 1, &b);
}

void bufferBarrier(VkCommandBuffer cmd, VkBuffer buffer, VkAccessFlags srcAccess, VkAccessFlags dstAccess,
                   VkPipelineStageFlags srcStage, VkPipelineStageFlags dstStage) {
    VkBufferMemoryBarrier b{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER};
    b.srcAccessMask = srcAccess;
    b.dstAccessMask = dstAccess;
    b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    b.buffer = buffer;
    b.size = VK_WHOLE_SIZE;
    vkCmdPipelineBarrier(cmd, srcStage, dstStage, 0, 0, nullptr, 1, &b, 0, nullptr);
}

}  // namespace

Presenter::Presenter(gpu::Context& context, VkSurfaceKHR surface, VkExtent2D windowSize)
    : context_(context), surface_(surface) {
    VkDevice device = context.device();
    try {
        VkBool32 supported = VK_FALSE;
        VK_CHECK(vkGetPhysicalDeviceSurfaceSupportKHR(context.physicalDevice(), context.queueFamily(), surface_,
                                                      &supported));
        if (!supported)
            throw std::runtime_error(fmt::format("view: device {} ({}) cannot present to this window; choose another "
                                                 "with --device (see 'telescope devices')",
                                                 context.info().index, context.info().name));
        uint32_t count = 0;
        VK_CHECK(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface_, &count, nullptr));
        std::vector<VkSurfaceFormatKHR> formats(count);
        VK_CHECK(vkGetPhysicalDeviceSurfaceFormatsKHR(context.physicalDevice(), surface_, &count, formats.data()));
        if (!chooseFormat(formats, format_, flags_))
            throw std::runtime_error("view: the window offers no 8-bit RGBA or BGRA swapchain format");

        VkSemaphoreCreateInfo semaphoreInfo{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
        VK_CHECK(vkCreateSemaphore(device, &semaphoreInfo, nullptr, &acquired_));
        VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        VK_CHECK(vkCreateFence(device, &fenceInfo, nullptr, &fence_));
        VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
        alloc.commandPool = context.commandPool();
        alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
        alloc.commandBufferCount = 1;
        VK_CHECK(vkAllocateCommandBuffers(device, &alloc, &cmd_));
        display_ = std::make_unique<gpu::ComputePipeline>(context, "view_display", 1, uint32_t(sizeof(shader::ViewPush)));
        createSwapchain(windowSize);
    } catch (...) {
        release();
        throw;
    }
}

Presenter::~Presenter() { release(); }

void Presenter::release() {
    VkDevice device = context_.device();
    vkDeviceWaitIdle(device);
    destroySwapchainResources();
    if (swapchain_) vkDestroySwapchainKHR(device, swapchain_, nullptr);
    swapchain_ = VK_NULL_HANDLE;
    display_.reset();
    if (cmd_) vkFreeCommandBuffers(device, context_.commandPool(), 1, &cmd_);
    cmd_ = VK_NULL_HANDLE;
    if (fence_) vkDestroyFence(device, fence_, nullptr);
    fence_ = VK_NULL_HANDLE;
    if (acquired_) vkDestroySemaphore(device, acquired_, nullptr);
    acquired_ = VK_NULL_HANDLE;
    if (surface_) vkDestroySurfaceKHR(context_.instance(), surface_, nullptr);
    surface_ = VK_NULL_HANDLE;
}

void Presenter::destroySwapchainResources() {
    for (VkSemaphore s : renderDone_) vkDestroySemaphore(context_.device(), s, nullptr);
    renderDone_.clear();
    images_.clear();
    pixels_ = gpu::Buffer();
    readback_ = gpu::Buffer();
}

// ---- Swapchain: FIFO, the window's size, written by transfers (and read back for screenshots) ----
void Presenter::createSwapchain(VkExtent2D windowSize) {
    VkDevice device = context_.device();
    vkDeviceWaitIdle(device);
    destroySwapchainResources();
    requested_ = windowSize;

    VkSurfaceCapabilitiesKHR caps;
    VK_CHECK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(context_.physicalDevice(), surface_, &caps));
    if (!(caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT))
        throw std::runtime_error("view: the swapchain images of this window cannot be written by transfers");
    canReadBack_ = (caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_SRC_BIT) != 0;
    extent_ = caps.currentExtent;
    if (extent_.width == 0xffffffffu) {
        extent_.width = std::clamp(windowSize.width, caps.minImageExtent.width, caps.maxImageExtent.width);
        extent_.height = std::clamp(windowSize.height, caps.minImageExtent.height, caps.maxImageExtent.height);
    }
    if (extent_.width == 0 || extent_.height == 0) return;  // minimised: nothing to present to

    VkSwapchainCreateInfoKHR info{VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR};
    info.surface = surface_;
    info.minImageCount = caps.maxImageCount ? std::min(caps.minImageCount + 1, caps.maxImageCount) : caps.minImageCount + 1;
    info.imageFormat = format_.format;
    info.imageColorSpace = format_.colorSpace;
    info.imageExtent = extent_;
    info.imageArrayLayers = 1;
    info.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | (canReadBack_ ? VK_IMAGE_USAGE_TRANSFER_SRC_BIT : 0);
    info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;
    info.preTransform = caps.currentTransform;
    info.compositeAlpha = (caps.supportedCompositeAlpha & VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR)
                              ? VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR
                              : VkCompositeAlphaFlagBitsKHR(caps.supportedCompositeAlpha & -caps.supportedCompositeAlpha);
    info.presentMode = VK_PRESENT_MODE_FIFO_KHR;  // always available; Xvfb does not throttle it
    info.clipped = VK_TRUE;
    info.oldSwapchain = swapchain_;
    VkSwapchainKHR created = VK_NULL_HANDLE;
    VK_CHECK(vkCreateSwapchainKHR(device, &info, nullptr, &created));
    if (swapchain_) vkDestroySwapchainKHR(device, swapchain_, nullptr);
    swapchain_ = created;

    uint32_t count = 0;
    VK_CHECK(vkGetSwapchainImagesKHR(device, swapchain_, &count, nullptr));
    images_.resize(count);
    VK_CHECK(vkGetSwapchainImagesKHR(device, swapchain_, &count, images_.data()));
    VkSemaphoreCreateInfo semaphoreInfo{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    renderDone_.assign(count, VK_NULL_HANDLE);
    for (auto& s : renderDone_) VK_CHECK(vkCreateSemaphore(device, &semaphoreInfo, nullptr, &s));

    const VkDeviceSize bytes = VkDeviceSize(extent_.width) * extent_.height * 4;
    pixels_ = gpu::Buffer(context_, bytes, "view pixels");
    if (canReadBack_) readback_ = gpu::Buffer(context_, bytes, "view readback");
    display_->bindBuffers({&pixels_});
}

bool Presenter::present(shader::ViewPush push, VkDeviceAddress accumAddress, VkExtent2D windowSize,
                        std::vector<uint8_t>* capture) {
    const auto start = std::chrono::steady_clock::now();
    VkDevice device = context_.device();
    if (windowSize.width != requested_.width || windowSize.height != requested_.height || images_.empty()) {
        createSwapchain(windowSize);
        return false;
    }
    if (capture && !canReadBack_) throw std::runtime_error("view: the swapchain images cannot be read back for a screenshot");

    uint32_t index = 0;
    VkResult acquired = vkAcquireNextImageKHR(device, swapchain_, UINT64_MAX, acquired_, VK_NULL_HANDLE, &index);
    if (acquired == VK_ERROR_OUT_OF_DATE_KHR) {
        createSwapchain(windowSize);
        return false;
    }
    if (acquired != VK_SUBOPTIMAL_KHR) VK_CHECK(acquired);

    push.accumLo = uint32_t(accumAddress);
    push.accumHi = uint32_t(accumAddress >> 32);
    push.outWidth = extent_.width;
    push.outHeight = extent_.height;
    push.flags = flags_;

    // ---- Record: display pass, copy into the swapchain image, optional read-back ----
    VK_CHECK(vkResetCommandBuffer(cmd_, 0));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(vkBeginCommandBuffer(cmd_, &begin));
    vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, display_->handle());
    VkDescriptorSet set = display_->descriptorSet();
    vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, display_->layout(), 0, 1, &set, 0, nullptr);
    vkCmdPushConstants(cmd_, display_->layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), &push);
    vkCmdDispatch(cmd_, (extent_.width + shader::kViewGroupSize - 1) / shader::kViewGroupSize,
                  (extent_.height + shader::kViewGroupSize - 1) / shader::kViewGroupSize, 1);

    bufferBarrier(cmd_, pixels_.handle(), VK_ACCESS_SHADER_WRITE_BIT, VK_ACCESS_TRANSFER_READ_BIT,
                  VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
    VkImage image = images_[index];
    imageBarrier(cmd_, image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0,
                 VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
    VkBufferImageCopy region{};
    region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    region.imageExtent = {extent_.width, extent_.height, 1};
    vkCmdCopyBufferToImage(cmd_, pixels_.handle(), image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
    VkImageLayout layout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
    VkAccessFlags lastAccess = VK_ACCESS_TRANSFER_WRITE_BIT;
    if (capture) {
        imageBarrier(cmd_, image, layout, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, VK_ACCESS_TRANSFER_WRITE_BIT,
                     VK_ACCESS_TRANSFER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT);
        vkCmdCopyImageToBuffer(cmd_, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.handle(), 1, &region);
        bufferBarrier(cmd_, readback_.handle(), VK_ACCESS_TRANSFER_WRITE_BIT, VK_ACCESS_HOST_READ_BIT,
                      VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT);
        layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
        lastAccess = 0;
    }
    imageBarrier(cmd_, image, layout, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR, lastAccess, 0, VK_PIPELINE_STAGE_TRANSFER_BIT,
                 VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT);
    VK_CHECK(vkEndCommandBuffer(cmd_));

    // ---- Submit after the acquire, present after the submit ----
    VkPipelineStageFlags waitStage = VK_PIPELINE_STAGE_TRANSFER_BIT;
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.waitSemaphoreCount = 1;
    submit.pWaitSemaphores = &acquired_;
    submit.pWaitDstStageMask = &waitStage;
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd_;
    submit.signalSemaphoreCount = 1;
    submit.pSignalSemaphores = &renderDone_[index];
    VK_CHECK(vkResetFences(device, 1, &fence_));
    VK_CHECK(vkQueueSubmit(context_.queue(), 1, &submit, fence_));
    VkPresentInfoKHR presentInfo{VK_STRUCTURE_TYPE_PRESENT_INFO_KHR};
    presentInfo.waitSemaphoreCount = 1;
    presentInfo.pWaitSemaphores = &renderDone_[index];
    presentInfo.swapchainCount = 1;
    presentInfo.pSwapchains = &swapchain_;
    presentInfo.pImageIndices = &index;
    VkResult presented = vkQueuePresentKHR(context_.queue(), &presentInfo);
    VK_CHECK(vkWaitForFences(device, 1, &fence_, VK_TRUE, UINT64_MAX));
    if (presented == VK_ERROR_OUT_OF_DATE_KHR || presented == VK_SUBOPTIMAL_KHR) createSwapchain(windowSize);
    else VK_CHECK(presented);

    if (capture) {
        const size_t n = size_t(extent_.width) * extent_.height;
        std::vector<uint8_t> raw(n * 4);
        readback_.download(raw.data(), raw.size());
        capture->resize(n * 4);
        const bool bgra = flags_ & shader::kViewFlagBgra;
        for (size_t i = 0; i < n; ++i) {
            (*capture)[i * 4 + 0] = raw[i * 4 + (bgra ? 2 : 0)];
            (*capture)[i * 4 + 1] = raw[i * 4 + 1];
            (*capture)[i * 4 + 2] = raw[i * 4 + (bgra ? 0 : 2)];
            (*capture)[i * 4 + 3] = raw[i * 4 + 3];
        }
    }
    lastSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return true;
}

}  // namespace telescope::viewer
