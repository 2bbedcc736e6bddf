#include "gpu/context.h"

#include <cstdlib>
#include <cstring>
#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#include <link.h>
#endif
#include <iostream>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "gpu/vk_check.h"

namespace telescope::gpu {

namespace {

const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::string deviceTypeName(VkPhysicalDeviceType type) {
    switch (type) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
        default: return "other";
    }
}

bool layerAvailable(const char* name) {
    uint32_t count = 0;
    VK_CHECK(vkEnumerateInstanceLayerProperties(&count, nullptr));
    std::vector<VkLayerProperties> layers(count);
    VK_CHECK(vkEnumerateInstanceLayerProperties(&count, layers.data()));
    for (const auto& l : layers)
        if (std::strcmp(l.layerName, name) == 0) return true;
    return false;
}

// Instance creation shared by listDevices() and Context.
VkInstance createInstance(bool validation, const std::vector<std::string>& extraExtensions = {}) {
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
    app.pApplicationName = "telescope";
    app.apiVersion = VK_API_VERSION_1_2;
    std::vector<const char*> layers, extensions;
    if (validation) {
        if (!layerAvailable(kValidationLayer))
            throw std::runtime_error(
                "validation requested but VK_LAYER_KHRONOS_validation is not installed "
                "(Debian: apt-get install vulkan-validationlayers)");
        layers.push_back(kValidationLayer);
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    for (const auto& e : extraExtensions) extensions.push_back(e.c_str());
    VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
    info.pApplicationInfo = &app;
    info.enabledLayerCount = uint32_t(layers.size());
    info.ppEnabledLayerNames = layers.data();
    info.enabledExtensionCount = uint32_t(extensions.size());
    info.ppEnabledExtensionNames = extensions.data();
    VkInstance instance = VK_NULL_HANDLE;
    VkResult r = vkCreateInstance(&info, nullptr, &instance);
    if (r == VK_ERROR_EXTENSION_NOT_PRESENT && !extraExtensions.empty())
        throw std::runtime_error(fmt::format("the Vulkan driver lacks an instance extension needed here ({})",
                                             fmt::join(extraExtensions, ", ")));
    if (r == VK_ERROR_INCOMPATIBLE_DRIVER)
        throw std::runtime_error("no Vulkan 1.2 driver found (Debian: apt-get install mesa-vulkan-drivers)");
    VK_CHECK(r);
#if defined(__SANITIZE_ADDRESS__)
    // Under AddressSanitizer: keep every library loaded by now, the drivers and layers the loader
    // opened among them, mapped until the process ends (repeat calls only repeat the pinning).
    // Drivers allocate some things once for the life of the process and hold them in their
    // globals (lavapipe: 128 bytes in a pthread_once initialiser, seen on a Zen 3 machine and not on
    // earlier ones); vkDestroyInstance unloads them, after which LeakSanitizer sees those blocks
    // unreferenced and reports them from an "<unknown module>" that no suppression can name.
    // Pinned, the blocks stay reachable, as in a process that never destroys its instance; a leak
    // of ours is still reported.
    dl_iterate_phdr(
        [](dl_phdr_info* lib, size_t, void*) {
            if (lib->dlpi_name && *lib->dlpi_name)
                dlopen(lib->dlpi_name, RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);
            return 0;
        },
        nullptr);
#endif
    return instance;
}

std::vector<VkPhysicalDevice> physicalDevices(VkInstance instance) {
    uint32_t count = 0;
    VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, nullptr));
    std::vector<VkPhysicalDevice> devices(count);
    VK_CHECK(vkEnumeratePhysicalDevices(instance, &count, devices.data()));
    return devices;
}

int computeQueueFamily(VkPhysicalDevice pd) {
    uint32_t count = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, nullptr);
    std::vector<VkQueueFamilyProperties> families(count);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &count, families.data());
    for (uint32_t i = 0; i < count; ++i)
        if (families[i].queueFlags & VK_QUEUE_COMPUTE_BIT) return int(i);
    return -1;
}

DeviceInfo describe(VkPhysicalDevice pd, uint32_t index) {
    VkPhysicalDeviceDriverProperties driver{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES};
    VkPhysicalDeviceSubgroupProperties subgroup{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    driver.pNext = &subgroup;
    VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
    props.pNext = &driver;
    vkGetPhysicalDeviceProperties2(pd, &props);
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    features.pNext = &f12;
    vkGetPhysicalDeviceFeatures2(pd, &features);

    DeviceInfo d;
    d.index = index;
    d.name = props.properties.deviceName;
    d.type = deviceTypeName(props.properties.deviceType);
    d.driver = fmt::format("{} {}", driver.driverName, driver.driverInfo);
    d.apiVersion = props.properties.apiVersion;
    if (props.properties.apiVersion < VK_API_VERSION_1_2) d.whyNot = "Vulkan 1.2 not supported";
    else if (computeQueueFamily(pd) < 0) d.whyNot = "no compute queue";
    else if (!f12.bufferDeviceAddress) d.whyNot = "no bufferDeviceAddress";
    else if (!features.features.shaderInt64) d.whyNot = "no shaderInt64";
    // photon_trace reserves photon slots once per subgroup (ballot); the hash grid's scan adds
    // within subgroups (arithmetic)
    else if (!(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
             !(subgroup.supportedOperations & VK_SUBGROUP_FEATURE_BALLOT_BIT) ||
             !(subgroup.supportedOperations & VK_SUBGROUP_FEATURE_ARITHMETIC_BIT))
        d.whyNot = "no subgroup ballot and arithmetic in compute shaders";
    d.suitable = d.whyNot.empty();
    return d;
}

// The first of `wanted` the device does not support, or "" when it supports them all.
std::string missingDeviceExtension(VkPhysicalDevice pd, const std::vector<std::string>& wanted) {
    if (wanted.empty()) return "";
    uint32_t count = 0;
    VK_CHECK(vkEnumerateDeviceExtensionProperties(pd, nullptr, &count, nullptr));
    std::vector<VkExtensionProperties> present(count);
    VK_CHECK(vkEnumerateDeviceExtensionProperties(pd, nullptr, &count, present.data()));
    for (const auto& w : wanted) {
        bool found = false;
        for (const auto& p : present) found = found || w == p.extensionName;
        if (!found) return w;
    }
    return "";
}

}  // namespace

bool validationRequestedByEnvironment() {
    const char* v = std::getenv("TELESCOPE_VALIDATION");
    return v && *v && std::strcmp(v, "0") != 0;
}

std::vector<DeviceInfo> Context::listDevices() {
    VkInstance instance = createInstance(false);
    std::vector<DeviceInfo> out;
    try {
        auto devices = physicalDevices(instance);
        for (uint32_t i = 0; i < devices.size(); ++i) out.push_back(describe(devices[i], i));
    } catch (...) {
        vkDestroyInstance(instance, nullptr);
        throw;
    }
    vkDestroyInstance(instance, nullptr);
    return out;
}

Context::Context(const ContextOptions& options) {
    bool validation = options.validation || validationRequestedByEnvironment();
    instance_ = createInstance(validation, options.instanceExtensions);
    try {
        // ---- Validation messenger: warnings and errors are counted and printed ----
        if (validation) {
            auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
                vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
            VkDebugUtilsMessengerCreateInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
            info.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                                   VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
            info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
            info.pfnUserCallback = &Context::debugCallback;
            info.pUserData = this;
            VK_CHECK(create(instance_, &info, nullptr, &messenger_));
        }

        // ---- Device choice: the requested index, else a GPU, else any suitable device ----
        auto devices = physicalDevices(instance_);
        if (devices.empty()) throw std::runtime_error("no Vulkan device found");
        int chosen = -1;
        if (options.deviceIndex >= 0) {
            if (options.deviceIndex >= int(devices.size()))
                throw std::runtime_error(fmt::format("--device {}: only {} Vulkan device(s) present",
                                                     options.deviceIndex, devices.size()));
            DeviceInfo d = describe(devices[options.deviceIndex], options.deviceIndex);
            const std::string missing = missingDeviceExtension(devices[options.deviceIndex], options.deviceExtensions);
            if (d.suitable && !missing.empty()) d.whyNot = "no " + missing;
            d.suitable = d.whyNot.empty();
            if (!d.suitable)
                throw std::runtime_error(fmt::format("device {} ({}) cannot run Telescope: {}",
                                                     d.index, d.name, d.whyNot));
            chosen = options.deviceIndex;
        } else {
            for (int pass = 0; pass < 2 && chosen < 0; ++pass)
                for (uint32_t i = 0; i < devices.size() && chosen < 0; ++i) {
                    DeviceInfo d = describe(devices[i], i);
                    bool gpu = d.type == "discrete GPU" || d.type == "integrated GPU";
                    bool extensions = missingDeviceExtension(devices[i], options.deviceExtensions).empty();
                    if (d.suitable && extensions && (pass == 1 || gpu)) chosen = int(i);
                }
            if (chosen < 0)
                throw std::runtime_error(options.deviceExtensions.empty()
                                             ? "no Vulkan 1.2 device with compute and buffer device address"
                                             : fmt::format("no Vulkan 1.2 device with compute, buffer device address and {}",
                                                           fmt::join(options.deviceExtensions, ", ")));
        }
        physicalDevice_ = devices[chosen];
        info_ = describe(physicalDevice_, uint32_t(chosen));
        vkGetPhysicalDeviceProperties(physicalDevice_, &properties_);
        vkGetPhysicalDeviceMemoryProperties(physicalDevice_, &memoryProperties_);
        queueFamily_ = uint32_t(computeQueueFamily(physicalDevice_));
        {
            uint32_t count = 0;
            vkGetPhysicalDeviceQueueFamilyProperties(physicalDevice_, &count, nullptr);
            std::vector<VkQueueFamilyProperties> families(count);
            vkGetPhysicalDeviceQueueFamilyProperties(physicalDevice_, &count, families.data());
            timestampValidBits_ = families[queueFamily_].timestampValidBits;
        }

        // ---- Logical device with the features the shaders use ----
        VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
        f12.bufferDeviceAddress = VK_TRUE;
        VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
        features.pNext = &f12;
        features.features.shaderInt64 = VK_TRUE;
        float priority = 1.0f;
        VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
        queueInfo.queueFamilyIndex = queueFamily_;
        queueInfo.queueCount = 1;
        queueInfo.pQueuePriorities = &priority;
        VkDeviceCreateInfo deviceInfo{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
        deviceInfo.pNext = &features;
        deviceInfo.queueCreateInfoCount = 1;
        deviceInfo.pQueueCreateInfos = &queueInfo;
        std::vector<const char*> deviceExtensions;
        for (const auto& e : options.deviceExtensions) deviceExtensions.push_back(e.c_str());
        deviceInfo.enabledExtensionCount = uint32_t(deviceExtensions.size());
        deviceInfo.ppEnabledExtensionNames = deviceExtensions.data();
        VK_CHECK(vkCreateDevice(physicalDevice_, &deviceInfo, nullptr, &device_));
        vkGetDeviceQueue(device_, queueFamily_, 0, &queue_);

        VkCommandPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
        poolInfo.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
        poolInfo.queueFamilyIndex = queueFamily_;
        VK_CHECK(vkCreateCommandPool(device_, &poolInfo, nullptr, &commandPool_));
        VkFenceCreateInfo fenceInfo{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
        VK_CHECK(vkCreateFence(device_, &fenceInfo, nullptr, &fence_));
    } catch (...) {
        release();
        throw;
    }
}

Context::~Context() { release(); }

void Context::release() {
    if (device_) {
        vkDeviceWaitIdle(device_);
        if (fence_) vkDestroyFence(device_, fence_, nullptr);
        if (commandPool_) vkDestroyCommandPool(device_, commandPool_, nullptr);
        vkDestroyDevice(device_, nullptr);
        device_ = VK_NULL_HANDLE;
    }
    if (messenger_) {
        auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
        destroy(instance_, messenger_, nullptr);
        messenger_ = VK_NULL_HANDLE;
    }
    if (instance_) vkDestroyInstance(instance_, nullptr);
    instance_ = VK_NULL_HANDLE;
}

VkBool32 VKAPI_CALL Context::debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                           VkDebugUtilsMessageTypeFlagsEXT,
                                           const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    auto* self = static_cast<Context*>(user);
    std::string msg = fmt::format("[vulkan {}] {}",
                                  severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT ? "error" : "warning",
                                  data && data->pMessage ? data->pMessage : "(no message)");
    std::cerr << msg << "\n";
    self->validationMessages_.fetch_add(1);
    std::lock_guard<std::mutex> lock(self->messagesMutex_);
    self->messages_.push_back(std::move(msg));
    return VK_FALSE;
}

std::vector<std::string> Context::validationMessages() const {
    std::lock_guard<std::mutex> lock(messagesMutex_);
    return messages_;
}

uint32_t Context::findMemoryType(uint32_t typeBits, VkMemoryPropertyFlags required) const {
    for (uint32_t i = 0; i < memoryProperties_.memoryTypeCount; ++i)
        if ((typeBits & (1u << i)) && (memoryProperties_.memoryTypes[i].propertyFlags & required) == required)
            return i;
    return UINT32_MAX;
}

void Context::submitAndWait(VkCommandBuffer cmd) const {
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &cmd;
    VK_CHECK(vkResetFences(device_, 1, &fence_));
    VK_CHECK(vkQueueSubmit(queue_, 1, &submit, fence_));
    VK_CHECK(vkWaitForFences(device_, 1, &fence_, VK_TRUE, UINT64_MAX));
}

}  // namespace telescope::gpu
