// The scale-out path on a real Slurm (tools/slurm/setup-local-cluster: slurmctld, slurmd and
// munge on localhost): `telescope shard`, tools/slurm/submit (a 4-task array and a merge job
// that depends on it), and the result against single-process renders of the same seeds: every
// shard bit for bit, the merge equal to their sums added in seed order, its EXR listing the
// shards. Without a cluster that answers it says "skipped: no Slurm" (CTest: Skipped).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "cli_process.h"
#include "render/film_io.h"
#include "render/image_output.h"
#include "render_harness.h"

namespace fs = std::filesystem;
using namespace telescope;
using namespace telescope::test;

namespace {
const char* kSmall = " --set camera.resolution=[32,24] --set integrator.max_bounces=2 -q";
}

TEST(Slurm, AnArrayOfFourShardsAndADependentMergeEqualSingleProcessRendersOfTheSameSeeds) {
    const fs::path dir = fs::temp_directory_path() / "telescope-slurm-test";
    fs::remove_all(dir);
    fs::create_directories(dir);
    if (runShell("scontrol ping | grep -q UP && sinfo -h -o %T | grep -Eq '^(idle|mixed|allocated)'", dir).exitCode != 0) {
        std::printf("\n******** skipped: no Slurm (no controller or no idle node; as root run "
                    "tools/slurm/setup-local-cluster, which .ci/install-deps runs) ********\n\n");
        GTEST_SKIP() << "skipped: no Slurm";
    }
    const std::string scene = sourcePath("scenes/tungsten/cornell-box/scene.json");
    const std::string plan = (dir / "plan").string(), merged = (dir / "merged.exr").string();
    CommandResult r = runTelescope("shard " + scene + kSmall + " --shards 4 --spp-per-shard 3 --seed 21 -o " + plan, dir);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    r = runShell("TELESCOPE=" + std::string(TELESCOPE_BINARY) + " timeout 600 " + sourcePath("tools/slurm/submit") +
                     " --wait " + plan + " " + merged,
                 dir);
    std::string logs;
    for (const auto& name : filesIn(plan + "/logs")) logs += name + ":\n" + readText(plan + "/logs/" + name);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText << logs;

    std::vector<std::string> single;
    for (uint32_t i = 0; i < 4; ++i) {
        const std::string name = (dir / ("single" + std::to_string(i))).string();
        r = runTelescope("render " + scene + kSmall + " --spp 3 --seed " + std::to_string(21 + i) + " --no-png -o " + name +
                             ".exr --checkpoint " + name + ".ckpt",
                         dir);
        ASSERT_EQ(r.exitCode, 0) << r.stderrText;
        single.push_back(name + ".ckpt");
        EXPECT_TRUE(sameSums(loadCheckpoint(plan + "/shard-" + std::to_string(i) + ".checkpoint").film,
                             loadCheckpoint(single.back()).film))
            << "shard " << i;
    }
    Film expected = loadCheckpoint(single[0]).film;
    for (size_t i = 1; i < 4; ++i) expected.merge(loadCheckpoint(single[i]).film);
    const Checkpoint m = loadCheckpoint((dir / "merged.checkpoint").string());
    EXPECT_EQ(m.film.samplesPerPixel(), 12u);
    EXPECT_TRUE(sameSums(m.film, expected)) << "the merged image is not the single-process renders' sum";
    // The control: three of the four shards do not pass the same comparison.
    Film three = loadCheckpoint(single[0]).film;
    for (size_t i = 1; i < 3; ++i) three.merge(loadCheckpoint(single[i]).film);
    EXPECT_FALSE(sameSums(three, expected));

    RgbImage img = readExrChannels(merged, {"R", "G", "B"});
    size_t mismatches = 0;
    for (size_t i = 0; i < expected.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) mismatches += img.pixels[i * 3 + c] != float(expected.mean(shader::kChannelEstimate, i)[c]);
    EXPECT_EQ(mismatches, 0u);
    auto meta = exrStringAttributes(merged);
    EXPECT_EQ(meta["telescope:seeds"], "21,22,23,24");
    nlohmann::json shards = nlohmann::json::parse(meta["telescope:shards"]);
    ASSERT_EQ(shards.size(), 4u);
    for (size_t i = 0; i < 4; ++i) EXPECT_EQ(shards[i]["file"], plan + "/shard-" + std::to_string(i) + ".checkpoint");
    fs::remove_all(dir);
}
