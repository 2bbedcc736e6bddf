// Compute pipelines and the command batches that run them.
//
// A ComputePipeline is one .comp shader (compiled to SPIR-V at build time) with its
// specialisation constants folded in, a descriptor set of storage buffers (binding i = buffer i)
// and a push-constant block. A CommandBatch records named dispatches with a barrier between
// consecutive ones and a timestamp after each, so every pass is timed by the name the host gave
// it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <vulkan/vulkan.h>

namespace telescope::gpu {

class Context;
class Buffer;

struct SpecConstant {
    uint32_t id;
    uint32_t value;  // bools as 0/1; floats by bit pattern (see specFloat)
};
uint32_t specFloat(float f);
float floatOfSpec(uint32_t bits);  // specFloat's inverse

// Directory holding the compiled .spv files: $TELESCOPE_SHADER_DIR, else the build tree's.
std::string shaderDirectory();

// The module with the specialisation constants' values frozen in and the code they make
// unreachable removed (SPIRV-Tools: freeze, fold, constant propagation, dead branches, dead
// functions), then inlined, its single-store locals promoted and its dead code removed. Lavapipe
// runs its NIR passes over the whole inlined module before it folds specialisation constants, so
// handing it the specialised module cuts pipeline creation of the path tracer from seconds to a
// tenth of a second, and the inlined one halves that again (docs/BENCHMARKS.md). Returns false
// (and leaves `out` empty) when the optimizer rejects the module; `error` then says why.
bool specialiseSpirv(const std::vector<uint32_t>& code, const std::vector<SpecConstant>& spec,
                     std::vector<uint32_t>& out, std::string* error = nullptr);

// Whether a function of the module takes a buffer reference (a physical-storage-buffer pointer, or
// a struct, array or pointer holding one) as a parameter: SPIRV-Tools 2023.1's aggressive
// dead-code pass crashes on calls that pass them, so specialiseSpirv skips it for such modules.
bool passesBufferReferences(const std::vector<uint32_t>& code);

// Whether ComputePipeline specialises SPIR-V on the host (default) or passes the constants to the
// driver (TELESCOPE_DRIVER_SPECIALISATION=1, for A/B measurements).
bool hostSpecialisation();

// specialiseSpirv through a cache of specialised modules on disk: with its inlining the optimizer
// would take 0.12-0.22 s of every process (the path tracer on Tungsten's Cornell box, whose
// pipeline setup is 0.05 s with the cache), so a later process reads the module it wrote instead
// (as Mesa caches what it compiles from the module).
// The directory is $TELESCOPE_CACHE_DIR, else $XDG_CACHE_HOME/telescope, else
// $HOME/.cache/telescope; TELESCOPE_SPIRV_CACHE=0 turns the cache off. An entry repeats its whole
// key (the input module's size and hash, the optimizer's version, every constant) and the hash of
// its module, so a stale, colliding, torn or damaged entry is a miss, never another module; an
// entry that cannot be read or written costs only the optimizer's time. `name` names the entry's
// file. The cache keeps under 64 MiB (the oldest entries go first).
bool specialiseSpirvCached(const std::string& name, const std::vector<uint32_t>& code,
                           const std::vector<SpecConstant>& spec, std::vector<uint32_t>& out,
                           std::string* error = nullptr);
// The cache's directory ("" when it is off or no directory is known).
std::string spirvCacheDirectory();

class ComputePipeline {
public:
    // Binding i is a storage buffer; a uniform buffer when bit i of uniformBindings is set; a
    // uniform texel buffer (Buffer::texelView, 4 x uint32 texels) when bit i of texelBindings is
    // set, a storage texel buffer when bit i of storageTexelBindings is.
    ComputePipeline(const Context& context, std::string shaderName, uint32_t bufferCount,
                    uint32_t pushConstantBytes, const std::vector<SpecConstant>& spec = {},
                    uint32_t uniformBindings = 0, uint32_t texelBindings = 0, uint32_t storageTexelBindings = 0);
    ~ComputePipeline();
    ComputePipeline(const ComputePipeline&) = delete;
    ComputePipeline& operator=(const ComputePipeline&) = delete;

    // Points binding i at buffers[i] (whole buffer; each must fit maxStorageBufferRange; a uniform
    // binding sees the first min(size, maxUniformBufferRange) bytes; a texel binding the whole
    // buffer, which must fit maxTexelBufferElements).
    void bindBuffers(const std::vector<const Buffer*>& buffers);

    const std::string& name() const { return name_; }
    VkPipeline handle() const { return pipeline_; }
    VkPipelineLayout layout() const { return layout_; }
    VkDescriptorSet descriptorSet() const { return set_; }
    uint32_t pushConstantBytes() const { return pushBytes_; }

private:
    void release();
    VkDescriptorType descriptorType(uint32_t binding) const;

    const Context& context_;
    std::string name_;
    uint32_t bufferCount_ = 0, pushBytes_ = 0, uniformBindings_ = 0, texelBindings_ = 0, storageTexelBindings_ = 0;
    VkShaderModule module_ = VK_NULL_HANDLE;
    VkDescriptorSetLayout setLayout_ = VK_NULL_HANDLE;
    VkPipelineLayout layout_ = VK_NULL_HANDLE;
    VkPipeline pipeline_ = VK_NULL_HANDLE;
    VkDescriptorPool pool_ = VK_NULL_HANDLE;
    VkDescriptorSet set_ = VK_NULL_HANDLE;
};

// The arguments of one ComputePipeline, for createComputePipelines.
struct PipelineDesc {
    std::string shaderName;
    uint32_t bufferCount = 0;
    uint32_t pushConstantBytes = 0;
    std::vector<SpecConstant> spec;
    uint32_t uniformBindings = 0;
    uint32_t texelBindings = 0;
    uint32_t storageTexelBindings = 0;
};

// Creates the pipelines on parallel host threads, returned in the order given. What a pipeline
// costs to create here is CPU work (reading and specialising the SPIR-V, the driver's translation
// to its IR), so independent pipelines overlap on the host's cores; lavapipe's LLVM compile runs
// at the first dispatch and is not covered. The first exception thrown is rethrown once every
// thread has finished.
std::vector<std::unique_ptr<ComputePipeline>> createComputePipelines(const Context& context,
                                                                     const std::vector<PipelineDesc>& descs);

struct DispatchTiming {
    std::string name;
    double gpuMs = 0.0;  // from timestamps; 0 when the device has none
};

class CommandBatch {
public:
    // maxDispatches bounds the dispatches recorded between begin() and submit().
    CommandBatch(const Context& context, uint32_t maxDispatches);
    ~CommandBatch();
    CommandBatch(const CommandBatch&) = delete;
    CommandBatch& operator=(const CommandBatch&) = delete;

    // Room for at least maxDispatches dispatches per batch (outside begin()/submitAndWait()).
    void reserve(uint32_t maxDispatches);
    void begin();
    // Records a dispatch of groups.x * groups.y * groups.z workgroups, named for timing.
    void dispatch(const ComputePipeline& pipeline, const void* push, uint32_t pushBytes, uint32_t groupsX,
                  uint32_t groupsY = 1, uint32_t groupsZ = 1, const char* name = nullptr);
    // Submits, waits, and returns the timings of this batch's dispatches in order.
    std::vector<DispatchTiming> submitAndWait();
    uint32_t recorded() const { return count_; }
    uint32_t capacity() const { return maxDispatches_; }

private:
    const Context& context_;
    uint32_t maxDispatches_;
    VkCommandBuffer cmd_ = VK_NULL_HANDLE;
    VkQueryPool queries_ = VK_NULL_HANDLE;
    uint32_t count_ = 0;
    bool recording_ = false;
    std::vector<std::string> names_;
};

}  // namespace telescope::gpu
