#include "gpu/buffer.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <utility>

#include <sys/mman.h>

#include <fmt/format.h>

#include "gpu/context.h"
#include "gpu/vk_check.h"

namespace telescope::gpu {

namespace {

// On a CPU device the mapping is the memory the shaders read and write. Large buffers written at
// random (the photon map: photon stores, bucket counts, the scatter into bucket order) spend much
// of their time in TLB misses on 4 KiB pages; transparent huge pages (2 MiB) remove most of them
// (measured on lavapipe: photon_trace and hash_grid_build, docs/BENCHMARKS.photon-notes.md). Only advice: where
// the kernel has transparent huge pages off, or the range is not ordinary anonymous memory,
// madvise fails and nothing changes.
void adviseHugePages(void* mapped, VkDeviceSize bytes) {
#ifdef MADV_HUGEPAGE
    constexpr uintptr_t kHuge = uintptr_t(2) << 20;
    if (bytes < 2 * kHuge) return;
    const uintptr_t begin = (reinterpret_cast<uintptr_t>(mapped) + kHuge - 1) & ~(kHuge - 1);
    const uintptr_t end = (reinterpret_cast<uintptr_t>(mapped) + bytes) & ~(kHuge - 1);
    if (end > begin) (void)madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
    (void)mapped, (void)bytes;
#endif
}

}  // namespace

Buffer::Buffer(const Context& context, VkDeviceSize size, std::string name)
    : context_(&context), size_(size), name_(std::move(name)) {
    if (size == 0) size = 16;  // Vulkan forbids empty buffers; keep size() truthful
    VkDevice device = context.device();
    try {
        VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        info.size = size;
        info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
                     VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_SHADER_DEVICE_ADDRESS_BIT |
                     VK_BUFFER_USAGE_UNIFORM_TEXEL_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_TEXEL_BUFFER_BIT;
        info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        VK_CHECK(vkCreateBuffer(device, &info, nullptr, &buffer_));

        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(device, buffer_, &req);
        const VkMemoryPropertyFlags hostVisible =
            VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
        uint32_t type = context.findMemoryType(req.memoryTypeBits,
                                               VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT | hostVisible);
        bool mappable = type != UINT32_MAX;
        if (!mappable) type = context.findMemoryType(req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
        if (type == UINT32_MAX) throw std::runtime_error("no device-local memory type for buffer " + name_);

        VkMemoryAllocateFlagsInfo flags{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_FLAGS_INFO};
        flags.flags = VK_MEMORY_ALLOCATE_DEVICE_ADDRESS_BIT;
        VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        alloc.pNext = &flags;
        alloc.allocationSize = req.size;
        alloc.memoryTypeIndex = type;
        VkResult r = vkAllocateMemory(device, &alloc, nullptr, &memory_);
        if (r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY)
            throw std::runtime_error(fmt::format("out of memory allocating buffer '{}' ({:.1f} MiB)", name_,
                                                 double(size) / (1 << 20)));
        VK_CHECK(r);
        VK_CHECK(vkBindBufferMemory(device, buffer_, memory_, 0));
        if (mappable) VK_CHECK(vkMapMemory(device, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_));
        mappedCached_ = mappable && context.memoryTypeHas(type, VK_MEMORY_PROPERTY_HOST_CACHED_BIT);
        if (mapped_ && context.cpuDevice()) adviseHugePages(mapped_, req.size);

        VkBufferDeviceAddressInfo addressInfo{VK_STRUCTURE_TYPE_BUFFER_DEVICE_ADDRESS_INFO};
        addressInfo.buffer = buffer_;
        address_ = vkGetBufferDeviceAddress(device, &addressInfo);
    } catch (...) {
        release();
        throw;
    }
}

Buffer::~Buffer() { release(); }

Buffer::Buffer(Buffer&& o) noexcept { *this = std::move(o); }

Buffer& Buffer::operator=(Buffer&& o) noexcept {
    if (this != &o) {
        release();
        context_ = std::exchange(o.context_, nullptr);
        buffer_ = std::exchange(o.buffer_, VK_NULL_HANDLE);
        memory_ = std::exchange(o.memory_, VK_NULL_HANDLE);
        size_ = std::exchange(o.size_, 0);
        address_ = std::exchange(o.address_, 0);
        mapped_ = std::exchange(o.mapped_, nullptr);
        texelView_ = std::exchange(o.texelView_, VK_NULL_HANDLE);
        mappedCached_ = std::exchange(o.mappedCached_, false);
        name_ = std::move(o.name_);
    }
    return *this;
}

void Buffer::release() {
    if (!context_) return;
    VkDevice device = context_->device();
    if (texelView_) vkDestroyBufferView(device, texelView_, nullptr);
    texelView_ = VK_NULL_HANDLE;
    if (buffer_) vkDestroyBuffer(device, buffer_, nullptr);
    if (memory_) vkFreeMemory(device, memory_, nullptr);  // also unmaps
    buffer_ = VK_NULL_HANDLE;
    memory_ = VK_NULL_HANDLE;
    mapped_ = nullptr;
}

bool Buffer::texelViewFits(const Context& context, VkDeviceSize bytes) {
    uint64_t limit = context.properties().limits.maxTexelBufferElements;
    // Test aid: TELESCOPE_MAX_TEXELS lowers the limit, so that the paths taken beyond it run on
    // any device.
    if (const char* v = std::getenv("TELESCOPE_MAX_TEXELS"); v && *v) limit = std::min<uint64_t>(limit, std::strtoull(v, nullptr, 10));
    return bytes / 16 <= limit;
}

VkBufferView Buffer::texelView() const {
    if (texelView_) return texelView_;
    const VkDeviceSize bytes = std::max<VkDeviceSize>(size_, 16) / 16 * 16;
    if (!texelViewFits(*context_, bytes))
        throw std::runtime_error(fmt::format("buffer '{}' ({} bytes) holds more texels than a texel buffer may ({})",
                                             name_, size_, context_->properties().limits.maxTexelBufferElements));
    VkBufferViewCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_VIEW_CREATE_INFO};
    info.buffer = buffer_;
    info.format = VK_FORMAT_R32G32B32A32_UINT;
    info.offset = 0;
    info.range = bytes;
    VK_CHECK(vkCreateBufferView(context_->device(), &info, nullptr, &texelView_));
    return texelView_;
}

void Buffer::upload(const void* data, VkDeviceSize bytes, VkDeviceSize offset) {
    if (offset + bytes > size_)
        throw std::out_of_range(fmt::format("upload of {} bytes at {} overruns buffer '{}' ({} bytes)", bytes,
                                            offset, name_, size_));
    if (bytes == 0) return;
    if (mapped_) std::memcpy(static_cast<char*>(mapped_) + offset, data, bytes);
    else copyViaStaging(const_cast<void*>(data), bytes, offset, true);
}

void Buffer::download(void* data, VkDeviceSize bytes, VkDeviceSize offset) const {
    if (offset + bytes > size_)
        throw std::out_of_range(fmt::format("download of {} bytes at {} overruns buffer '{}' ({} bytes)", bytes,
                                            offset, name_, size_));
    if (bytes == 0) return;
    // Device-local memory that is also host-visible but uncached (a resizable-BAR GPU) is written
    // fast through the mapping and read very slowly: reads go through a HOST_CACHED staging buffer
    // there. On lavapipe and integrated GPUs the one memory type is cached and read directly.
    if (mapped_ && mappedCached_) std::memcpy(data, static_cast<const char*>(mapped_) + offset, bytes);
    else copyViaStaging(data, bytes, offset, false);
}

void Buffer::fill(uint32_t value) { fill(value, 0, VK_WHOLE_SIZE); }

void Buffer::fill(uint32_t value, VkDeviceSize offset, VkDeviceSize bytes) {
    OneTimeCommands once(*context_);
    vkCmdFillBuffer(once.cmd(), buffer_, offset, bytes, value);
    once.submit();
}

void Buffer::copyViaStaging(void* host, VkDeviceSize bytes, VkDeviceSize offset, bool toDevice) const {
    // Host-visible staging buffer for devices whose device-local memory cannot be mapped.
    VkDevice device = context_->device();
    VkBuffer staging = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    auto cleanup = [&] {
        if (staging) vkDestroyBuffer(device, staging, nullptr);
        if (memory) vkFreeMemory(device, memory, nullptr);
    };
    try {
        VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
        info.size = bytes;
        info.usage = VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
        VK_CHECK(vkCreateBuffer(device, &info, nullptr, &staging));
        VkMemoryRequirements req;
        vkGetBufferMemoryRequirements(device, staging, &req);
        // Readback prefers cached memory (coherent if there is such, else invalidated after the copy).
        const VkMemoryPropertyFlags visible = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
                                    coherent = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                    cached = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
        uint32_t type = UINT32_MAX;
        if (!toDevice) type = context_->findMemoryType(req.memoryTypeBits, visible | coherent | cached);
        if (!toDevice && type == UINT32_MAX) type = context_->findMemoryType(req.memoryTypeBits, visible | cached);
        if (type == UINT32_MAX) type = context_->findMemoryType(req.memoryTypeBits, visible | coherent);
        if (type == UINT32_MAX) throw std::runtime_error("no host-visible memory for staging");
        const bool invalidate = !context_->memoryTypeHas(type, coherent);
        VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
        alloc.allocationSize = req.size;
        alloc.memoryTypeIndex = type;
        VK_CHECK(vkAllocateMemory(device, &alloc, nullptr, &memory));
        VK_CHECK(vkBindBufferMemory(device, staging, memory, 0));
        void* p = nullptr;
        VK_CHECK(vkMapMemory(device, memory, 0, VK_WHOLE_SIZE, 0, &p));
        if (toDevice) std::memcpy(p, host, bytes);
        OneTimeCommands once(*context_);
        VkBufferCopy region{toDevice ? 0 : offset, toDevice ? offset : 0, bytes};
        if (toDevice) vkCmdCopyBuffer(once.cmd(), staging, buffer_, 1, &region);
        else vkCmdCopyBuffer(once.cmd(), buffer_, staging, 1, &region);
        once.submit();
        if (!toDevice && invalidate) {
            VkMappedMemoryRange range{VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE};
            range.memory = memory;
            range.size = VK_WHOLE_SIZE;
            VK_CHECK(vkInvalidateMappedMemoryRanges(device, 1, &range));
        }
        if (!toDevice) std::memcpy(host, p, bytes);
    } catch (...) {
        cleanup();
        throw;
    }
    cleanup();
}

OneTimeCommands::OneTimeCommands(const Context& context) : context_(context) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = context.commandPool();
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    VK_CHECK(vkAllocateCommandBuffers(context.device(), &alloc, &cmd_));
    VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VkResult r = vkBeginCommandBuffer(cmd_, &begin);
    if (r != VK_SUCCESS) {
        vkFreeCommandBuffers(context.device(), context.commandPool(), 1, &cmd_);
        VK_CHECK(r);
    }
}

OneTimeCommands::~OneTimeCommands() {
    if (cmd_) vkFreeCommandBuffers(context_.device(), context_.commandPool(), 1, &cmd_);
}

void OneTimeCommands::submit() {
    if (submitted_) return;
    VK_CHECK(vkEndCommandBuffer(cmd_));
    // Make transfer writes visible to the host and to later submissions.
    context_.submitAndWait(cmd_);
    submitted_ = true;
}

}  // namespace telescope::gpu
