#include "cli_process.h"

#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>

extern char** environ;

namespace fs = std::filesystem;

namespace telescope::test {

CommandResult runShell(const std::string& command, const fs::path& scratch) {
    const std::string errFile = (scratch / ".stderr.txt").string();
    int status = std::system((command + " >/dev/null 2>" + errFile).c_str());
    CommandResult r;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.stderrText = readText(errFile);
    fs::remove(errFile);
    return r;
}

CommandResult runTelescope(const std::string& args, const fs::path& scratch) {
    return runShell(std::string(TELESCOPE_BINARY) + " " + args, scratch);
}

BackgroundTelescope::BackgroundTelescope(const std::string& args, const std::string& stderrFile) {
    const std::string cmd = "exec " + std::string(TELESCOPE_BINARY) + " " + args + " >/dev/null 2>" + stderrFile;
    const char* argv[] = {"/bin/sh", "-c", cmd.c_str(), nullptr};
    if (posix_spawn(&pid_, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ) != 0) pid_ = -1;
}

BackgroundTelescope::~BackgroundTelescope() {
    if (pid_ <= 0) return;
    kill(pid_, SIGKILL);
    int status = 0;
    waitpid(pid_, &status, 0);
}

void BackgroundTelescope::signal(int sig) {
    if (pid_ > 0) kill(pid_, sig);
}

int BackgroundTelescope::waitForExit(double timeoutSeconds) {
    if (pid_ <= 0) return -1;
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeoutSeconds);
    while (true) {
        int status = 0;
        pid_t r = waitpid(pid_, &status, WNOHANG);
        if (r == pid_) {
            pid_ = -1;
            return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        }
        if (r < 0) return -1;
        if (std::chrono::steady_clock::now() > end) return -1;  // the destructor kills it
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
}

bool waitForFile(const std::string& path, double timeoutSeconds) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeoutSeconds);
    while (!fs::exists(path)) {
        if (std::chrono::steady_clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return true;
}

std::string readText(const std::string& path) {
    std::ifstream in(path);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::vector<std::string> filesIn(const fs::path& dir) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

bool sameSums(const Film& a, const Film& b) {
    if (a.width() != b.width() || a.height() != b.height() || a.samplesPerPixel() != b.samplesPerPixel()) return false;
    for (uint32_t c = 0; c < shader::kChannelCount; ++c)
        if (a.sums(c) != b.sums(c)) return false;
    return true;
}

std::map<std::string, std::string> exrStringAttributes(const std::string& path) {
    std::map<std::string, std::string> out;
    Imf::InputFile file(path.c_str());
    for (auto it = file.header().begin(); it != file.header().end(); ++it)
        if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) out[it.name()] = s->value();
    return out;
}

}  // namespace telescope::test
