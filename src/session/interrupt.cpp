#include "session/interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <utility>

#include <fmt/format.h>

#include "core/error.h"

namespace telescope::session {

namespace {

volatile sig_atomic_t gSignal = 0;
struct sigaction gOldInt, gOldTerm;

void onSignal(int sig) {
    gSignal = sig;
    static const char msg[] =
        "\ntelescope: interrupted: stopping after the running batch (signal again to quit at once)\n";
    ssize_t ignored = ::write(STDERR_FILENO, msg, sizeof(msg) - 1);
    (void)ignored;
}

double now() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

InterruptGuard::InterruptGuard() {
    gSignal = 0;
    struct sigaction sa {};
    sa.sa_handler = onSignal;
    sigemptyset(&sa.sa_mask);
    // Restart interrupted system calls (the fence wait, file writes); the second signal gets the
    // default action.
    sa.sa_flags = SA_RESTART | SA_RESETHAND;
    sigaction(SIGINT, &sa, &gOldInt);
    sigaction(SIGTERM, &sa, &gOldTerm);
}

InterruptGuard::~InterruptGuard() {
    sigaction(SIGINT, &gOldInt, nullptr);
    sigaction(SIGTERM, &gOldTerm, nullptr);
}

bool InterruptGuard::requested() { return gSignal != 0; }
int InterruptGuard::signalNumber() { return gSignal; }
const char* InterruptGuard::signalName() {
    return gSignal == SIGINT ? "SIGINT" : gSignal == SIGTERM ? "SIGTERM" : "no signal";
}
int InterruptGuard::exitCode() { return 128 + gSignal; }

PeriodicCheckpoint::PeriodicCheckpoint(double intervalSeconds, std::string path, std::function<Checkpoint()> snapshot)
    : interval_(intervalSeconds), path_(std::move(path)), snapshot_(std::move(snapshot)), last_(now()) {}

void PeriodicCheckpoint::afterBatch() {
    if (interval_ <= 0.0 || path_.empty() || now() - last_ < interval_) return;
    saveCheckpoint(path_, snapshot_());
    last_ = now();
    ++saved_;
}

int saveInterrupted(ImageOutputOptions o, const Film& film, const OutputInfo& info, uint64_t newSamples,
                    const std::string& howToContinue) {
    const char* sig = InterruptGuard::signalName();
    const PendingSamples& block = film.pending();
    if (newSamples == 0 && block.unitsDone == 0) {
        fmt::print(stderr, "telescope: {}: interrupted before a sample was completed; nothing saved\n", sig);
        return InterruptGuard::exitCode();
    }
    if (o.checkpointPath.empty()) o.checkpointPath = o.exrPath + ".checkpoint";
    const std::string inProgress =
        block.unitsDone ? " (with " + pendingBlockText(film.samplesPerPixel(), block.level, block.unitsDone, block.unitsTotal) + ")"
                        : std::string();
    // Printed even with -q: files changed.
    if (film.samplesPerPixel() == 0) {
        // Only a block in progress: nothing to show yet, but its passes are kept.
        saveCheckpoint(o.checkpointPath, checkpointOf(film, info));
        fmt::print(stderr, "telescope: {}: no sample completed yet, so no image; saved the checkpoint {}{}; {}\n", sig,
                   o.checkpointPath, inProgress, howToContinue);
        return InterruptGuard::exitCode();
    }
    writeImages(o, film, info);
    fmt::print(stderr, "telescope: {}: saved {} spp ({} new) to {}{} and the checkpoint {}{}; {}\n", sig,
               film.samplesPerPixel(), newSamples, o.exrPath, o.noPng ? "" : ", " + o.pngPath, o.checkpointPath,
               inProgress, howToContinue);
    return InterruptGuard::exitCode();
}

namespace {
std::vector<std::string> gKeptCheckpoints;
}

void keepCheckpointsOnFailure(std::vector<std::string> paths) { gKeptCheckpoints = std::move(paths); }

std::string keptCheckpointsNote() {
    std::string s;
    for (const auto& p : gKeptCheckpoints) {
        if (p.empty() || !std::filesystem::exists(p)) continue;
        try {
            const CheckpointHeader c = readCheckpointHeader(p);
            s += fmt::format("; the checkpoint {} ({} spp) is kept: continue with --resume {}", p, c.samplesPerPixel, p);
        } catch (const std::exception&) {
            // Not a checkpoint this build reads: say nothing about it.
        }
    }
    return s;
}

}  // namespace telescope::session
