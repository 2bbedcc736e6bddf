#include "gpu/pipeline.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <future>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include <fmt/format.h>
#include <spirv-tools/libspirv.h>
#include <spirv-tools/optimizer.hpp>

#include "core/atomic_file.h"
#include "gpu/buffer.h"
#include "gpu/context.h"
#include "gpu/vk_check.h"

namespace telescope::gpu {

uint32_t specFloat(float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

float floatOfSpec(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

std::string shaderDirectory() {
    if (const char* dir = std::getenv("TELESCOPE_SHADER_DIR"); dir && *dir) return dir;
    return TELESCOPE_SHADER_DIR;
}

namespace {
std::vector<uint32_t> readSpirv(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) throw std::runtime_error(fmt::format("cannot open shader {} (is the build complete?)", path));
    std::streamsize size = in.tellg();
    if (size <= 0 || size % 4) throw std::runtime_error(fmt::format("{} is not SPIR-V", path));
    std::vector<uint32_t> code(size_t(size) / 4);
    in.seekg(0);
    in.read(reinterpret_cast<char*>(code.data()), size);
    return code;
}
}  // namespace

namespace {
enum : uint32_t {
    OpTypeArray = 28, OpTypeRuntimeArray = 29, OpTypeStruct = 30, OpTypePointer = 32, OpTypeForwardPointer = 39,
    OpFunction = 54, OpFunctionParameter = 55, OpVariable = 59, OpDecorate = 71,
    kStorageFunction = 7, kStoragePhysicalStorageBuffer = 5349,
    kDecorationRestrictPointer = 5355, kDecorationAliasedPointer = 5356,
};

// Calls f(opcode, words, word count, offset) for each instruction after the header; false where
// the module is malformed.
template <class F>
bool forEachInstruction(const std::vector<uint32_t>& code, F&& f) {
    for (size_t i = 5; i < code.size();) {
        const uint32_t count = code[i] >> 16;
        if (count == 0 || i + count > code.size()) return false;
        f(code[i] & 0xffffu, &code[i], count, i);
        i += count;
    }
    return true;
}

// The type ids that are or hold a buffer reference (types precede their uses, except the forward
// pointers buffer references are declared through).
std::unordered_set<uint32_t> bufferReferenceTypes(const std::vector<uint32_t>& code) {
    std::unordered_set<uint32_t> holds;
    forEachInstruction(code, [&](uint32_t op, const uint32_t* w, uint32_t count, size_t) {
        if (op == OpTypeForwardPointer && count >= 3 && w[2] == kStoragePhysicalStorageBuffer) {
            holds.insert(w[1]);
        } else if (op == OpTypePointer && count >= 4 && (w[2] == kStoragePhysicalStorageBuffer || holds.count(w[3]))) {
            holds.insert(w[1]);
        } else if (op == OpTypeStruct) {
            for (uint32_t k = 2; k < count; ++k)
                if (holds.count(w[k])) holds.insert(w[1]);
        } else if ((op == OpTypeArray || op == OpTypeRuntimeArray) && count >= 3 && holds.count(w[2])) {
            holds.insert(w[1]);
        }
    });
    return holds;
}

// SPIRV-Tools 2023.1's inliner declares the variables that carry a callee's buffer-reference
// result without the AliasedPointer or RestrictPointer decoration such a variable must have;
// this gives each such local AliasedPointer (what glslang gives its own: no aliasing assumed).
void decorateBufferReferenceLocals(std::vector<uint32_t>& code) {
    const std::unordered_set<uint32_t> holds = bufferReferenceTypes(code);
    std::unordered_set<uint32_t> decorated, localPointers;
    std::vector<uint32_t> missing;
    size_t firstDecorate = 0;
    forEachInstruction(code, [&](uint32_t op, const uint32_t* w, uint32_t count, size_t at) {
        if (op == OpDecorate && count >= 3) {
            if (!firstDecorate) firstDecorate = at;
            if (w[2] == kDecorationAliasedPointer || w[2] == kDecorationRestrictPointer) decorated.insert(w[1]);
        } else if (op == OpTypePointer && count >= 4 && w[2] == kStorageFunction && holds.count(w[3])) {
            localPointers.insert(w[1]);
        } else if (op == OpVariable && count >= 4 && w[3] == kStorageFunction && localPointers.count(w[1]) &&
                   !decorated.count(w[2])) {
            missing.push_back(w[2]);
        }
    });
    if (missing.empty() || !firstDecorate) return;
    std::vector<uint32_t> decorations;
    for (uint32_t id : missing) decorations.insert(decorations.end(), {(3u << 16) | OpDecorate, id, kDecorationAliasedPointer});
    code.insert(code.begin() + std::ptrdiff_t(firstDecorate), decorations.begin(), decorations.end());
}
}  // namespace

bool passesBufferReferences(const std::vector<uint32_t>& code) {
    const std::unordered_set<uint32_t> holds = bufferReferenceTypes(code);
    bool passes = false;
    const bool wellFormed = forEachInstruction(code, [&](uint32_t op, const uint32_t* w, uint32_t count, size_t) {
        if (op == OpFunctionParameter && count >= 3 && holds.count(w[1])) passes = true;
    });
    return passes || !wellFormed;
}

bool specialiseSpirv(const std::vector<uint32_t>& code, const std::vector<SpecConstant>& spec,
                     std::vector<uint32_t>& out, std::string* error) {
    out.clear();
    std::unordered_map<uint32_t, std::vector<uint32_t>> values;
    for (const auto& s : spec) values[s.id] = {s.value};  // bools: 0 false, else true
    std::string messages;
    const auto consumer = [&](spv_message_level_t level, const char*, const spv_position_t&, const char* m) {
        if (level <= SPV_MSG_ERROR) messages += std::string(m) + "\n";
    };
    spvtools::OptimizerOptions options;
    options.set_run_validator(false);  // glslang's output; the validation layer checks the result
    const auto fail = [&] {
        out.clear();
        if (error) *error = messages.empty() ? "the SPIR-V optimizer failed" : messages;
        return false;
    };
    // Constant propagation folds the branches on the frozen constants; only then can the dead
    // branches, the functions only they called and the code feeding them go. Then every function
    // whose one return ends it is inlined and the locals stored once or used in one block become
    // values, and the dead code goes: lavapipe's own inlining and NIR passes over what is left take
    // half the time (pipeline creation of the path tracer on Tungsten's Cornell box 0.13 -> 0.065
    // s, on its non-exponential scene 0.36 -> 0.14 s; every process). No merge-return (functions
    // returning early stay calls): its single-iteration loops cost lavapipe's code 3% of its speed
    // on the Cornell box.
    std::vector<uint32_t> inlined;
    {
        spvtools::Optimizer opt(SPV_ENV_VULKAN_1_2);
        opt.SetMessageConsumer(consumer);
        opt.RegisterPass(spvtools::CreateSetSpecConstantDefaultValuePass(values))
            .RegisterPass(spvtools::CreateFreezeSpecConstantValuePass())
            .RegisterPass(spvtools::CreateFoldSpecConstantOpAndCompositePass())
            .RegisterPass(spvtools::CreateCCPPass())
            .RegisterPass(spvtools::CreateDeadBranchElimPass())
            .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass())
            .RegisterPass(spvtools::CreateInlineExhaustivePass())
            .RegisterPass(spvtools::CreateEliminateDeadFunctionsPass())
            .RegisterPass(spvtools::CreateLocalSingleBlockLoadStoreElimPass())
            .RegisterPass(spvtools::CreateLocalSingleStoreElimPass());
        if (!opt.Run(code.data(), code.size(), &inlined, options) || inlined.empty()) return fail();
    }
    // SPIRV-Tools 2023.1's aggressive dead-code pass crashes on calls that pass buffer references
    // (the queued level schedule's functions that return early stay calls): it runs only where no
    // function left takes one.
    const bool deadCode = !passesBufferReferences(inlined);
    spvtools::Optimizer opt(SPV_ENV_VULKAN_1_2);
    opt.SetMessageConsumer(consumer);
    if (deadCode) opt.RegisterPass(spvtools::CreateAggressiveDCEPass());
    opt.RegisterPass(spvtools::CreateCCPPass())
        .RegisterPass(spvtools::CreateDeadBranchElimPass())
        .RegisterPass(spvtools::CreateBlockMergePass());
    if (deadCode) opt.RegisterPass(spvtools::CreateAggressiveDCEPass());
    if (!opt.Run(inlined.data(), inlined.size(), &out, options) || out.empty()) return fail();
    decorateBufferReferenceLocals(out);
    return true;
}

// ---- Specialised modules on disk ----
namespace {
constexpr uint32_t kCacheMagic = 0x43505354u;  // "TSPC"
constexpr uint32_t kCacheFormat = 2u;  // bump with every change to specialiseSpirv's passes

uint64_t fnv1a(const void* data, size_t bytes, uint64_t h = 0xcbf29ce484222325ull) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
    return h;
}

// The header an entry starts with: everything the specialised module depends on.
std::vector<uint32_t> cacheKey(const std::vector<uint32_t>& code, const std::vector<SpecConstant>& spec) {
    const uint64_t codeHash = fnv1a(code.data(), code.size() * 4);
    const std::string tools = spvSoftwareVersionString();
    const uint64_t toolsHash = fnv1a(tools.data(), tools.size());
    std::vector<uint32_t> key = {kCacheMagic,         kCacheFormat,           uint32_t(code.size()),
                                 uint32_t(codeHash),  uint32_t(codeHash >> 32), uint32_t(toolsHash),
                                 uint32_t(toolsHash >> 32), uint32_t(spec.size())};
    for (const auto& s : spec) {
        key.push_back(s.id);
        key.push_back(s.value);
    }
    return key;
}
// Keeps the cache under kCacheBytes: after a write that passes it, the least recently written
// entries go until it holds three quarters of it (renders that sweep a constant leave one entry
// per value).
constexpr uintmax_t kCacheBytes = uintmax_t(64) << 20;
void trimSpirvCache(const std::string& dir) {
    namespace fs = std::filesystem;
    std::vector<std::pair<fs::file_time_type, fs::path>> files;
    uintmax_t total = 0;
    for (const auto& e : fs::directory_iterator(dir)) {
        if (!e.is_regular_file() || e.path().extension() != ".spv") continue;
        total += e.file_size();
        files.emplace_back(e.last_write_time(), e.path());
    }
    if (total <= kCacheBytes) return;
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
        if (total <= kCacheBytes / 4 * 3) break;
        std::error_code ec;
        const uintmax_t size = fs::file_size(f.second, ec);
        if (!ec && fs::remove(f.second, ec)) total -= size;
    }
}
}  // namespace

std::string spirvCacheDirectory() {
    if (const char* off = std::getenv("TELESCOPE_SPIRV_CACHE"); off && std::string(off) == "0") return "";
    if (const char* dir = std::getenv("TELESCOPE_CACHE_DIR"); dir && *dir) return dir;
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) return std::string(xdg) + "/telescope";
    if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.cache/telescope";
    return "";
}

bool specialiseSpirvCached(const std::string& name, const std::vector<uint32_t>& code,
                           const std::vector<SpecConstant>& spec, std::vector<uint32_t>& out, std::string* error) {
    const std::string dir = spirvCacheDirectory();
    if (dir.empty()) return specialiseSpirv(code, spec, out, error);
    const std::vector<uint32_t> key = cacheKey(code, spec);
    const std::string path =
        fmt::format("{}/{}-{:016x}.spv", dir, name, fnv1a(key.data(), key.size() * 4));
    // An entry: the key, the module's size and hash (a torn or damaged entry is a miss), the module.
    {
        std::ifstream in(path, std::ios::binary | std::ios::ate);
        const std::streamsize size = in ? std::streamsize(in.tellg()) : std::streamsize(0);
        const size_t head = key.size() + 3;
        if (in && size > std::streamsize(head * 4) && size % 4 == 0) {
            std::vector<uint32_t> entry(size_t(size) / 4);
            in.seekg(0);
            if (in.read(reinterpret_cast<char*>(entry.data()), size) &&
                std::equal(key.begin(), key.end(), entry.begin()) && entry[key.size()] == entry.size() - head) {
                const uint64_t hash = fnv1a(entry.data() + head, (entry.size() - head) * 4);
                if (entry[key.size() + 1] == uint32_t(hash) && entry[key.size() + 2] == uint32_t(hash >> 32) &&
                    entry[head] == 0x07230203u) {
                    out.assign(entry.begin() + std::ptrdiff_t(head), entry.end());
                    return true;
                }
            }
        }
    }
    if (!specialiseSpirv(code, spec, out, error)) return false;
    try {
        std::filesystem::create_directories(dir);
        const uint64_t hash = fnv1a(out.data(), out.size() * 4);
        const uint32_t body[3] = {uint32_t(out.size()), uint32_t(hash), uint32_t(hash >> 32)};
        writeStreamAtomically(path, [&](std::ostream& o) {
            o.write(reinterpret_cast<const char*>(key.data()), std::streamsize(key.size() * 4));
            o.write(reinterpret_cast<const char*>(body), sizeof(body));
            o.write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size() * 4));
        });
        trimSpirvCache(dir);
    } catch (const std::exception&) {
        // A cache that cannot be written (read-only home, full disk) costs the optimizer's time only.
    }
    return true;
}

bool hostSpecialisation() {
    const char* v = std::getenv("TELESCOPE_DRIVER_SPECIALISATION");
    return !(v && *v && std::string(v) != "0");
}

// ---- ComputePipeline ----

ComputePipeline::ComputePipeline(const Context& context, std::string shaderName, uint32_t bufferCount,
                                 uint32_t pushConstantBytes, const std::vector<SpecConstant>& spec,
                                 uint32_t uniformBindings, uint32_t texelBindings, uint32_t storageTexelBindings)
    : context_(context), name_(std::move(shaderName)), bufferCount_(bufferCount), pushBytes_(pushConstantBytes),
      uniformBindings_(uniformBindings), texelBindings_(texelBindings), storageTexelBindings_(storageTexelBindings) {
    VkDevice device = context.device();
    try {
        auto code = readSpirv(shaderDirectory() + "/" + name_ + ".spv");
        bool specialised = false;
        if (!spec.empty() && hostSpecialisation()) {
            std::vector<uint32_t> out;
            // On failure the driver specialises the original module (slower to create, same code).
            if (specialiseSpirvCached(name_, code, spec, out)) {
                code = std::move(out);
                specialised = true;
            }
        }
        // Debugging aid: TELESCOPE_DUMP_SPIRV=DIR writes the module the driver gets.
        if (const char* dump = std::getenv("TELESCOPE_DUMP_SPIRV"); dump && *dump) {
            std::ofstream f(fmt::format("{}/{}-{:08x}.spv", dump, name_, std::hash<std::string>{}(std::string(
                                            reinterpret_cast<const char*>(code.data()), code.size() * 4)) & 0xffffffffu),
                            std::ios::binary);
            f.write(reinterpret_cast<const char*>(code.data()), std::streamsize(code.size() * 4));
        }
        VkShaderModuleCreateInfo moduleInfo{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
        moduleInfo.codeSize = code.size() * 4;
        moduleInfo.pCode = code.data();
        VK_CHECK(vkCreateShaderModule(device, &moduleInfo, nullptr, &module_));

        std::vector<VkDescriptorSetLayoutBinding> bindings(bufferCount);
        const VkDescriptorType types[4] = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
                                           VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER};
        uint32_t typeCounts[4] = {0, 0, 0, 0};
        for (uint32_t i = 0; i < bufferCount; ++i) {
            bindings[i] = {i, descriptorType(i), 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
            for (int t = 0; t < 4; ++t) typeCounts[t] += types[t] == descriptorType(i);
        }
        VkDescriptorSetLayoutCreateInfo setInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
        setInfo.bindingCount = bufferCount;
        setInfo.pBindings = bindings.data();
        VK_CHECK(vkCreateDescriptorSetLayout(device, &setInfo, nullptr, &setLayout_));

        VkPushConstantRange range{VK_SHADER_STAGE_COMPUTE_BIT, 0, pushConstantBytes};
        VkPipelineLayoutCreateInfo layoutInfo{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
        layoutInfo.setLayoutCount = 1;
        layoutInfo.pSetLayouts = &setLayout_;
        layoutInfo.pushConstantRangeCount = pushConstantBytes ? 1 : 0;
        layoutInfo.pPushConstantRanges = &range;
        VK_CHECK(vkCreatePipelineLayout(device, &layoutInfo, nullptr, &layout_));

        std::vector<VkSpecializationMapEntry> entries;
        std::vector<uint32_t> values;
        for (const auto& s : spec) {
            entries.push_back({s.id, uint32_t(values.size() * 4), 4});
            values.push_back(s.value);
        }
        VkSpecializationInfo specInfo{uint32_t(entries.size()), entries.data(), values.size() * 4, values.data()};
        VkComputePipelineCreateInfo info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
        info.stage.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO;
        info.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
        info.stage.module = module_;
        info.stage.pName = "main";
        info.stage.pSpecializationInfo = entries.empty() || specialised ? nullptr : &specInfo;
        info.layout = layout_;
        VK_CHECK(vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &info, nullptr, &pipeline_));

        if (bufferCount) {
            std::vector<VkDescriptorPoolSize> sizes;
            for (int t = 0; t < 4; ++t)
                if (typeCounts[t]) sizes.push_back({types[t], typeCounts[t]});
            VkDescriptorPoolCreateInfo poolInfo{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
            poolInfo.maxSets = 1;
            poolInfo.poolSizeCount = uint32_t(sizes.size());
            poolInfo.pPoolSizes = sizes.data();
            VK_CHECK(vkCreateDescriptorPool(device, &poolInfo, nullptr, &pool_));
            VkDescriptorSetAllocateInfo alloc{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
            alloc.descriptorPool = pool_;
            alloc.descriptorSetCount = 1;
            alloc.pSetLayouts = &setLayout_;
            VK_CHECK(vkAllocateDescriptorSets(device, &alloc, &set_));
        }
    } catch (...) {
        release();
        throw;
    }
}

ComputePipeline::~ComputePipeline() { release(); }

VkDescriptorType ComputePipeline::descriptorType(uint32_t binding) const {
    if ((texelBindings_ >> binding) & 1u) return VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER;
    if ((storageTexelBindings_ >> binding) & 1u) return VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER;
    return (uniformBindings_ >> binding) & 1u ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
}

void ComputePipeline::release() {
    VkDevice device = context_.device();
    if (pool_) vkDestroyDescriptorPool(device, pool_, nullptr);
    if (pipeline_) vkDestroyPipeline(device, pipeline_, nullptr);
    if (layout_) vkDestroyPipelineLayout(device, layout_, nullptr);
    if (setLayout_) vkDestroyDescriptorSetLayout(device, setLayout_, nullptr);
    if (module_) vkDestroyShaderModule(device, module_, nullptr);
    pool_ = VK_NULL_HANDLE;
    pipeline_ = VK_NULL_HANDLE;
    layout_ = VK_NULL_HANDLE;
    setLayout_ = VK_NULL_HANDLE;
    module_ = VK_NULL_HANDLE;
}

void ComputePipeline::bindBuffers(const std::vector<const Buffer*>& buffers) {
    if (buffers.size() != bufferCount_)
        throw std::logic_error(fmt::format("pipeline {} takes {} buffers, got {}", name_, bufferCount_, buffers.size()));
    const VkDeviceSize maxRange = context_.properties().limits.maxStorageBufferRange;
    const VkDeviceSize maxUniformRange = context_.properties().limits.maxUniformBufferRange;
    std::vector<VkDescriptorBufferInfo> infos(buffers.size());
    std::vector<VkBufferView> views(buffers.size());
    std::vector<VkWriteDescriptorSet> writes(buffers.size());
    for (size_t i = 0; i < buffers.size(); ++i) {
        const VkDescriptorType type = descriptorType(uint32_t(i));
        writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
        writes[i].dstSet = set_;
        writes[i].dstBinding = uint32_t(i);
        writes[i].descriptorCount = 1;
        writes[i].descriptorType = type;
        if (type == VK_DESCRIPTOR_TYPE_UNIFORM_TEXEL_BUFFER || type == VK_DESCRIPTOR_TYPE_STORAGE_TEXEL_BUFFER) {
            views[i] = buffers[i]->texelView();
            writes[i].pTexelBufferView = &views[i];
            continue;
        }
        if (type == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER) {
            infos[i] = {buffers[i]->handle(), 0, std::min(buffers[i]->size(), maxUniformRange)};
        } else {
            if (buffers[i]->size() > maxRange)
                throw std::runtime_error(fmt::format(
                    "buffer '{}' ({} bytes) exceeds the storage-buffer binding limit ({} bytes); reach it by device address",
                    buffers[i]->name(), buffers[i]->size(), maxRange));
            infos[i] = {buffers[i]->handle(), 0, VK_WHOLE_SIZE};
        }
        writes[i].pBufferInfo = &infos[i];
    }
    vkUpdateDescriptorSets(context_.device(), uint32_t(writes.size()), writes.data(), 0, nullptr);
}

std::vector<std::unique_ptr<ComputePipeline>> createComputePipelines(const Context& context,
                                                                     const std::vector<PipelineDesc>& descs) {
    std::vector<std::future<std::unique_ptr<ComputePipeline>>> pending;
    pending.reserve(descs.size());
    for (const PipelineDesc& d : descs)
        pending.push_back(std::async(std::launch::async, [&context, &d] {
            return std::make_unique<ComputePipeline>(context, d.shaderName, d.bufferCount, d.pushConstantBytes, d.spec,
                                                     d.uniformBindings, d.texelBindings, d.storageTexelBindings);
        }));
    std::vector<std::unique_ptr<ComputePipeline>> out;
    std::exception_ptr error;
    for (auto& f : pending) {
        try {
            out.push_back(f.get());
        } catch (...) {
            if (!error) error = std::current_exception();
        }
    }
    if (error) std::rethrow_exception(error);
    return out;
}

// ---- CommandBatch ----

CommandBatch::CommandBatch(const Context& context, uint32_t maxDispatches)
    : context_(context), maxDispatches_(maxDispatches) {
    VkCommandBufferAllocateInfo alloc{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    alloc.commandPool = context.commandPool();
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    VK_CHECK(vkAllocateCommandBuffers(context.device(), &alloc, &cmd_));
    if (context.timestampsSupported()) {
        VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        info.queryType = VK_QUERY_TYPE_TIMESTAMP;
        info.queryCount = maxDispatches + 1;
        VkResult r = vkCreateQueryPool(context.device(), &info, nullptr, &queries_);
        if (r != VK_SUCCESS) {
            vkFreeCommandBuffers(context.device(), context.commandPool(), 1, &cmd_);
            VK_CHECK(r);
        }
    }
}

void CommandBatch::reserve(uint32_t maxDispatches) {
    if (maxDispatches <= maxDispatches_) return;
    if (recording_) throw std::logic_error("CommandBatch::reserve while recording");
    if (queries_) {
        VkQueryPoolCreateInfo info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
        info.queryType = VK_QUERY_TYPE_TIMESTAMP;
        info.queryCount = maxDispatches + 1;
        VkQueryPool pool = VK_NULL_HANDLE;
        VK_CHECK(vkCreateQueryPool(context_.device(), &info, nullptr, &pool));
        vkDestroyQueryPool(context_.device(), queries_, nullptr);
        queries_ = pool;
    }
    maxDispatches_ = maxDispatches;
}

CommandBatch::~CommandBatch() {
    if (queries_) vkDestroyQueryPool(context_.device(), queries_, nullptr);
    if (cmd_) vkFreeCommandBuffers(context_.device(), context_.commandPool(), 1, &cmd_);
}

void CommandBatch::begin() {
    VK_CHECK(vkResetCommandBuffer(cmd_, 0));
    VkCommandBufferBeginInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    info.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    VK_CHECK(vkBeginCommandBuffer(cmd_, &info));
    if (queries_) {
        vkCmdResetQueryPool(cmd_, queries_, 0, maxDispatches_ + 1);
        vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries_, 0);
    }
    count_ = 0;
    names_.clear();
    recording_ = true;
}

void CommandBatch::dispatch(const ComputePipeline& pipeline, const void* push, uint32_t pushBytes,
                            uint32_t groupsX, uint32_t groupsY, uint32_t groupsZ, const char* name) {
    if (!recording_) throw std::logic_error("CommandBatch::dispatch outside begin()/submitAndWait()");
    if (count_ >= maxDispatches_)
        throw std::logic_error(fmt::format("CommandBatch holds at most {} dispatches", maxDispatches_));
    if (pushBytes != pipeline.pushConstantBytes())
        throw std::logic_error(fmt::format("pipeline {}: {} push-constant bytes, expected {}", pipeline.name(),
                                           pushBytes, pipeline.pushConstantBytes()));
    const auto& limits = context_.properties().limits;
    if (groupsX > limits.maxComputeWorkGroupCount[0] || groupsY > limits.maxComputeWorkGroupCount[1] ||
        groupsZ > limits.maxComputeWorkGroupCount[2])
        throw std::runtime_error(fmt::format("dispatch {} of {}x{}x{} workgroups exceeds the device limit",
                                             pipeline.name(), groupsX, groupsY, groupsZ));
    {
        // Each pass sees the writes of every pass before it, in this batch or an earlier one.
        VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
        barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        barrier.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT;
        vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1,
                             &barrier, 0, nullptr, 0, nullptr);
    }
    vkCmdBindPipeline(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.handle());
    VkDescriptorSet set = pipeline.descriptorSet();
    if (set)
        vkCmdBindDescriptorSets(cmd_, VK_PIPELINE_BIND_POINT_COMPUTE, pipeline.layout(), 0, 1, &set, 0, nullptr);
    if (pushBytes) vkCmdPushConstants(cmd_, pipeline.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, pushBytes, push);
    vkCmdDispatch(cmd_, groupsX, groupsY, groupsZ);
    ++count_;
    if (queries_) vkCmdWriteTimestamp(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, queries_, count_);
    names_.push_back(name ? name : pipeline.name());
}

std::vector<DispatchTiming> CommandBatch::submitAndWait() {
    if (!recording_) throw std::logic_error("CommandBatch::submitAndWait without begin()");
    recording_ = false;
    // Results are read by the host after the batch: make shader writes visible to it.
    VkMemoryBarrier barrier{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
    barrier.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    barrier.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cmd_, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &barrier, 0,
                         nullptr, 0, nullptr);
    VK_CHECK(vkEndCommandBuffer(cmd_));
    context_.submitAndWait(cmd_);

    std::vector<DispatchTiming> out(count_);
    for (uint32_t i = 0; i < count_; ++i) out[i].name = names_[i];
    if (queries_ && count_) {
        std::vector<uint64_t> stamps(count_ + 1);
        VK_CHECK(vkGetQueryPoolResults(context_.device(), queries_, 0, count_ + 1, stamps.size() * 8, stamps.data(), 8,
                                       VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
        for (uint32_t i = 0; i < count_; ++i)
            out[i].gpuMs = double(stamps[i + 1] - stamps[i]) * context_.timestampPeriodNs() * 1e-6;
    }
    return out;
}

}  // namespace telescope::gpu
