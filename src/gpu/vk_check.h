// Every VkResult goes through VK_CHECK, which throws VulkanError naming the call site.
#pragma once

#include <stdexcept>
#include <string>

#include <vulkan/vulkan.h>

namespace telescope::gpu {

const char* resultName(VkResult result);

class VulkanError : public std::runtime_error {
public:
    VulkanError(VkResult result, const char* expr, const char* file, int line);
    VkResult result() const { return result_; }

private:
    VkResult result_;
};

}  // namespace telescope::gpu

#define VK_CHECK(expr)                                                                   \
    do {                                                                                 \
        VkResult vkCheckResult_ = (expr);                                                \
        if (vkCheckResult_ != VK_SUCCESS)                                                \
            throw ::telescope::gpu::VulkanError(vkCheckResult_, #expr, __FILE__, __LINE__); \
    } while (0)
