// The telescope command: exit codes, one-line messages naming the file and key, no output on bad
// input, the EXR it writes (channels with known values, metadata with the settings as run), and
// what `plan` says.
#include <OpenImageIO/imageio.h>  // before anything that may pull in X11

#include <gtest/gtest.h>

#include "cli_process.h"

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <map>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "render/film_io.h"
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
    // The furnace (Le = 1, albedo 0.5) at k = 1 with the default pmf: every channel has a known
    // mean, I(1) = 1.5 in base.*, I - I(1) = 0.5 in correction.*, 2 in R, G, B (a swapped or
    // misnamed channel fails), and the settings as run are in the metadata and the stats.
    std::string exr = out("cb.exr"), stats = out("stats.json");
    CommandResult r = run("render " + test::sourcePath("scenes/furnace.json") + " -o " + exr +
                          " --spp 8 --seed 5 -q --stats-json " + stats +
                          " --set camera.resolution=[32,24] --set integrator.max_bounces=2"
                          " --set 'integrator.debias={\"estimator\":\"single_term\"}'");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_TRUE(fs::exists(out("cb.png")));
    EXPECT_TRUE(fs::exists(stats));
    RgbImage img = readExrChannels(exr, {"R", "G", "B", "base.R", "base.G", "base.B", "correction.R", "correction.G",
                                         "correction.B", "variance.R", "variance.G", "variance.B"});
    ASSERT_EQ(img.width, 32);
    ASSERT_EQ(img.height, 24);
    const int n = img.width * img.height;
    double mean[12] = {};
    for (int p = 0; p < n; ++p)
        for (int c = 0; c < 12; ++c) mean[c] += img.pixels[p * 12 + c] / double(n);
    for (int c = 0; c < 3; ++c) {
        // The image mean's standard error from the variance channel: sqrt(mean variance / n).
        const double se = std::sqrt(mean[9 + c] / n);
        EXPECT_GT(se, 0.0);
        EXPECT_LT(std::abs(mean[c] - 2.0), 4.5 * se) << "channel " << c << ": " << mean[c];
        EXPECT_NEAR(mean[3 + c], 1.5, 0.05) << "base";
        EXPECT_NEAR(mean[6 + c], 0.5, 0.05) << "correction";
    }
    auto in = OIIO::ImageInput::open(exr);
    ASSERT_TRUE(in);
    const nlohmann::json meta = nlohmann::json::parse(in->spec().get_string_attribute("telescope:settings"));
    EXPECT_EQ(meta["integrator"]["debias"]["pmf"]["type"], "geometric");
    EXPECT_FLOAT_EQ(meta["integrator"]["debias"]["pmf"]["r"].get<float>(), 0.25f);
    EXPECT_NE(meta["integrator"]["debias"]["pmf"]["origin"].get<std::string>().find("default for path depth"), std::string::npos);
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(stats));
    EXPECT_EQ(j["settings"], meta);
    EXPECT_TRUE(j["passes"].contains("path_trace"));
    EXPECT_GT(j["passes"]["path_trace"]["dispatches"].get<int>(), 0);
    EXPECT_TRUE(j.contains("device"));
}

TEST_F(Cli, OutputsRecordThePmfTheAutoPilotChose) {
    std::string exr = out("auto.exr"), stats = out("auto.json");
    CommandResult r = run("render " + test::sourcePath("scenes/furnace.json") + " -o " + exr + " --no-png" +
                          " --spp 2 -q --stats-json " + stats + " --set camera.resolution=[8,8] --set integrator.max_bounces=2"
                          " --set 'integrator.debias={\"estimator\":\"single_term\",\"pmf\":{\"type\":\"auto\",\"pilot_spp\":1,\"pilot_levels\":3}}'");
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(stats));
    const nlohmann::json& pmf = j["settings"]["integrator"]["debias"]["pmf"];
    EXPECT_NE(pmf["type"], "auto") << pmf.dump();
    EXPECT_NE(pmf["origin"].get<std::string>().find("auto pilot"), std::string::npos) << pmf.dump();
    auto in = OIIO::ImageInput::open(exr);
    ASSERT_TRUE(in);
    EXPECT_EQ(nlohmann::json::parse(in->spec().get_string_attribute("telescope:settings")), j["settings"]);
}

TEST_F(Cli, PlanSaysWhichPmfAndWhy) {
    auto plan = [&](const std::string& scenePath, const std::string& sets) {
        std::string outFile = out("plan.txt");
        int status = std::system((std::string(TELESCOPE_BINARY) + " plan " + scenePath + sets + " > " + outFile).c_str());
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        std::ifstream in(outFile);
        return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    };
    std::string text = plan(scene(), " --set 'integrator.debias={\"estimator\":\"sum\"}'");
    EXPECT_NE(text.find("path-depth pmf: geometric pmf, r = 0.25; default for path depth"), std::string::npos) << text;
    text = plan(scene(), " --set 'integrator.debias={\"estimator\":\"sum\",\"pmf\":{\"type\":\"power_law\"}}'");
    EXPECT_NE(text.find("path-depth pmf: power-law pmf, alpha = 0.666667; given in the scene"), std::string::npos) << text;
    text = plan(test::sourcePath("scenes/absorbing-slab.json"), "");
    EXPECT_NE(text.find("transmittance pmf: geometric pmf, r = 0.65; "), std::string::npos) << text;
    text = plan(scene(), " --set 'integrator.debias={\"estimator\":\"sum\",\"test_pmf_weight\":1.07}'");
    EXPECT_NE(text.find("TEST ONLY"), std::string::npos) << text;
    // pmf "auto" for debiased marching: plan runs the pilot and prints what it chose and why.
    text = plan(test::sourcePath("scenes/absorbing-slab.json"),
                " --set 'integrator.transmittance_estimator.pmf={\"type\":\"auto\",\"pilot_levels\":3}'");
    EXPECT_NE(text.find("transmittance pmf: auto pmf (pilot); chosen by a pilot before the render"), std::string::npos) << text;
    EXPECT_NE(text.find("transmittance_pilot"), std::string::npos) << text;
    EXPECT_NE(text.find("transmittance (debiased ray marching) pmf pilot (3 levels"), std::string::npos) << text;
    EXPECT_NE(text.find("default geometric r = 0.65: predicted variance x cost"), std::string::npos) << text;
    const size_t last = text.rfind("transmittance pmf: ");  // the pmf the pilot chose, last
    ASSERT_NE(last, std::string::npos) << text;
    const std::string chosen = text.substr(last, text.find('\n', last) - last);
    EXPECT_TRUE(chosen.find("geometric pmf, r = ") != std::string::npos ||
                chosen.find("power-law pmf, alpha = ") != std::string::npos) << chosen;
    EXPECT_NE(chosen.find("chosen by the auto pilot"), std::string::npos) << chosen;
}

TEST_F(Cli, WideFilterWithPhotonMappingIsBadInput) {
    expectBadInput("render " + test::sourcePath("scenes/point-plane-photon.json") + " -o " + out("a.exr") +
                       " --set camera.reconstruction_filter=gaussian",
                   {"point-plane-photon.json", "camera.reconstruction_filter", "gaussian"});
}

// ---- Checkpoints, resume and merge ----

namespace {
std::string readText(const std::string& path) {
    std::ifstream in(path);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
const char* kSmall = " --set camera.resolution=[32,24] --set integrator.max_bounces=2 -q";
}  // namespace

TEST_F(Cli, ResumedRenderEqualsOneLongRender) {
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 8 -o " + out("a.exr") + " --checkpoint " + out("a.ckpt")).exitCode, 0);
    CommandResult r = run("render " + scene() + kSmall + " --spp 8 -o " + out("b.exr") + " --resume " + out("a.ckpt"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 16 -o " + out("c.exr")).exitCode, 0);
    RgbImage resumed = readExrChannels(out("b.exr"), {"R", "G", "B"});
    RgbImage whole = readExrChannels(out("c.exr"), {"R", "G", "B"});
    ASSERT_EQ(resumed.pixels.size(), whole.pixels.size());
    double total = 0.0;
    for (size_t i = 0; i < whole.pixels.size(); ++i) {
        EXPECT_NEAR(resumed.pixels[i], whole.pixels[i], 1e-5f * (1.0f + std::abs(whole.pixels[i]))) << i;
        total += whole.pixels[i];
    }
    EXPECT_GT(total, 0.0);
}

TEST_F(Cli, ResumeRejectsAnotherScene) {
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 2 -o " + out("a.exr") + " --checkpoint " + out("a.ckpt")).exitCode, 0);
    expectBadInput("render " + scene() + kSmall + " --set integrator.max_bounces=3 --spp 2 -o " + out("b.exr") +
                       " --resume " + out("a.ckpt"),
                   {"a.ckpt", "another scene"});
}

TEST_F(Cli, ResumeRejectsOtherResolvedSettingsNamingTheKey) {
    // The same scene file can resolve to other settings (a build with other defaults): resume
    // compares the resolved settings the checkpoint recorded and names the first key that differs.
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 2 -o " + out("a.exr") + " --checkpoint " + out("a.ckpt")).exitCode, 0);
    Checkpoint c = loadCheckpoint(out("a.ckpt"));
    nlohmann::json settings = nlohmann::json::parse(c.settings);
    ASSERT_TRUE(settings["integrator"].contains("enable_light_sampling")) << c.settings;
    settings["integrator"]["enable_light_sampling"] = !settings["integrator"]["enable_light_sampling"].get<bool>();
    c.settings = settings.dump();
    saveCheckpoint(out("edited.ckpt"), c);
    expectBadInput("render " + scene() + kSmall + " --spp 2 -o " + out("b.exr") + " --resume " + out("edited.ckpt"),
                   {"edited.ckpt", "integrator.enable_light_sampling", "other settings"});
    // the unedited checkpoint resumes
    EXPECT_EQ(run("render " + scene() + kSmall + " --spp 2 -o " + out("b.exr") + " --resume " + out("a.ckpt")).exitCode, 0);
}

TEST_F(Cli, CorruptCheckpointIsBadInput) {
    std::string bad = write("bad.ckpt", "TELESCOPE-FILM but not really");
    expectBadInput("render " + scene() + kSmall + " --spp 2 -o " + out("b.exr") + " --resume " + bad, {"bad.ckpt"});
}

TEST_F(Cli, MergeAddsIndependentRendersAndRejectsTheSameSeed) {
    for (const char* seed : {"1", "2"})
        ASSERT_EQ(run("render " + scene() + kSmall + " --spp 4 --seed " + seed + " -o " + out(std::string("s") + seed + ".exr") +
                      " --checkpoint " + out(std::string("s") + seed + ".ckpt"))
                      .exitCode,
                  0);
    expectBadInput("merge " + out("s1.ckpt") + " " + out("s1.ckpt") + " -o " + out("m.exr"), {"s1.ckpt", "seed"});
    CommandResult r = run("merge " + out("s1.ckpt") + " " + out("s2.ckpt") + " -o " + out("m.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    RgbImage a = readExrChannels(out("s1.exr"), {"R", "G", "B"});
    RgbImage b = readExrChannels(out("s2.exr"), {"R", "G", "B"});
    RgbImage m = readExrChannels(out("m.exr"), {"R", "G", "B"});
    for (size_t i = 0; i < m.pixels.size(); ++i)
        EXPECT_NEAR(m.pixels[i], 0.5f * (a.pixels[i] + b.pixels[i]), 1e-5f * (1.0f + std::abs(m.pixels[i]))) << i;
}

// ---- reference and converge ----

TEST_F(Cli, ReferenceResumesFromItsCheckpoint) {
    std::string args = "reference " + scene() + kSmall + " --spp 8 -o " + out("ref.exr");
    ASSERT_EQ(run(args).exitCode, 0);
    ASSERT_TRUE(fs::exists(out("ref.exr.checkpoint")));
    CommandResult r = run(args);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    RgbImage img = readExrChannels(out("ref.exr"), {"R"});
    EXPECT_EQ(img.width, 32);
    auto in = OIIO::ImageInput::open(out("ref.exr"));
    ASSERT_TRUE(in);
    EXPECT_EQ(in->spec().get_string_attribute("telescope:spp"), "16") << "the second run adds 8 spp to the first 8";
    EXPECT_NE(in->spec().get_string_attribute("telescope:estimator").find("sum"), std::string::npos)
        << "a biased scene gets an unbiased estimator for its reference";
}

// A reference of a scene whose pmf is "auto": the session runs the pilot (the Renderer cannot be
// built without), and the outputs record the pmf it chose. The next run resumes the checkpoint
// (2 spp, then 4 more) with that pmf, running no second pilot (whose choice could differ: two estimators in one
// film); a render --resume of it likewise. Control of the "no pilot" check: the first run, not
// quiet, does print the pilot's summary.
TEST_F(Cli, AnAutoPmfIsResolvedOnceAndResumedWithThePilotsChoice) {
    const std::string scene = test::sourcePath("scenes/furnace.json") +
                              " --set camera.resolution=[8,8] --set integrator.max_bounces=2 --no-png"
                              " --set 'integrator.debias={\"estimator\":\"sum\",\"pmf\":{\"type\":\"auto\","
                              "\"pilot_spp\":1,\"pilot_levels\":3}}'";
    auto settingsOf = [](const std::string& exr) {
        auto in = OIIO::ImageInput::open(exr);
        EXPECT_TRUE(in) << exr;
        return in ? nlohmann::json::parse(in->spec().get_string_attribute("telescope:settings")) : nlohmann::json();
    };
    auto sppOf = [](const std::string& exr) {
        auto in = OIIO::ImageInput::open(exr);
        return in ? std::string(in->spec().get_string_attribute("telescope:spp")) : std::string();
    };
    CommandResult r = run("reference " + scene + " --spp 2 -o " + out("ref.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_NE(r.stderrText.find("path-depth pmf pilot"), std::string::npos) << r.stderrText;
    const nlohmann::json first = settingsOf(out("ref.exr"));
    const nlohmann::json& pmf = first["integrator"]["debias"]["pmf"];
    EXPECT_NE(pmf["type"], "auto") << pmf.dump();
    EXPECT_NE(pmf["origin"].get<std::string>().find("auto pilot"), std::string::npos) << pmf.dump();

    r = run("reference " + scene + " --spp 4 -o " + out("ref.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_EQ(r.stderrText.find("pmf pilot"), std::string::npos) << "a second pilot ran:\n" << r.stderrText;
    EXPECT_EQ(settingsOf(out("ref.exr")), first);
    EXPECT_EQ(sppOf(out("ref.exr")), "6");  // --spp adds to the checkpoint's 2

    r = run("render " + scene + " --spp 2 --resume " + out("ref.exr.checkpoint") + " -o " + out("more.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    EXPECT_EQ(r.stderrText.find("pmf pilot"), std::string::npos) << "a second pilot ran:\n" << r.stderrText;
    EXPECT_EQ(settingsOf(out("more.exr")), first);
    EXPECT_EQ(sppOf(out("more.exr")), "8");
}

TEST_F(Cli, ConvergeShowsTheBiasOfTruncationAndNotOfTheDebiasedEstimator) {
    ASSERT_EQ(run("reference " + scene() + " --set camera.resolution=[32,24] -q --spp 128 -o " + out("ref.exr")).exitCode, 0);
    CommandResult r = run("converge " + scene() + " --set camera.resolution=[32,24] -q --reference " + out("ref.exr") +
                          " --methods biased:1,sum:1 --method 'deep: integrator.max_bounces=64' --spp 8,32 -o " +
                          out("conv"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    for (const char* f : {"convergence.csv", "convergence.png", "convergence.gp", "strip.png", "report.md"})
        EXPECT_TRUE(fs::exists(dir_ / "conv" / f)) << f;
    // Rows: method, seed, slice, spp, wall, gpu, rmse, rel_mse, mean_error, rel_mean_error.
    std::istringstream csv(readText(out("conv/convergence.csv")));
    std::string line;
    std::getline(csv, line);
    std::map<std::string, double> finalBias;
    int rows = 0;
    while (std::getline(csv, line)) {
        ++rows;
        std::vector<std::string> cells;
        std::stringstream ls(line);
        for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
        ASSERT_EQ(cells.size(), 10u) << line;
        EXPECT_EQ(cells[1], "1") << line;
        finalBias[cells[0]] = std::stod(cells[9]);
        EXPECT_GT(std::stod(cells[7]), 0.0) << line;
    }
    EXPECT_EQ(rows, 6);
    // Truncating at one bounce loses about a quarter of the light; the debiased estimator and the
    // deep render agree with the reference to within their noise.
    EXPECT_LT(finalBias["\"biased:1\""], -0.15);
    EXPECT_LT(std::abs(finalBias["\"sum:1\""]), 0.05);
    EXPECT_LT(std::abs(finalBias["\"deep\""]), 0.05);
    EXPECT_NE(readText(out("conv/report.md")).find("| biased:1 |"), std::string::npos);
}

TEST_F(Cli, ConvergeAveragesIndependentSeeds) {
    ASSERT_EQ(run("reference " + scene() + " --set camera.resolution=[16,12] -q --spp 64 -o " + out("ref.exr")).exitCode, 0);
    CommandResult r = run("converge " + scene() + " --set camera.resolution=[16,12] -q --reference " + out("ref.exr") +
                          " --methods single_term:1,single_term_auto:1 --spp 2,4 --seeds 2 -o " + out("conv"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    std::istringstream csv(readText(out("conv/convergence.csv")));
    std::string line;
    std::getline(csv, line);
    // (method, slice) -> relative MSE per seed, and the mean row.
    std::map<std::pair<std::string, std::string>, std::vector<double>> perSeed;
    std::map<std::pair<std::string, std::string>, double> mean;
    while (std::getline(csv, line)) {
        std::vector<std::string> cells;
        std::stringstream ls(line);
        for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
        ASSERT_EQ(cells.size(), 10u) << line;
        if (cells[1] == "mean") mean[{cells[0], cells[2]}] = std::stod(cells[7]);
        else perSeed[{cells[0], cells[2]}].push_back(std::stod(cells[7]));
    }
    ASSERT_EQ(mean.size(), 4u);
    for (const auto& [key, values] : perSeed) {
        ASSERT_EQ(values.size(), 2u) << key.first;
        EXPECT_NE(values[0], values[1]) << "independent seeds give different errors";
        EXPECT_NEAR(mean[key], (values[0] + values[1]) / 2.0, 1e-6 * mean[key]) << key.first;
    }
    std::string report = readText(out("conv/report.md"));
    EXPECT_NE(report.find("Seeds 1 to 2"), std::string::npos) << report;
    EXPECT_NE(report.find("single_term_auto:1 vs single_term:1"), std::string::npos) << report;
    EXPECT_NE(report.find("ratio of the medians over seeds"), std::string::npos) << report;
    EXPECT_NE(report.find("pilot per seed"), std::string::npos) << report;
}

TEST_F(Cli, ConvergeRejectsZeroSeeds) {
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 1 --no-png -o " + out("ref.exr")).exitCode, 0);
    expectBadInput("converge " + scene() + kSmall + " --reference " + out("ref.exr") +
                       " --methods biased:1 --spp 1 --seeds 0 -o " + out("conv"),
                   {"--seeds"});
    EXPECT_FALSE(fs::exists(dir_ / "conv" / "convergence.csv"));
}

TEST_F(Cli, ConvergeRejectsAReferenceOfAnotherSize) {
    ASSERT_EQ(run("render " + scene() + kSmall + " --spp 1 --no-png -o " + out("ref.exr")).exitCode, 0);
    expectBadInput("converge " + scene() + " --set camera.resolution=[16,16] --reference " + out("ref.exr") +
                       " --methods biased:1 --spp 1 -o " + out("conv"),
                   {"ref.exr", "32x24"});
}

TEST_F(Cli, ConvergeRejectsAnUnknownPreset) {
    expectBadInput("converge " + scene() + " --reference " + out("ref.exr") + " --methods magic:3 --spp 1 -o " + out("conv"),
                   {"--methods", "magic"});
}

// ---- Participating media: bad input names the file and the key; the plan says what is compiled ----
TEST_F(Cli, UnknownMediumType) {
    std::string bad = write("fog.json", R"({"media": [{"name": "fog", "type": "fog"}]})");
    expectBadInput("render " + bad + " -o " + out("a.exr"), {"fog.json", "media[0].type", "unknown medium type"});
}

TEST_F(Cli, VdbGridMissingFile) {
    std::string bad = write("vdb.json", R"({"media": [{"type": "voxel", "grid": {"type": "vdb", "file": "x.vdb"}}]})");
    expectBadInput("render " + bad + " -o " + out("a.exr"), {"vdb.json", "media[0].grid.file", "x.vdb"});
}

TEST_F(Cli, UnknownMediumReference) {
    expectBadInput("render " + test::sourcePath("scenes/absorbing-slab.json") + " -o " + out("a.exr") +
                       " --set 'primitives[0].int_medium=\"mist\"'",
                   {"absorbing-slab.json", "primitives[0].int_medium", "unknown medium 'mist'"});
}

TEST_F(Cli, TrackerOnNonExponentialMedium) {
    expectBadInput("render " + test::sourcePath("scenes/davis-cloud.json") + " -o " + out("a.exr") +
                       " --set 'integrator.transmittance_estimator={\"type\":\"delta_tracking\"}'",
                   {"davis-cloud.json", "integrator.transmittance_estimator.type", "exponential media only"});
}

TEST_F(Cli, NegativeMediumDensity) {
    expectBadInput("render " + test::sourcePath("scenes/smoke-box.json") + " -o " + out("a.exr") +
                       " --set media[0].density=-1",
                   {"smoke-box.json", "media[0].density"});
}

TEST_F(Cli, PlanSaysWhetherVolumeCodeIsCompiled) {
    auto plan = [&](const std::string& scenePath) {
        std::string outFile = (dir_ / "plan.txt").string();
        int status = std::system((std::string(TELESCOPE_BINARY) + " plan " + scenePath + " > " + outFile).c_str());
        EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
        std::ifstream in(outFile);
        std::stringstream ss;
        ss << in.rdbuf();
        return ss.str();
    };
    std::string withMedia = plan(test::sourcePath("scenes/absorbing-slab.json"));
    EXPECT_NE(withMedia.find("debiased_ray_march"), std::string::npos) << withMedia;
    EXPECT_NE(withMedia.find("media               on"), std::string::npos) << withMedia;
    std::string without = plan(scene());
    EXPECT_NE(without.find("media               off"), std::string::npos) << without;
    EXPECT_NE(without.find("volume code folded out"), std::string::npos) << without;
}

TEST_F(Cli, StudyTransmittanceWritesCsvHeatMapsAndSummary) {
    std::string dir = out("study");
    CommandResult r = run("study transmittance -q --samples 256 -o " + dir);
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    std::ifstream csv(dir + "/transmittance.csv");
    std::string header;
    std::getline(csv, header);
    EXPECT_NE(header.find("work_x_rel_mse"), std::string::npos) << header;
    size_t rows = 0;
    for (std::string line; std::getline(csv, line);) ++rows;
    EXPECT_EQ(rows, 3u * 600 + 4u * 150) << "two ray marchers and taylor on all four models, four exponential-only estimators";
    EXPECT_TRUE(fs::exists(dir + "/summary.md"));
    for (const char* e : {"ray_march", "debiased_ray_march", "delta_tracking", "ratio_tracking", "residual_ratio_tracking",
                          "unbiased_ray_march", "taylor"})
        EXPECT_TRUE(fs::exists(dir + "/heat_" + std::string(e) + ".png")) << e << " (gnuplot-nox installed?)";
}

// ---- Derivative images (docs/DERIVATIVES.md): bad parameters, the plan, the EXR's metadata ----

TEST_F(Cli, DerivativeRefusesBadParameters) {
    const std::string plane = test::sourcePath("scenes/point-plane.json") + " --set 'camera.resolution=[8,8]'";
    auto render = [&](const std::string& args) { return "render " + plane + " -o " + out("d.exr") + " --spp 1 " + args; };
    expectBadInput(render("--derivative 'bsdfs[0].type'"), {"bsdfs[0].type", "not a number"});         // a string
    expectBadInput(render("--derivative 'bsdfs[0].roughness'"), {"bsdfs[0].roughness", "no such value"});  // missing
    expectBadInput(render("--derivative 'camera.resolution[1]'"), {"camera.resolution[1]", "discrete"});
    expectBadInput(render("--derivative 'integrator.max_bounces'"), {"integrator.max_bounces", "estimator"});
    expectBadInput(render("--derivative 'bsdfs[0].albedo' --step -0.1"), {"--step", "positive"});
    expectBadInput(render("--derivative 'bsdfs[0].albedo' --step 0"), {"--step", "positive"});
    expectBadInput(render("--derivative 'bsdfs[0].albedo' --derivative-estimator central --step 0.6"),
                   {"bsdfs[0].albedo", "refuses the value"});
    expectBadInput(render("--derivative 'bsdfs[0].albedo' --derivative-estimator newton"), {"--derivative-estimator"});
    expectBadInput(render("--derivative 'bsdfs[0].albedo' --derivative-pmf '{\"type\":\"geometric\",\"r\":1.5}'"),
                   {"--derivative-pmf"});
    expectBadInput(render("--derivative 'renderer.spp'"), {"renderer.spp"});
}

TEST_F(Cli, DerivativePlanAndMetadata) {
    const std::string plane = test::sourcePath("scenes/point-plane.json") + " --set 'camera.resolution=[8,8]'";
    const std::string planFile = out("plan.txt");
    const int status = std::system((std::string(TELESCOPE_BINARY) + " plan " + plane +
                                    " --derivative 'primitives[1].transform.position[1]' > " + planFile).c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    const std::string text = readText(planFile);
    for (const char* line : {"parameter   primitives[1].transform.position[1] = 1", "h_0         0.0625",
                             "estimator   single_term", "geometric pmf, r = 0.5", "3.50 path_trace evaluations per sample",
                             "russian roulette    off"})
        EXPECT_NE(text.find(line), std::string::npos) << "missing '" << line << "' in:\n" << text;
    CommandResult r = run("render " + plane + " --derivative 'bsdfs[0].albedo' --spp 4 -q -o " + out("d.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    const auto meta = telescope::test::exrStringAttributes(out("d.exr"));
    EXPECT_EQ(meta.at("telescope:derivative_key"), "bsdfs[0].albedo");
    EXPECT_EQ(meta.at("telescope:derivative_value"), "0.5");
    EXPECT_EQ(meta.at("telescope:derivative_step"), "0.03125");  // |theta| / 16
    EXPECT_EQ(meta.at("telescope:derivative_estimator"), "single_term");
    EXPECT_TRUE(fs::exists(out("d.png")));
    // Stopping and resuming equals one long render (sample indices and levels continue).
    const std::string d = plane + " --derivative 'bsdfs[0].albedo' -q --no-png";
    ASSERT_EQ(run("render " + d + " --spp 3 -o " + out("a.exr") + " --checkpoint " + out("a.ckpt")).exitCode, 0);
    ASSERT_EQ(run("render " + d + " --spp 2 -o " + out("b.exr") + " --resume " + out("a.ckpt") + " --checkpoint " +
                  out("b.ckpt")).exitCode, 0);
    ASSERT_EQ(run("render " + d + " --spp 5 -o " + out("c.exr") + " --checkpoint " + out("c.ckpt")).exitCode, 0);
    EXPECT_TRUE(telescope::test::sameSums(loadCheckpoint(out("b.ckpt")).film, loadCheckpoint(out("c.ckpt")).film));
    // Resuming compares the settings as run (the derivative's too) and names the key that differs.
    CommandResult step = run("render " + d + " --step 0.01 --spp 1 -o " + out("s.exr") + " --resume " + out("a.ckpt"));
    EXPECT_EQ(step.exitCode, 2) << step.stderrText;
    EXPECT_NE(step.stderrText.find("derivative.step"), std::string::npos) << step.stderrText;
    CommandResult levels = run("render " + d + " --derivative-levels 6 --spp 1 -o " + out("s.exr") + " --resume " + out("a.ckpt"));
    EXPECT_EQ(levels.exitCode, 2) << levels.stderrText;
    EXPECT_NE(levels.stderrText.find("derivative.level"), std::string::npos) << levels.stderrText;
    // `reference --derivative` continues from its checkpoint when run again.
    for (int i = 0; i < 2; ++i)
        ASSERT_EQ(run("reference " + d + " --spp 2 -o " + out("ref.exr")).exitCode, 0);
    EXPECT_EQ(telescope::test::exrStringAttributes(out("ref.exr")).at("telescope:spp"), "4");
    // A radiance render's checkpoint is not a derivative's.
    ASSERT_EQ(run("render " + plane + " -q --no-png --spp 1 -o " + out("r.exr") + " --checkpoint " + out("r.ckpt")).exitCode, 0);
    CommandResult mixed = run("render " + d + " --spp 1 -o " + out("m.exr") + " --resume " + out("r.ckpt"));
    EXPECT_EQ(mixed.exitCode, 2) << mixed.stderrText;
    EXPECT_NE(mixed.stderrText.find("another estimator"), std::string::npos) << mixed.stderrText;
}

TEST_F(Cli, ConvergeDerivativeSeparatesABiasedStepFromTheUnbiasedSeries) {
    // d/dz of the point light's height (smooth): the reference is the sum estimator at 256 spp;
    // the forward difference at h_0 = 0.25 keeps its bias, single_term does not.
    const std::string plane = test::sourcePath("scenes/point-plane.json") +
                              " --set 'camera.resolution=[16,16]' --derivative 'primitives[1].transform.position[1]' "
                              "--step 0.25 -q";
    ASSERT_EQ(run("render " + plane + " --derivative-estimator sum --spp 256 --no-png -o " + out("ref.exr")).exitCode, 0);
    CommandResult r = run("converge " + plane + " --reference " + out("ref.exr") +
                          " --methods forward,single_term --spp 8,32 -o " + out("conv"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    std::istringstream csv(readText(out("conv/convergence.csv")));
    std::string line;
    std::getline(csv, line);
    std::map<std::string, double> finalRmse;
    while (std::getline(csv, line)) {
        std::vector<std::string> cells;
        std::stringstream ls(line);
        for (std::string c; std::getline(ls, c, ',');) cells.push_back(c);
        ASSERT_EQ(cells.size(), 10u) << line;
        finalRmse[cells[0]] = std::stod(cells[6]);
    }
    ASSERT_EQ(finalRmse.size(), 2u);
    EXPECT_GT(finalRmse["\"forward\""], 3.0 * finalRmse["\"single_term\""]);
    EXPECT_NE(readText(out("conv/report.md")).find("derivative d/d(primitives[1].transform.position[1])"), std::string::npos);
    // Radiance presets are not derivative estimators.
    CommandResult bad = run("converge " + plane + " --reference " + out("ref.exr") + " --methods biased:1 --spp 8 -o " +
                            out("conv2"));
    EXPECT_EQ(bad.exitCode, 2) << bad.stderrText;
}
