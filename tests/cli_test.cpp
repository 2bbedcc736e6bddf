// The telescope command: exit codes, one-line messages naming the file and key, no output on bad
// input, and the EXR it writes (channels, metadata, base + correction = estimate).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "render/image_output.h"
#include "render_harness.h"

namespace fs = std::filesystem;
using namespace telescope;

namespace {

struct CommandResult {
    int exitCode = -1;
    std::string stderrText;
};

class Cli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("telescope-cli-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    CommandResult run(const std::string& args) {
        std::string errFile = (dir_ / "stderr.txt").string();
        std::string cmd = std::string(TELESCOPE_BINARY) + " " + args + " >/dev/null 2>" + errFile;
        int status = std::system(cmd.c_str());
        CommandResult r;
        r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        std::ifstream in(errFile);
        std::stringstream ss;
        ss << in.rdbuf();
        r.stderrText = ss.str();
        fs::remove(errFile);
        return r;
    }

    std::string write(const std::string& name, const std::string& text) {
        fs::path p = dir_ / name;
        std::ofstream(p) << text;
        return p.string();
    }

    // Bad input: exit code 2, exactly one line naming `mustMention`, nothing written to dir_.
    void expectBadInput(const std::string& args, const std::vector<std::string>& mustMention) {
        auto before = std::distance(fs::directory_iterator(dir_), fs::directory_iterator());
        CommandResult r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.stderrText;
        EXPECT_EQ(std::count(r.stderrText.begin(), r.stderrText.end(), '\n'), 1) << r.stderrText;
        for (const auto& m : mustMention) EXPECT_NE(r.stderrText.find(m), std::string::npos) << "missing '" << m << "' in: " << r.stderrText;
        auto after = std::distance(fs::directory_iterator(dir_), fs::directory_iterator());
        EXPECT_EQ(before, after) << "bad input left files behind";
    }

    std::string scene() const { return test::sourcePath("scenes/tungsten/cornell-box/scene.json"); }
    std::string out(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

}  // namespace

TEST_F(Cli, MissingSceneFile) { expectBadInput("render " + out("nope.json") + " -o " + out("a.exr"), {"nope.json"}); }

TEST_F(Cli, MalformedSceneJson) {
    std::string bad = write("bad.json", "{\"primitives\": [ {\"type\": \"quad\", }\n");
    expectBadInput("render " + bad + " -o " + out("a.exr"), {"bad.json"});
}

TEST_F(Cli, UnknownPrimitiveTypeThroughSet) {
    expectBadInput("render " + scene() + " -o " + out("a.exr") + " --set primitives[0].type=\\\"banana\\\"",
                   {"scene.json", "primitives[0].type"});
}

TEST_F(Cli, NegativeResolution) {
    expectBadInput("render " + scene() + " -o " + out("a.exr") + " --set camera.resolution=[-5,5]",
                   {"scene.json", "camera.resolution"});
}

TEST_F(Cli, SetWithoutEquals) {
    expectBadInput("render " + scene() + " -o " + out("a.exr") + " --set camera.fov", {"command line"});
}

TEST_F(Cli, ZeroSpp) { expectBadInput("render " + scene() + " -o " + out("a.exr") + " --spp 0", {"--spp"}); }

TEST_F(Cli, SppAndTimeTogether) {
    expectBadInput("render " + scene() + " -o " + out("a.exr") + " --spp 4 --time 1", {"--time"});
}

TEST_F(Cli, OutputDirectoryMissing) {
    expectBadInput("render " + scene() + " -o " + out("missing/a.exr"), {"-o", "missing"});
}

TEST_F(Cli, OutputNotExr) { expectBadInput("render " + scene() + " -o " + out("a.tiff"), {"-o", ".exr"}); }

TEST_F(Cli, UnknownDebiasEstimator) {
    expectBadInput("render " + scene() + " -o " + out("a.exr") +
                       " --set 'integrator.debias={\"estimator\":\"magic\"}'",
                   {"scene.json", "integrator.debias.estimator"});
}

TEST_F(Cli, PlanListsOnlyThePathTracePass) {
    std::string outFile = (dir_ / "plan.txt").string();
    int status = std::system((std::string(TELESCOPE_BINARY) + " plan " + scene() + " > " + outFile).c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    std::ifstream in(outFile);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto scheduled = text.substr(0, text.find("not scheduled:"));
    EXPECT_NE(scheduled.find("path_trace"), std::string::npos) << text;
    for (const char* pass : {"photon_trace", "hash_grid_build", "gather", "ray_march"})
        EXPECT_EQ(scheduled.find(pass), std::string::npos) << pass << " should not be scheduled:\n" << text;
}

TEST_F(Cli, RenderWritesExrWithChannelsMetadataAndPreview) {
    std::string exr = out("cb.exr"), stats = out("stats.json");
    CommandResult r = run("render " + scene() + " -o " + exr + " --spp 4 --seed 5 -q --stats-json " + stats +
                          " --set camera.resolution=[32,24] --set integrator.max_bounces=1"
                          " --set 'integrator.debias={\"estimator\":\"single_term\"}'");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_TRUE(fs::exists(out("cb.png")));
    EXPECT_TRUE(fs::exists(stats));
    RgbImage img = readExrChannels(exr, {"R", "G", "B", "base.R", "base.G", "base.B", "correction.R", "correction.G",
                                         "correction.B", "variance.R", "variance.G", "variance.B"});
    ASSERT_EQ(img.width, 32);
    ASSERT_EQ(img.height, 24);
    double correction = 0.0;
    for (int p = 0; p < img.width * img.height; ++p) {
        const float* px = &img.pixels[p * 12];
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(px[3 + c] + px[6 + c], px[c], 1e-5f * (1.0f + std::abs(px[c])));
            EXPECT_GE(px[9 + c], 0.0f);
            correction += std::abs(px[6 + c]);
        }
    }
    EXPECT_GT(correction, 0.0) << "a debiased render has a correction";
    std::ifstream in(stats);
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("\"path_trace\""), std::string::npos);
    EXPECT_NE(text.find("\"dispatches\""), std::string::npos);
    EXPECT_NE(text.find("\"device\""), std::string::npos);
}
