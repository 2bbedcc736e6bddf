#include "render/film_io.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"

namespace telescope {

namespace {

constexpr char kMagic[16] = "TELESCOPE-FILM\x01";  // 15 characters and the terminating zero
constexpr uint32_t kVersion = 3;
constexpr uint32_t kFlagPerPixelCounts = 1;
constexpr uint32_t kMaxSeeds = 1u << 20;

template <typename T>
void put(std::ostream& out, const T& v) {
    out.write(reinterpret_cast<const char*>(&v), sizeof(T));
}
void putString(std::ostream& out, const std::string& s) {
    put(out, uint64_t(s.size()));
    out.write(s.data(), std::streamsize(s.size()));
}

class Reader {
public:
    Reader(std::istream& in, const std::string& path) : in_(in), path_(path) {}
    template <typename T>
    T get(const char* what) {
        T v{};
        if (!in_.read(reinterpret_cast<char*>(&v), sizeof(T))) fail(what);
        return v;
    }
    std::string getString(const char* what, uint64_t maxSize) {
        uint64_t n = get<uint64_t>(what);
        if (n > maxSize) fail(what);
        std::string s(n, '\0');
        if (n && !in_.read(s.data(), std::streamsize(n))) fail(what);
        return s;
    }
    [[noreturn]] void fail(const char* what) {
        throw InputError(path_, "", fmt::format("not a Telescope checkpoint, or truncated (reading {})", what));
    }

private:
    std::istream& in_;
    const std::string& path_;
};

}  // namespace

void saveCheckpoint(const std::string& path, const Checkpoint& c) {
    writeStreamAtomically(path, [&](std::ostream& out) {
        out.write(kMagic, sizeof(kMagic));
        put(out, kVersion);
        put(out, c.film.width());
        put(out, c.film.height());
        put(out, shader::kChannelCount);
        put(out, c.film.samplesPerPixel());
        put(out, c.seed);
        putString(out, c.scene);
        putString(out, c.estimator);
        putString(out, c.settings);
        const std::vector<uint32_t> seeds = c.seeds.empty() ? std::vector<uint32_t>{c.seed} : c.seeds;
        put(out, uint32_t(seeds.size()));
        for (uint32_t s : seeds) put(out, s);
        put(out, c.film.perPixelCounts() ? kFlagPerPixelCounts : 0u);
        const PendingSamples& pending = c.film.pending();
        put(out, pending.unitsDone);
        put(out, pending.unitsTotal);
        put(out, pending.level);
        put(out, uint64_t(pending.device.size()));
        for (uint32_t ch = 0; ch < shader::kChannelCount; ++ch) {
            const auto& sums = c.film.sums(ch);
            out.write(reinterpret_cast<const char*>(sums.data()), std::streamsize(sums.size() * sizeof(sums[0])));
        }
        out.write(reinterpret_cast<const char*>(pending.device.data()), std::streamsize(pending.device.size()));
    });
}

namespace {

// Reads everything before the pixel sums.
CheckpointHeader readHeader(std::istream& in, Reader& r, const std::string& path) {
    char magic[sizeof(kMagic)];
    if (!in.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) r.fail("the header");
    const uint32_t version = r.get<uint32_t>("the version");
    if (version < 1 || version > kVersion)
        throw InputError(path, "", fmt::format("unsupported checkpoint version {}", version));
    CheckpointHeader h;
    h.width = r.get<uint32_t>("the width");
    h.height = r.get<uint32_t>("the height");
    uint32_t channels = r.get<uint32_t>("the channel count");
    if (channels != shader::kChannelCount)
        throw InputError(path, "", fmt::format("checkpoint has {} channels, this build keeps {}", channels,
                                               shader::kChannelCount));
    if (h.width == 0 || h.height == 0 || uint64_t(h.width) * h.height > (uint64_t(1) << 28))
        throw InputError(path, "", fmt::format("impossible image size {}x{}", h.width, h.height));
    h.samplesPerPixel = r.get<uint64_t>("the sample count");
    h.seed = r.get<uint32_t>("the seed");
    h.scene = r.getString("the scene", uint64_t(1) << 30);
    h.estimator = r.getString("the estimator", 1 << 20);
    if (version >= 2) {
        h.settings = r.getString("the settings", 1 << 24);
        const uint32_t n = r.get<uint32_t>("the seed count");
        if (n == 0 || n > kMaxSeeds) r.fail("the seed count");
        for (uint32_t i = 0; i < n; ++i) h.seeds.push_back(r.get<uint32_t>("the seeds"));
        const uint32_t flags = r.get<uint32_t>("the flags");
        if (flags & ~kFlagPerPixelCounts) r.fail("the flags");
        h.perPixelCounts = flags & kFlagPerPixelCounts;
    } else {
        h.seeds = {h.seed};
    }
    if (version >= 3) {
        h.pendingUnits = r.get<uint32_t>("the block in progress");
        h.pendingUnitsTotal = r.get<uint32_t>("the block in progress");
        h.pendingLevel = r.get<uint32_t>("the block in progress");
        h.pendingBytes = r.get<uint64_t>("the block in progress");
        if (h.pendingBytes > (uint64_t(1) << 34) || h.pendingUnits > h.pendingUnitsTotal) r.fail("the block in progress");
    }
    return h;
}

uint64_t sumsBytes(const CheckpointHeader& h) {
    return uint64_t(h.width) * h.height * shader::kChannelCount * sizeof(glm::dvec4);
}

}  // namespace

CheckpointHeader readCheckpointHeader(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot open checkpoint");
    Reader r(in, path);
    CheckpointHeader h = readHeader(in, r, path);
    std::error_code ec;
    const uint64_t size = std::filesystem::file_size(path, ec);
    if (ec || size != uint64_t(in.tellg()) + sumsBytes(h) + h.pendingBytes) r.fail("the pixel sums");
    return h;
}

Checkpoint loadCheckpoint(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot open checkpoint");
    Reader r(in, path);
    const CheckpointHeader h = readHeader(in, r, path);
    Checkpoint c;
    c.film = Film(h.width, h.height);
    c.film.setSamplesPerPixel(h.samplesPerPixel);
    c.film.setPerPixelCounts(h.perPixelCounts);
    c.seed = h.seed;
    c.scene = h.scene;
    c.estimator = h.estimator;
    c.settings = h.settings;
    c.seeds = h.seeds;
    for (uint32_t ch = 0; ch < shader::kChannelCount; ++ch) {
        auto& sums = c.film.sums(ch);
        if (!in.read(reinterpret_cast<char*>(sums.data()), std::streamsize(sums.size() * sizeof(sums[0]))))
            r.fail("the pixel sums");
    }
    PendingSamples pending;
    pending.unitsDone = h.pendingUnits;
    pending.unitsTotal = h.pendingUnitsTotal;
    pending.level = h.pendingLevel;
    pending.device.resize(h.pendingBytes);
    if (h.pendingBytes && !in.read(reinterpret_cast<char*>(pending.device.data()), std::streamsize(h.pendingBytes)))
        r.fail("the block in progress");
    c.film.setPending(std::move(pending));
    if (in.peek() != std::char_traits<char>::eof()) r.fail("the end of the file");
    return c;
}

}  // namespace telescope
