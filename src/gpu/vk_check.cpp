#include "gpu/vk_check.h"

#include <fmt/format.h>

namespace telescope::gpu {

const char* resultName(VkResult result) {
    switch (result) {
#define NAME(r) case r: return #r
        NAME(VK_SUCCESS); NAME(VK_NOT_READY); NAME(VK_TIMEOUT); NAME(VK_EVENT_SET);
        NAME(VK_EVENT_RESET); NAME(VK_INCOMPLETE); NAME(VK_ERROR_OUT_OF_HOST_MEMORY);
        NAME(VK_ERROR_OUT_OF_DEVICE_MEMORY); NAME(VK_ERROR_INITIALIZATION_FAILED);
        NAME(VK_ERROR_DEVICE_LOST); NAME(VK_ERROR_MEMORY_MAP_FAILED);
        NAME(VK_ERROR_LAYER_NOT_PRESENT); NAME(VK_ERROR_EXTENSION_NOT_PRESENT);
        NAME(VK_ERROR_FEATURE_NOT_PRESENT); NAME(VK_ERROR_INCOMPATIBLE_DRIVER);
        NAME(VK_ERROR_TOO_MANY_OBJECTS); NAME(VK_ERROR_FORMAT_NOT_SUPPORTED);
        NAME(VK_ERROR_FRAGMENTED_POOL); NAME(VK_ERROR_OUT_OF_POOL_MEMORY);
        NAME(VK_ERROR_INVALID_EXTERNAL_HANDLE); NAME(VK_ERROR_FRAGMENTATION);
        NAME(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS); NAME(VK_ERROR_UNKNOWN);
#undef NAME
        default: return "VK_ERROR_(unnamed)";
    }
}

VulkanError::VulkanError(VkResult result, const char* expr, const char* file, int line)
    : std::runtime_error(fmt::format("Vulkan call failed with {} ({}) at {}:{}", resultName(result),
                                     expr, file, line)),
      result_(result) {}

}  // namespace telescope::gpu
