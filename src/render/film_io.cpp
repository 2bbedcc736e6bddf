#include "render/film_io.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

#include "core/error.h"

namespace telescope {

namespace {

constexpr char kMagic[16] = "TELESCOPE-FILM\x01";  // 15 characters and the terminating zero
constexpr uint32_t kVersion = 1;

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
    std::string tmp = path + ".partial";
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error(fmt::format("{}: cannot write checkpoint", path));
        out.write(kMagic, sizeof(kMagic));
        put(out, kVersion);
        put(out, c.film.width());
        put(out, c.film.height());
        put(out, shader::kChannelCount);
        put(out, c.film.samplesPerPixel());
        put(out, c.seed);
        putString(out, c.scene);
        putString(out, c.estimator);
        for (uint32_t ch = 0; ch < shader::kChannelCount; ++ch) {
            const auto& sums = c.film.sums(ch);
            out.write(reinterpret_cast<const char*>(sums.data()), std::streamsize(sums.size() * sizeof(sums[0])));
        }
        if (!out.flush()) {
            out.close();
            std::filesystem::remove(tmp);
            throw std::runtime_error(fmt::format("{}: checkpoint write failed", path));
        }
    }
    std::filesystem::rename(tmp, path);
}

Checkpoint loadCheckpoint(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path, "", "cannot open checkpoint");
    Reader r(in, path);
    char magic[sizeof(kMagic)];
    if (!in.read(magic, sizeof(magic)) || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0) r.fail("the header");
    if (r.get<uint32_t>("the version") != kVersion) throw InputError(path, "", "unsupported checkpoint version");
    uint32_t width = r.get<uint32_t>("the width"), height = r.get<uint32_t>("the height");
    uint32_t channels = r.get<uint32_t>("the channel count");
    if (channels != shader::kChannelCount)
        throw InputError(path, "", fmt::format("checkpoint has {} channels, this build keeps {}", channels,
                                               shader::kChannelCount));
    if (width == 0 || height == 0 || uint64_t(width) * height > (uint64_t(1) << 28))
        throw InputError(path, "", fmt::format("impossible image size {}x{}", width, height));
    Checkpoint c;
    c.film = Film(width, height);
    c.film.setSamplesPerPixel(r.get<uint64_t>("the sample count"));
    c.seed = r.get<uint32_t>("the seed");
    c.scene = r.getString("the scene", uint64_t(1) << 30);
    c.estimator = r.getString("the estimator", 1 << 20);
    for (uint32_t ch = 0; ch < channels; ++ch) {
        auto& sums = c.film.sums(ch);
        if (!in.read(reinterpret_cast<char*>(sums.data()), std::streamsize(sums.size() * sizeof(sums[0]))))
            r.fail("the pixel sums");
    }
    if (in.peek() != std::char_traits<char>::eof()) r.fail("the end of the file");
    return c;
}

}  // namespace telescope
