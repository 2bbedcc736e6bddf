// The Vulkan instance, the chosen device and its compute queue.
//
// A Context owns the instance, the optional validation messenger, the logical device and one
// command pool. Everything else (buffers, pipelines) is owned by objects that borrow the Context
// and must be destroyed before it.
#pragma once

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

namespace telescope::gpu {

struct DeviceInfo {
    uint32_t index = 0;
    std::string name;
    std::string type;        // "discrete GPU", "integrated GPU", "CPU", ...
    std::string driver;
    uint32_t apiVersion = 0;
    bool suitable = false;   // Vulkan 1.2 with a compute queue and the features Telescope needs
    std::string whyNot;      // when not suitable
};

struct ContextOptions {
    // Device index from listDevices(), or -1 for the first suitable discrete/integrated GPU,
    // then any suitable device (lavapipe).
    int deviceIndex = -1;
    // Enables VK_LAYER_KHRONOS_validation; also on when TELESCOPE_VALIDATION=1.
    bool validation = false;
    // Extra extensions, for presenting to a window (the viewer): none for headless work. A device
    // without every device extension is not chosen.
    std::vector<std::string> instanceExtensions;
    std::vector<std::string> deviceExtensions;
};

class Context {
public:
    explicit Context(const ContextOptions& options = {});
    ~Context();
    Context(const Context&) = delete;
    Context& operator=(const Context&) = delete;

    // Lists the Vulkan devices without creating a logical device.
    static std::vector<DeviceInfo> listDevices();

    VkInstance instance() const { return instance_; }
    VkPhysicalDevice physicalDevice() const { return physicalDevice_; }
    VkDevice device() const { return device_; }
    VkQueue queue() const { return queue_; }
    uint32_t queueFamily() const { return queueFamily_; }
    VkCommandPool commandPool() const { return commandPool_; }
    const DeviceInfo& info() const { return info_; }
    const VkPhysicalDeviceProperties& properties() const { return properties_; }
    // A CPU implementation (lavapipe): device memory is host memory, the mapping is the storage.
    bool cpuDevice() const { return properties_.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU; }
    bool timestampsSupported() const { return timestampValidBits_ > 0; }
    float timestampPeriodNs() const { return properties_.limits.timestampPeriod; }

    bool validationEnabled() const { return messenger_ != VK_NULL_HANDLE; }
    // Validation messages (warnings and errors) seen so far; each is also printed to stderr.
    uint32_t validationMessageCount() const { return validationMessages_.load(); }
    std::vector<std::string> validationMessages() const;

    // Finds a memory type with the given properties; returns UINT32_MAX when there is none.
    uint32_t findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required) const;
    bool memoryTypeHas(uint32_t type, VkMemoryPropertyFlags flags) const {
        return type < memoryProperties_.memoryTypeCount && (memoryProperties_.memoryTypes[type].propertyFlags & flags) == flags;
    }

    // Submits one command buffer and waits for it.
    void submitAndWait(VkCommandBuffer cmd) const;

private:
    void release();  // destroys every handle; safe on a partly built Context

    static VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                             VkDebugUtilsMessageTypeFlagsEXT types,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data,
                                             void* user);

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkPhysicalDevice physicalDevice_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    uint32_t queueFamily_ = 0;
    uint32_t timestampValidBits_ = 0;
    VkCommandPool commandPool_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memoryProperties_{};
    DeviceInfo info_;
    std::atomic<uint32_t> validationMessages_{0};
    mutable std::mutex messagesMutex_;
    std::vector<std::string> messages_;
};

// True when TELESCOPE_VALIDATION is set to a non-empty value other than "0".
bool validationRequestedByEnvironment();

}  // namespace telescope::gpu
