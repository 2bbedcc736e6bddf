// A storage buffer and its memory, one owner (move-only).
//
// Device-local memory is preferred; when it is also host-visible (lavapipe, resizable BAR) the
// buffer is mapped and copies are plain memcpy, otherwise upload/download go through a staging
// buffer. Every buffer has a device address, so shaders can reach buffers larger than the
// storage-buffer binding limit (maxStorageBufferRange, 128 MiB on lavapipe) through
// GL_EXT_buffer_reference.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

namespace telescope::gpu {

class Context;

class Buffer {
public:
    Buffer() = default;
    Buffer(const Context& context, VkDeviceSize size, std::string name);
    ~Buffer();
    Buffer(Buffer&& other) noexcept;
    Buffer& operator=(Buffer&& other) noexcept;
    Buffer(const Buffer&) = delete;
    Buffer& operator=(const Buffer&) = delete;

    VkBuffer handle() const { return buffer_; }
    VkDeviceSize size() const { return size_; }
    VkDeviceAddress address() const { return address_; }
    const std::string& name() const { return name_; }
    bool valid() const { return buffer_ != VK_NULL_HANDLE; }
    // A view of the buffer as 4 x uint32 texels (R32G32B32A32_UINT), for a uniform or storage
    // texel buffer binding; created at the first call. Throws when the buffer holds more texels than
    // maxTexelBufferElements (texelViewFits says beforehand; $TELESCOPE_MAX_TEXELS lowers that
    // limit for tests).
    VkBufferView texelView() const;
    static bool texelViewFits(const Context& context, VkDeviceSize bytes);

    void upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset = 0);
    void download(void* data, VkDeviceSize bytes, VkDeviceSize offset = 0) const;
    void fill(uint32_t value);  // whole buffer
    void fill(uint32_t value, VkDeviceSize offset, VkDeviceSize bytes);  // bytes: a multiple of 4

    template <class T>
    void upload(const std::vector<T>& v) { if (!v.empty()) upload(v.data(), v.size() * sizeof(T)); }
    // Calls read(contents) with the whole buffer's contents: the mapping itself where reads through
    // it are fast (lavapipe, integrated GPUs: no copy, no second 2x-sized touch of fresh memory),
    // else a downloaded copy. `contents` is valid during the call only.
    template <class F>
    void readContents(F&& read) const {
        if (mapped_ && mappedCached_) {
            read(static_cast<const void*>(mapped_));
            return;
        }
        std::vector<char> copy(size_);
        download(copy.data(), size_);
        read(static_cast<const void*>(copy.data()));
    }
    template <class T>
    std::vector<T> downloadAll() const {
        std::vector<T> v(size_ / sizeof(T));
        download(v.data(), v.size() * sizeof(T));
        return v;
    }

private:
    void release();
    void copyViaStaging(void* host, VkDeviceSize bytes, VkDeviceSize offset, bool toDevice) const;

    const Context* context_ = nullptr;
    VkBuffer buffer_ = VK_NULL_HANDLE;
    VkDeviceMemory memory_ = VK_NULL_HANDLE;
    VkDeviceSize size_ = 0;
    VkDeviceAddress address_ = 0;
    void* mapped_ = nullptr;
    mutable VkBufferView texelView_ = VK_NULL_HANDLE;
    bool mappedCached_ = false;  // the mapping is HOST_CACHED: reads through it are fast
    std::string name_;
};

// A one-time command buffer: begin on construction, submitted and waited for by submit().
class OneTimeCommands {
public:
    explicit OneTimeCommands(const Context& context);
    ~OneTimeCommands();
    OneTimeCommands(const OneTimeCommands&) = delete;
    OneTimeCommands& operator=(const OneTimeCommands&) = delete;
    VkCommandBuffer cmd() const { return cmd_; }
    void submit();

private:
    const Context& context_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    bool submitted_ = false;
};

}  // namespace telescope::gpu
