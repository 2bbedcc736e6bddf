// Scale-out without a scheduler: `telescope merge` is exact (the merged sums are the shards'
// sums added in seed order, bit for bit, whatever the order of the arguments) and refuses
// checkpoints that do not belong together (exit 2, naming both files); `telescope shard`,
// `shard-render` (with a requeued task resuming its checkpoint) and `shard-merge` equal plain
// renders of the same seeds merged. tests/slurm/ runs the same through a real Slurm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
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

class ScaleOut : public ScratchTest {
protected:
    ScaleOut() : ScratchTest("scale") {}

    void render(uint32_t seed, uint64_t spp, const std::string& name, const std::string& extra = "") {
        CommandResult r = run("render " + scene() + kSmall + extra + " --seed " + std::to_string(seed) + " --spp " +
                              std::to_string(spp) + " --no-png -o " + out(name + ".exr") + " --checkpoint " +
                              out(name + ".ckpt"));
        ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    }

    // Bad input: exit 2, one line naming every string in `mustMention`, no new file.
    void expectRefused(const std::string& args, const std::vector<std::string>& mustMention) {
        const auto before = filesIn(dir_);
        CommandResult r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.stderrText;
        EXPECT_EQ(std::count(r.stderrText.begin(), r.stderrText.end(), '\n'), 1) << r.stderrText;
        for (const auto& m : mustMention) EXPECT_NE(r.stderrText.find(m), std::string::npos) << m << " in " << r.stderrText;
        EXPECT_EQ(filesIn(dir_), before);
    }

};

// The shards' sums added in order of their seeds, as the merge must.
Film sumInSeedOrder(const std::vector<std::string>& checkpointsInSeedOrder) {
    Film sum = loadCheckpoint(checkpointsInSeedOrder.front()).film;
    for (size_t i = 1; i < checkpointsInSeedOrder.size(); ++i) sum.merge(loadCheckpoint(checkpointsInSeedOrder[i]).film);
    return sum;
}

}  // namespace

TEST_F(ScaleOut, MergeIsExactAndIndependentOfTheOrderOfItsArguments) {
    render(5, 3, "s5");
    render(6, 2, "s6");
    render(7, 4, "s7");
    CommandResult r = run("merge " + out("s7.ckpt") + " " + out("s5.ckpt") + " " + out("s6.ckpt") + " -q --no-png -o " +
                          out("m.exr") + " --checkpoint " + out("m.ckpt"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    ASSERT_EQ(run("merge " + out("s5.ckpt") + " " + out("s6.ckpt") + " " + out("s7.ckpt") + " -q --no-png -o " +
                  out("m2.exr") + " --checkpoint " + out("m2.ckpt"))
                  .exitCode,
              0);
    EXPECT_EQ(readText(out("m.ckpt")), readText(out("m2.ckpt"))) << "the order of the arguments changed the sums";

    const Checkpoint merged = loadCheckpoint(out("m.ckpt"));
    const Film expected = sumInSeedOrder({out("s5.ckpt"), out("s6.ckpt"), out("s7.ckpt")});
    EXPECT_EQ(merged.film.samplesPerPixel(), 9u);
    EXPECT_TRUE(sameSums(merged.film, expected)) << "merged sums differ from the shards' sums";
    EXPECT_EQ(merged.seeds, (std::vector<uint32_t>{5, 6, 7}));
    // The control: the same comparison tells a merge of two of the three apart.
    EXPECT_FALSE(sameSums(sumInSeedOrder({out("s5.ckpt"), out("s6.ckpt")}), expected));

    // The EXR holds sum / spp, rounded once to float, and lists its shards.
    RgbImage img = readExrChannels(out("m.exr"), {"R", "G", "B"});
    size_t mismatches = 0;
    for (size_t i = 0; i < expected.pixelCount(); ++i) {
        const glm::dvec3 mean = expected.mean(shader::kChannelEstimate, i);
        for (int c = 0; c < 3; ++c) mismatches += img.pixels[i * 3 + c] != float(mean[c]);
    }
    EXPECT_EQ(mismatches, 0u);
    auto meta = exrStringAttributes(out("m.exr"));
    EXPECT_EQ(meta["telescope:spp"], "9");
    EXPECT_EQ(meta["telescope:seeds"], "5,6,7");
    nlohmann::json shards = nlohmann::json::parse(meta["telescope:shards"]);
    ASSERT_EQ(shards.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
        EXPECT_EQ(shards[i]["file"], out("s" + std::to_string(5 + i) + ".ckpt"));
        EXPECT_EQ(shards[i]["seeds"], nlohmann::json::array({5 + i}));
    }
    EXPECT_EQ(shards[2]["spp"], 4);
    EXPECT_FALSE(meta["telescope:settings"].empty());
}

TEST_F(ScaleOut, MergeRefusesOtherScenesOtherSettingsAndSharedSeedsNamingBothFiles) {
    render(1, 1, "a");
    render(2, 1, "b", " --set integrator.max_bounces=3");
    expectRefused("merge " + out("a.ckpt") + " " + out("b.ckpt") + " -o " + out("m.exr"),
                  {"a.ckpt", "b.ckpt", "integrator.max_bounces", "another scene"});
    // Other settings for the same scene (a pmf "auto" pilot picks per seed): edit the record.
    render(3, 1, "c");
    Checkpoint c = loadCheckpoint(out("c.ckpt"));
    nlohmann::json settings = nlohmann::json::parse(c.settings);
    settings["integrator"]["max_bounces"] = 7;
    c.settings = settings.dump();
    saveCheckpoint(out("c.ckpt"), c);
    expectRefused("merge " + out("a.ckpt") + " " + out("c.ckpt") + " -o " + out("m.exr"),
                  {"a.ckpt", "c.ckpt", "integrator.max_bounces", "other settings"});
    // A seed in two checkpoints, also inside a merged one.
    render(4, 1, "d");
    ASSERT_EQ(run("merge " + out("a.ckpt") + " " + out("d.ckpt") + " -q --no-png -o " + out("ad.exr") + " --checkpoint " +
                  out("ad.ckpt"))
                  .exitCode,
              0);
    expectRefused("merge " + out("d.ckpt") + " " + out("ad.ckpt") + " -o " + out("m.exr"),
                  {"d.ckpt", "ad.ckpt", "same seed (4)"});
    expectRefused("merge " + out("a.ckpt") + " " + out("a.ckpt") + " -o " + out("m.exr"), {"a.ckpt", "same seed (1)"});
}

TEST_F(ScaleOut, ShardRenderAndShardMergeEqualPlainRendersOfTheSameSeedsMerged) {
    const std::string dir = out("plan");
    CommandResult r = run("shard " + scene() + kSmall + " --shards 3 --spp-per-shard 2 --seed 11 -o " + dir);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    expectRefused("shard " + scene() + kSmall + " --shards 3 --spp-per-shard 2 -o " + dir, {"shards.json", "already"});
    // Task 0 was "preempted" after 1 of its 2 samples: its checkpoint is resumed to 2.
    ASSERT_EQ(run("render " + scene() + kSmall + " --seed 11 --spp 1 --no-png -o " + out("x.exr") + " --checkpoint " + dir +
                  "/shard-0.checkpoint")
                  .exitCode,
              0);
    for (const char* task : {"0", "1"}) {
        r = run("shard-render " + dir + " --task " + task + " -q");
        ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    }
    // Shard 2 missing: the merge names it and writes nothing.
    expectRefused("shard-merge " + dir + " -o " + out("m.exr"), {"shard-2.checkpoint", "1 of 3"});
    r = runShell("SLURM_ARRAY_TASK_ID=2 " + std::string(TELESCOPE_BINARY) + " shard-render " + dir, dir_);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    r = run("shard-render " + dir + " --task 2");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_NE(r.stderrText.find("nothing to do"), std::string::npos) << r.stderrText;
    expectRefused("shard-render " + dir + " --task 3", {"shards.json", "task 3"});
    r = run("shard-merge " + dir + " -q --no-png -o " + out("m.exr") + " --checkpoint " + out("m.ckpt"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;

    for (uint32_t i = 0; i < 3; ++i) render(11 + i, 2, "plain" + std::to_string(i));
    const Film plain = sumInSeedOrder({out("plain0.ckpt"), out("plain1.ckpt"), out("plain2.ckpt")});
    const Film merged = loadCheckpoint(out("m.ckpt")).film;
    // Shards 1 and 2 ran without interruption: bit for bit the plain renders.
    for (uint32_t i = 1; i < 3; ++i)
        EXPECT_TRUE(sameSums(loadCheckpoint(dir + "/shard-" + std::to_string(i) + ".checkpoint").film,
                             loadCheckpoint(out("plain" + std::to_string(i) + ".ckpt")).film));
    // Shard 0 resumed once (a double -> float pair round trip), so the merge is equal to rounding.
    EXPECT_EQ(merged.samplesPerPixel(), 6u);
    EXPECT_LT(largestRelativeDifference(merged, plain, 1e-2), 1e-6);
    EXPECT_EQ(exrStringAttributes(out("m.exr"))["telescope:seeds"], "11,12,13");
}

TEST_F(ScaleOut, AShardPlanRefusesAnAutoPmf) {
    expectRefused("shard " + scene() + kSmall +
                      " --set 'integrator.debias={\"estimator\":\"single_term\",\"pmf\":{\"type\":\"auto\"}}'"
                      " --shards 2 --spp-per-shard 1 -o " + out("plan"),
                  {"scene.json", "integrator.debias.pmf.type"});
}

// Derivative images scale out the same way: each shard a derivative render of its seed, the merge
// equal to the plain derivative renders of the same seeds; an auto pmf (per-shard pilots) refused.
TEST_F(ScaleOut, DerivativeShardsMergeToThePlainDerivativeRenders) {
    const std::string d = " --derivative 'primitives[7].emission[0]'";
    const std::string dir = out("plan");
    expectRefused("shard " + scene() + kSmall + d + " --derivative-pmf '{\"type\":\"auto\"}' --shards 2 --spp-per-shard 1 -o " + dir,
                  {"--derivative-pmf", "auto"});
    CommandResult r = run("shard " + scene() + kSmall + d + " --shards 2 --spp-per-shard 2 --seed 21 -o " + dir);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    for (const char* task : {"0", "1"}) ASSERT_EQ(run("shard-render " + dir + " --task " + task + " -q").exitCode, 0);
    r = run("shard-merge " + dir + " -q --no-png -o " + out("m.exr") + " --checkpoint " + out("m.ckpt"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    for (uint32_t i = 0; i < 2; ++i) render(21 + i, 2, "plain" + std::to_string(i), d);
    EXPECT_TRUE(sameSums(loadCheckpoint(out("m.ckpt")).film, sumInSeedOrder({out("plain0.ckpt"), out("plain1.ckpt")})));
    EXPECT_NE(exrStringAttributes(out("m.exr"))["telescope:estimator"].find("derivative d/d(primitives[7].emission[0])"),
              std::string::npos);
}
