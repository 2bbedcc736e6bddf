// What the benchmark programs share: one Vulkan context, and a main that runs the registered
// benchmarks with the console output and, given --markdown=FILE, writes the device line and the
// program's markdown tables to FILE (bench/run assembles docs/BENCHMARKS.md from them).
#pragma once

#include <benchmark/benchmark.h>

#include <fstream>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "gpu/context.h"

namespace telescope::bench {

using Runs = std::vector<benchmark::BenchmarkReporter::Run>;

inline gpu::Context& context() {
    static gpu::Context ctx{gpu::ContextOptions{}};
    return ctx;
}

// Keeps every run next to the usual console output.
class CollectingReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        runs_.insert(runs_.end(), runs.begin(), runs.end());
    }
    const Runs& runs() const { return runs_; }

private:
    Runs runs_;
};

inline int runWithMarkdown(int argc, char** argv, const std::function<std::string(const Runs&)>& markdown) {
    std::string path;
    for (int i = 1; i < argc; ++i)
        if (std::string(argv[i]).rfind("--markdown=", 0) == 0) path = std::string(argv[i]).substr(11);
    benchmark::Initialize(&argc, argv);
    CollectingReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    if (!path.empty()) {
        std::ofstream out(path);
        out << fmt::format("Device: {}; host threads: {}.\n", context().info().name, std::thread::hardware_concurrency())
            << markdown(reporter.runs());
    }
    benchmark::Shutdown();
    return 0;
}

}  // namespace telescope::bench
