// SIGINT and SIGTERM during `render`, `reference` and `view` (one handler for all of them): the
// first signal asks the render to stop
// after the running batch (a photon pass); the command then writes the EXR and the PNG of every
// completed sample and a checkpoint that also keeps a photon block in progress (Film::pending:
// --resume continues it at its next pass), and exits with 128 + the signal (130, 143). A second signal ends the process at once
// (default action); the atomic writes (core/atomic_file.h) leave no half-written output.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "session/outputs.h"
#include "render/film_io.h"

namespace telescope::session {

class InterruptGuard {
public:
    InterruptGuard();   // installs the handlers
    ~InterruptGuard();  // restores the previous ones
    InterruptGuard(const InterruptGuard&) = delete;
    InterruptGuard& operator=(const InterruptGuard&) = delete;

    static bool requested();
    static int signalNumber();       // 0 while none arrived
    static const char* signalName();  // "SIGINT", "SIGTERM"
    static int exitCode();            // 128 + the signal
};

// Writes the render's checkpoint every `intervalSeconds` of wall time (0: never), from the
// progress callback between batches. The file is replaced atomically, so `kill -9` at any moment
// leaves the last complete checkpoint.
class PeriodicCheckpoint {
public:
    PeriodicCheckpoint(double intervalSeconds, std::string path, std::function<Checkpoint()> snapshot);
    void afterBatch();
    unsigned saved() const { return saved_; }

private:
    double interval_;
    std::string path_;
    std::function<Checkpoint()> snapshot_;
    double last_;
    unsigned saved_ = 0;
};

// After a render stopped on a signal: writes the EXR, the PNG and the checkpoint (the
// --checkpoint file, or OUT.exr.checkpoint) of every completed sample, says what it saved and
// returns the exit code (130 for SIGINT, 143 for SIGTERM). Writes nothing when the render had
// added no sample and has no block in progress; only the checkpoint when it has a block in
// progress but no completed sample.
// howToContinue ends the message, e.g. "continue with --resume a.exr.checkpoint".
int saveInterrupted(ImageOutputOptions o, const Film& film, const OutputInfo& info, uint64_t newSamples,
                    const std::string& howToContinue);

// The checkpoints a render leaves when it fails at run time (a device lost, out of memory):
// main.cpp appends keptCheckpointsNote() to the error, e.g. "; the checkpoint a.exr.checkpoint
// (48 spp) is kept: continue with --resume a.exr.checkpoint". Paths that do not exist (or are not
// checkpoints) when the error is reported are left out.
void keepCheckpointsOnFailure(std::vector<std::string> paths);
std::string keptCheckpointsNote();

}  // namespace telescope::session
