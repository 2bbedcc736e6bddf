#include "core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <fmt/format.h>

namespace telescope {

namespace fs = std::filesystem;

std::string temporaryPathFor(const std::string& path) {
    fs::path p(path);
    return (p.parent_path() /
            fmt::format(".{}.partial-{}{}", p.stem().string(), long(::getpid()), p.extension().string()))
        .string();
}

namespace {

// fsync the finished temporary file, so that the rename never publishes a name whose data is
// still only in the page cache (a power cut would leave an empty file under the target's name).
void syncFile(const std::string& tmp) {
    int fd = ::open(tmp.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw std::runtime_error(std::strerror(errno));
    int rc = ::fsync(fd);
    int err = errno;
    ::close(fd);
    if (rc != 0) throw std::runtime_error(std::strerror(err));
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::function<void(const std::string& tmp)>& write) {
    const std::string tmp = temporaryPathFor(path);
    try {
        write(tmp);
        syncFile(tmp);
    } catch (const std::exception& e) {
        std::remove(tmp.c_str());
        throw std::runtime_error(fmt::format("{}: write failed: {}", path, e.what()));
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        const int err = errno;
        std::remove(tmp.c_str());
        throw std::runtime_error(fmt::format("{}: cannot move the finished file into place: {}", path, std::strerror(err)));
    }
}

void writeStreamAtomically(const std::string& path, const std::function<void(std::ostream& out)>& write) {
    writeFileAtomically(path, [&](const std::string& tmp) {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        if (!out) throw std::runtime_error(std::strerror(errno));
        errno = 0;
        write(out);
        out.flush();
        if (!out) throw std::runtime_error(errno ? std::strerror(errno) : "stream error");
        out.close();
        if (out.fail()) throw std::runtime_error(errno ? std::strerror(errno) : "close failed");
    });
}

void writeTextAtomically(const std::string& path, const std::string& text) {
    writeStreamAtomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace telescope
