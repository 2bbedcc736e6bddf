// The cache of specialised SPIR-V modules (gpu/pipeline.h specialiseSpirvCached): a later call
// reads what an earlier one wrote, and an entry that does not match its key, or whose module was
// damaged, is a miss that the optimizer replaces, never another module.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <vector>

#include <unistd.h>

#include <spirv-tools/libspirv.hpp>

#include "gpu/pipeline.h"
#include "shared/gpu_types.h"

namespace telescope {
namespace {

namespace fs = std::filesystem;

std::vector<uint32_t> readWords(const fs::path& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    std::vector<uint32_t> words(size_t(in.tellg()) / 4);
    in.seekg(0);
    in.read(reinterpret_cast<char*>(words.data()), std::streamsize(words.size() * 4));
    return words;
}

void writeWords(const fs::path& path, const std::vector<uint32_t>& words) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(words.data()), std::streamsize(words.size() * 4));
}

class SpirvCache : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("telescope-spirv-cache-test-" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        setenv("TELESCOPE_CACHE_DIR", dir_.c_str(), 1);
        unsetenv("TELESCOPE_SPIRV_CACHE");
        code_ = readWords(fs::path(gpu::shaderDirectory()) / "level_count.spv");
        ASSERT_GT(code_.size(), 5u);
    }
    void TearDown() override {
        unsetenv("TELESCOPE_CACHE_DIR");
        unsetenv("TELESCOPE_SPIRV_CACHE");
        fs::remove_all(dir_);
    }
    std::vector<fs::path> entries() const {
        std::vector<fs::path> out;
        if (fs::exists(dir_))
            for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path());
        return out;
    }

    fs::path dir_;
    std::vector<uint32_t> code_;
    const std::vector<gpu::SpecConstant> spec_ = {{shader::kSpecPmfType, 1}, {shader::kSpecPmfR, gpu::specFloat(0.5f)}};
};

TEST_F(SpirvCache, ALaterCallReadsTheEntryAndADamagedOneIsReplaced) {
    std::vector<uint32_t> direct, first, second;
    ASSERT_TRUE(gpu::specialiseSpirv(code_, spec_, direct));
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, first));
    EXPECT_EQ(first, direct);
    ASSERT_EQ(entries().size(), 1u);
    const fs::path entry = entries()[0];
    const std::vector<uint32_t> written = readWords(entry);
    ASSERT_GT(written.size(), direct.size());

    // Read, not recomputed: the entry's module replaced by another valid module (its size and
    // FNV-1a hash in the three words before it) is what a later call returns.
    std::vector<gpu::SpecConstant> other = spec_;
    other[1].value = gpu::specFloat(0.25f);
    std::vector<uint32_t> otherModule;
    ASSERT_TRUE(gpu::specialiseSpirv(code_, other, otherModule));
    ASSERT_NE(otherModule, direct);
    const size_t head = written.size() - direct.size();
    std::vector<uint32_t> swapped(written.begin(), written.begin() + std::ptrdiff_t(head));
    uint64_t hash = 0xcbf29ce484222325ull;
    for (uint32_t w : otherModule)
        for (int b = 0; b < 4; ++b) hash = (hash ^ ((w >> (8 * b)) & 0xffu)) * 0x100000001b3ull;
    swapped[head - 3] = uint32_t(otherModule.size());
    swapped[head - 2] = uint32_t(hash);
    swapped[head - 1] = uint32_t(hash >> 32);
    swapped.insert(swapped.end(), otherModule.begin(), otherModule.end());
    writeWords(entry, swapped);
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, second));
    EXPECT_EQ(second, otherModule) << "the entry was not read";
    writeWords(entry, written);
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, second));
    EXPECT_EQ(second, direct);

    // One word of the module flipped: the module's hash no longer matches, so a miss; the
    // optimizer's module is returned and the entry rewritten whole.
    std::vector<uint32_t> damaged = written;
    damaged[damaged.size() - 2] ^= 0x10u;
    writeWords(entry, damaged);
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, second));
    EXPECT_EQ(second, direct);
    EXPECT_EQ(readWords(entry), written);

    // Cut short (a torn write): a miss.
    writeWords(entry, std::vector<uint32_t>(written.begin(), written.begin() + std::ptrdiff_t(written.size() / 2)));
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, second));
    EXPECT_EQ(second, direct);
    EXPECT_EQ(readWords(entry), written);
}

TEST_F(SpirvCache, OtherConstantsOrAnotherModuleAreOtherEntries) {
    std::vector<uint32_t> a, b, c;
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, a));
    std::vector<gpu::SpecConstant> other = spec_;
    other[1].value = gpu::specFloat(0.25f);
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, other, b));
    EXPECT_NE(a, b) << "another pmf parameter must give another module";
    EXPECT_EQ(entries().size(), 2u);

    // An entry under the right file name whose key names another module (a colliding name): a miss.
    std::vector<uint32_t> want;
    ASSERT_TRUE(gpu::specialiseSpirv(code_, other, want));
    EXPECT_EQ(b, want);
    for (const fs::path& e : entries()) {
        std::vector<uint32_t> words = readWords(e);
        words[3] ^= 1u;  // the input module's hash in the key
        writeWords(e, words);
    }
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, other, c));
    EXPECT_EQ(c, want);
}

TEST_F(SpirvCache, KeepsUnder64MiBByDroppingTheOldest) {
    // 70 stale entries of 1 MiB, oldest first; a write past 64 MiB trims to 48 MiB from the oldest.
    fs::create_directories(dir_);
    const std::vector<uint32_t> mib(1u << 18, 0u);
    const auto now = fs::file_time_type::clock::now();
    for (int i = 0; i < 70; ++i) {
        const fs::path p = dir_ / ("stale-" + std::to_string(i) + ".spv");
        writeWords(p, mib);
        fs::last_write_time(p, now - std::chrono::hours(100 - i));
    }
    std::vector<uint32_t> out;
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, out));
    uintmax_t total = 0;
    int stale = 0;
    bool newest = false, oldest = false;
    for (const fs::path& e : entries()) {
        total += fs::file_size(e);
        const std::string name = e.filename().string();
        stale += name.rfind("stale-", 0) == 0;
        newest = newest || name == "stale-69.spv";
        oldest = oldest || name == "stale-0.spv";
    }
    EXPECT_LE(total, uintmax_t(48) << 20);
    EXPECT_GE(stale, 46);
    EXPECT_TRUE(newest);
    EXPECT_FALSE(oldest);
    const std::vector<fs::path> left = entries();
    EXPECT_TRUE(std::any_of(left.begin(), left.end(), [](const fs::path& e) {
        return e.filename().string().rfind("level_count-", 0) == 0;
    })) << "the new entry stays";
}

TEST_F(SpirvCache, OffWritesNothing) {
    setenv("TELESCOPE_SPIRV_CACHE", "0", 1);
    EXPECT_EQ(gpu::spirvCacheDirectory(), "");
    std::vector<uint32_t> out;
    ASSERT_TRUE(gpu::specialiseSpirvCached("level_count", code_, spec_, out));
    EXPECT_TRUE(entries().empty());
}

size_t countOps(const std::vector<uint32_t>& code, uint32_t opcode) {
    size_t n = 0;
    for (size_t i = 5; i < code.size() && (code[i] >> 16) > 0; i += code[i] >> 16) n += (code[i] & 0xffffu) == opcode;
    return n;
}

// Every shipped module comes out of the optimizer as valid SPIR-V: each with its constants'
// defaults (the path tracer then inlined), and the path tracer with the queued level schedule and
// with a loop budget, whose functions take and return buffer references (SPIRV-Tools 2023.1's
// inliner leaves the locals carrying them undecorated, which the validator rejects, and its
// dead-code pass crashes on calls passing them).
TEST(SpecialiseSpirv, EveryShaderComesOutValidAndThePathTracerInlined) {
    constexpr uint32_t kOpFunction = 54;
    spvtools::SpirvTools tools(SPV_ENV_VULKAN_1_2);
    std::string messages;
    tools.SetMessageConsumer([&](spv_message_level_t, const char*, const spv_position_t&, const char* m) {
        messages += std::string(m) + "\n";
    });
    spvtools::ValidatorOptions options;
    options.SetScalarBlockLayout(true);
    const auto check = [&](const fs::path& path, const std::vector<uint32_t>& code,
                           const std::vector<gpu::SpecConstant>& spec) {
        std::vector<uint32_t> out;
        std::string error;
        EXPECT_TRUE(gpu::specialiseSpirv(code, spec, out, &error)) << path << ": " << error;
        messages.clear();
        EXPECT_TRUE(tools.Validate(out.data(), out.size(), options)) << path << ": " << messages;
        EXPECT_LE(countOps(out, kOpFunction), countOps(code, kOpFunction)) << path;
        return out;
    };
    int modules = 0;
    for (const auto& e : fs::directory_iterator(gpu::shaderDirectory())) {
        if (e.path().extension() != ".spv") continue;
        ++modules;
        const std::vector<uint32_t> code = readWords(e.path());
        const std::vector<uint32_t> out = check(e.path(), code, {});
        if (e.path().stem() != "path_trace") continue;
        EXPECT_LT(countOps(out, kOpFunction) * 4, countOps(code, kOpFunction)) << "the path tracer was not inlined";
        check(e.path(), code, {{shader::kSpecDebiasMode, shader::kDebiasSingleTerm}, {shader::kSpecLevelSchedule, shader::kLevelScheduleQueued}});
        check(e.path(), code, {{shader::kSpecLoopBudget, 4096u}});
    }
    EXPECT_GE(modules, 8);
}

// The check that keeps the dead-code pass away: the path tracer's unspecialised module passes
// buffer references to functions (the pass crashes on it), the transmittance study's none.
TEST(SpecialiseSpirv, FindsFunctionsTakingBufferReferences) {
    const fs::path dir = gpu::shaderDirectory();
    EXPECT_TRUE(gpu::passesBufferReferences(readWords(dir / "path_trace.spv")));
    EXPECT_FALSE(gpu::passesBufferReferences(readWords(dir / "transmittance_study.spv")));
}

}  // namespace
}  // namespace telescope
