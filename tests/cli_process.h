// Running the telescope binary from tests: synchronously (exit code and stderr), or in the
// background to signal it; comparing checkpoints; reading EXR metadata (OpenEXR, no OpenImageIO).
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "render/film_io.h"

namespace telescope::test {

struct CommandResult {
    int exitCode = -1;  // -1: killed by a signal
    std::string stderrText;
};

// Runs `telescope ARGS` through /bin/sh (ARGS may use shell quoting); stdout is discarded.
CommandResult runTelescope(const std::string& args, const std::filesystem::path& scratch);
// Runs a shell command line; its stderr is returned.
CommandResult runShell(const std::string& command, const std::filesystem::path& scratch);

std::string sourcePath(const std::string& relative);  // render_harness.h

// A fixture with a fresh scratch directory per test (TMP/telescope-PREFIX-TESTNAME), removed after.
class ScratchTest : public ::testing::Test {
protected:
    explicit ScratchTest(std::string prefix) : prefix_(std::move(prefix)) {}
    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               ("telescope-" + prefix_ + "-" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    std::string out(const std::string& name) const { return (dir_ / name).string(); }
    std::string scene() const { return sourcePath("scenes/tungsten/cornell-box/scene.json"); }
    CommandResult run(const std::string& args) { return runTelescope(args, dir_); }

    std::string prefix_;
    std::filesystem::path dir_;
};

// `telescope ARGS` in the background, stderr to `stderrFile`; killed (SIGKILL) when the object
// goes out of scope unless waited for, so a failed test leaves no render running.
class BackgroundTelescope {
public:
    BackgroundTelescope(const std::string& args, const std::string& stderrFile);
    ~BackgroundTelescope();
    BackgroundTelescope(const BackgroundTelescope&) = delete;
    BackgroundTelescope& operator=(const BackgroundTelescope&) = delete;
    bool started() const { return pid_ > 0; }
    void signal(int sig);
    // The exit code, 128 + the signal that ended it, or -1 on a timeout (it is then killed).
    int waitForExit(double timeoutSeconds);

private:
    pid_t pid_ = -1;
};
// Polls until `path` exists; false after timeoutSeconds.
bool waitForFile(const std::string& path, double timeoutSeconds);

std::string readText(const std::string& path);
std::vector<std::string> filesIn(const std::filesystem::path& dir);  // names, sorted

// Every double of every channel, and the sample count, equal (bit for bit).
bool sameSums(const Film& a, const Film& b);

std::map<std::string, std::string> exrStringAttributes(const std::string& path);

}  // namespace telescope::test
