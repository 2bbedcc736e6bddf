// Faults a render survives: SIGINT / SIGTERM at a random moment (every completed sample saved, a
// resumed render equal to an uninterrupted one), kill -9 (the last periodic checkpoint intact
// and resumable), an unwritable output and a full disk (exit 1 naming the path, nothing
// half-written, an older file intact), and a device out of memory (exit 1, the checkpoint kept).
#include <gtest/gtest.h>

#include <signal.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <thread>

#include "cli_process.h"
#include "render/film_io.h"
#include "render_harness.h"

namespace fs = std::filesystem;
using namespace telescope;
using namespace telescope::test;

namespace {

const char* kSmall = " --set camera.resolution=[32,24] --set integrator.max_bounces=2 -q";
// Far more samples than a test waits for: the render only ends on a signal.
const char* kEndless = " --spp 10000000";
constexpr double kTimeout = 300.0;  // seconds: a bound against hangs, never reached when correct

class Faults : public ScratchTest {
protected:
    Faults() : ScratchTest("faults") {}

    // No temporary file of an atomic write is left in the directory.
    void expectNoPartialFiles() {
        for (const auto& name : filesIn(dir_)) EXPECT_EQ(name.find(".partial"), std::string::npos) << name;
    }

    // A random moment in [0, maxSeconds), printed so a failure can be reproduced.
    double randomDelay(double maxSeconds) {
        std::random_device rd;
        const unsigned seed = rd();
        std::mt19937 gen(seed);
        const double d = std::uniform_real_distribution<double>(0.0, maxSeconds)(gen);
        std::printf("random delay %.3f s (seed %u)\n", d, seed);
        return d;
    }

    // Resuming `checkpoint` for `more` samples equals an uninterrupted render of the same seed and
    // total count. The resumed sums go through one double -> float pair round trip (Renderer::
    // resume), hence a relative tolerance; a render of another seed (the control) must fail it.
    void expectResumeEqualsUninterrupted(const std::string& checkpoint, uint64_t more) {
        const uint64_t have = loadCheckpoint(checkpoint).film.samplesPerPixel();
        ASSERT_GT(have, 0u);
        const std::string total = std::to_string(have + more);
        CommandResult r = run("render " + scene() + kSmall + " --resume " + checkpoint + " --spp " + std::to_string(more) +
                              " -o " + out("resumed.exr") + " --checkpoint " + out("resumed.ckpt"));
        ASSERT_EQ(r.exitCode, 0) << r.stderrText;
        ASSERT_EQ(run("render " + scene() + kSmall + " --spp " + total + " -o " + out("whole.exr") + " --checkpoint " +
                      out("whole.ckpt"))
                      .exitCode,
                  0);
        ASSERT_EQ(run("render " + scene() + kSmall + " --seed 99 --spp " + total + " -o " + out("control.exr") +
                      " --checkpoint " + out("control.ckpt"))
                      .exitCode,
                  0);
        const Film resumed = loadCheckpoint(out("resumed.ckpt")).film, whole = loadCheckpoint(out("whole.ckpt")).film;
        const Film control = loadCheckpoint(out("control.ckpt")).film;
        EXPECT_EQ(resumed.samplesPerPixel(), have + more);
        const double tolerance = 1e-6, floor = 1e-3 * double(have + more);
        EXPECT_LT(largestRelativeDifference(resumed, whole, floor), tolerance);
        EXPECT_GT(largestRelativeDifference(control, whole, floor), 100 * tolerance) << "the control passed";
    }

};

}  // namespace

TEST_F(Faults, SigintAtARandomMomentSavesEverySampleAndTheResumedRenderEqualsAnUninterruptedOne) {
    const std::string ckpt = out("a.exr.checkpoint");
    BackgroundTelescope render("render " + scene() + kSmall + kEndless + " --checkpoint-every 0.2 -o " + out("a.exr"),
                               out("err.txt"));
    ASSERT_TRUE(render.started());
    ASSERT_TRUE(waitForFile(ckpt, kTimeout)) << "no periodic checkpoint";
    std::this_thread::sleep_for(std::chrono::duration<double>(randomDelay(1.5)));
    render.signal(SIGINT);
    EXPECT_EQ(render.waitForExit(kTimeout), 130);
    const std::string err = readText(out("err.txt"));
    EXPECT_NE(err.find("SIGINT: saved"), std::string::npos) << err;
    EXPECT_NE(err.find(ckpt), std::string::npos) << err;
    fs::remove(out("err.txt"));
    expectNoPartialFiles();
    // The EXR, the PNG and the checkpoint hold the same samples.
    const Checkpoint c = loadCheckpoint(ckpt);
    EXPECT_EQ(exrStringAttributes(out("a.exr"))["telescope:spp"], std::to_string(c.film.samplesPerPixel()));
    EXPECT_TRUE(fs::exists(out("a.png")));
    expectResumeEqualsUninterrupted(ckpt, 3);
}

TEST_F(Faults, SigtermDuringAReferenceSavesItAndRunningAgainContinues) {
    const std::string ckpt = out("ref.exr.checkpoint");
    const std::string args = "reference " + scene() + kSmall + " --checkpoint-every 0.2 -o " + out("ref.exr");
    BackgroundTelescope reference(args + kEndless, out("err.txt"));
    ASSERT_TRUE(reference.started());
    ASSERT_TRUE(waitForFile(ckpt, kTimeout));
    std::this_thread::sleep_for(std::chrono::duration<double>(randomDelay(1.0)));
    reference.signal(SIGTERM);
    EXPECT_EQ(reference.waitForExit(kTimeout), 143);
    const std::string err = readText(out("err.txt"));
    EXPECT_NE(err.find("SIGTERM: saved"), std::string::npos) << err;
    fs::remove(out("err.txt"));
    expectNoPartialFiles();
    const uint64_t saved = loadCheckpoint(ckpt).film.samplesPerPixel();
    EXPECT_EQ(exrStringAttributes(out("ref.exr"))["telescope:spp"], std::to_string(saved));
    CommandResult r = run(args + " --spp 2");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_EQ(exrStringAttributes(out("ref.exr"))["telescope:spp"], std::to_string(saved + 2));
}

TEST_F(Faults, KillMinus9LeavesTheLastPeriodicCheckpointIntactAndNoOutputFile) {
    const std::string ckpt = out("k.ckpt");
    BackgroundTelescope render("render " + scene() + kSmall + kEndless + " --checkpoint-every 0.1 --checkpoint " + ckpt +
                                   " -o " + out("k.exr"),
                               out("err.txt"));
    ASSERT_TRUE(render.started());
    ASSERT_TRUE(waitForFile(ckpt, kTimeout));
    std::this_thread::sleep_for(std::chrono::duration<double>(randomDelay(1.0)));
    render.signal(SIGKILL);
    EXPECT_EQ(render.waitForExit(kTimeout), 128 + SIGKILL);
    fs::remove(out("err.txt"));
    // Nothing under the output names; a temporary file of a checkpoint write cut short may
    // remain under its hidden temporary name, never under k.ckpt.
    EXPECT_FALSE(fs::exists(out("k.exr")));
    EXPECT_FALSE(fs::exists(out("k.png")));
    for (const auto& name : filesIn(dir_)) EXPECT_TRUE(name == "k.ckpt" || name.rfind(".k.partial-", 0) == 0) << name;
    expectResumeEqualsUninterrupted(ckpt, 2);
}

TEST_F(Faults, AnUnwritableOutputIsARuntimeErrorNamingThePath) {
    fs::create_directories(out("a.exr"));  // a directory where the EXR should go
    CommandResult r = run("render " + scene() + kSmall + " --spp 1 -o " + out("a.exr"));
    EXPECT_EQ(r.exitCode, 1) << r.stderrText;
    EXPECT_NE(r.stderrText.find(out("a.exr")), std::string::npos) << r.stderrText;
    EXPECT_EQ(std::count(r.stderrText.begin(), r.stderrText.end(), '\n'), 1) << r.stderrText;
    expectNoPartialFiles();
    EXPECT_TRUE(fs::is_directory(out("a.exr")));
}

TEST_F(Faults, AFullDiskIsARuntimeErrorAndLeavesTheOlderFilesIntact) {
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 1 -o " + out("a.exr") + " --checkpoint " + out("a.ckpt")).exitCode, 0);
    const std::string exrBefore = readText(out("a.exr")), ckptBefore = readText(out("a.ckpt"));
    // A file-size limit of 8 KiB: writes beyond it fail with EFBIG, as on a full disk (SIGXFSZ ignored).
    for (const char* what : {" --no-png", ""}) {
        CommandResult r = runShell("trap '' XFSZ; ulimit -f 8; exec " + std::string(TELESCOPE_BINARY) + " render " +
                                       scene() + kSmall + " --seed 5 --spp 1 -o " + out("a.exr") + " --checkpoint " +
                                       out("a.ckpt") + what,
                                   dir_);
        EXPECT_EQ(r.exitCode, 1) << r.stderrText;
        EXPECT_NE(r.stderrText.find(out("a.exr")), std::string::npos) << r.stderrText;
        EXPECT_NE(r.stderrText.find("File too large"), std::string::npos) << r.stderrText;
    }
    expectNoPartialFiles();
    EXPECT_EQ(readText(out("a.exr")), exrBefore);
    EXPECT_EQ(readText(out("a.ckpt")), ckptBefore);
    // The control: without the limit the same command replaces both.
    ASSERT_EQ(run("render " + scene() + kSmall + " --seed 5 --spp 1 -o " + out("a.exr") + " --checkpoint " + out("a.ckpt")).exitCode, 0);
    EXPECT_NE(readText(out("a.exr")), exrBefore);
}

TEST_F(Faults, OutOfDeviceMemoryIsARuntimeErrorThatKeepsTheCheckpoint) {
    const std::string photon = sourcePath("scenes/point-plane-photon.json");
    const std::string ckpt = out("p.ckpt");
    ASSERT_EQ(run("render " + photon + " --set camera.resolution=[16,16] -q --spp 1 -o " + out("p.exr") + " --checkpoint " + ckpt)
                  .exitCode,
              0);
    const std::string before = readText(ckpt);
    // The largest photon count the loader accepts: its photon map does not fit.
    CommandResult r = run("render " + photon + " --set camera.resolution=[16,16] --set integrator.photon_count=134217728 -q "
                          "--spp 1 -o " + out("p.exr") + " --checkpoint " + ckpt);
    EXPECT_EQ(r.exitCode, 1) << r.stderrText;
    EXPECT_NE(r.stderrText.find("OUT_OF_DEVICE_MEMORY"), std::string::npos) << r.stderrText;
    EXPECT_NE(r.stderrText.find(ckpt + " (1 spp) is kept"), std::string::npos) << r.stderrText;
    EXPECT_EQ(readText(ckpt), before);
    expectNoPartialFiles();
}
