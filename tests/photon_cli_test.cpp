// The telescope command on photon scenes: the plan names the photon passes, bad photon settings
// are one-line errors naming the file and the key (exit 2, nothing written), and signed pixels
// reach the EXR unclamped, with the positive and negative parts of the correction.
#include <OpenImageIO/imageio.h>  // before anything that may pull in X11

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "render/film_io.h"
#include "render/image_output.h"
#include "render/sample_passes.h"
#include "render_harness.h"

namespace fs = std::filesystem;
using namespace telescope;

namespace {

class PhotonCli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("telescope-photon-cli-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    // Exit code, stdout and stderr of the telescope command.
    int run(const std::string& args, std::string* out = nullptr, std::string* err = nullptr) {
        const std::string outFile = (dir_ / "stdout.txt").string(), errFile = (dir_ / "stderr.txt").string();
        int status = std::system((std::string(TELESCOPE_BINARY) + " " + args + " >" + outFile + " 2>" + errFile).c_str());
        auto slurp = [](const std::string& path) {
            std::ifstream in(path);
            std::stringstream ss;
            ss << in.rdbuf();
            return ss.str();
        };
        if (out) *out = slurp(outFile);
        if (err) *err = slurp(errFile);
        fs::remove(outFile);
        fs::remove(errFile);
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }

    void expectBadInput(const std::string& set, const std::string& key) {
        std::string err;
        int code = run("render " + scene() + " -o " + path("a.exr") + " --set '" + set + "'", nullptr, &err);
        EXPECT_EQ(code, 2) << set << "\n" << err;
        EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << err;
        EXPECT_NE(err.find("point-plane-photon.json"), std::string::npos) << err;
        EXPECT_NE(err.find(key), std::string::npos) << err;
        EXPECT_TRUE(fs::is_empty(dir_)) << "bad input left files behind";
    }

    std::string scene() const { return test::sourcePath("scenes/point-plane-photon.json"); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    fs::path dir_;
};

}  // namespace

TEST_F(PhotonCli, PlanListsThePhotonPasses) {
    for (const char* file : {"scenes/point-plane-photon.json", "scenes/cornell-box-caustic.json"}) {
        std::string text;
        ASSERT_EQ(run("plan " + test::sourcePath(file), &text), 0);
        const std::string scheduled = text.substr(0, text.find("not scheduled:"));
        for (const char* pass : {"photon_trace", "hash_grid_build", "gather"})
            EXPECT_NE(scheduled.find(pass), std::string::npos) << pass << " missing in\n" << text;
        EXPECT_EQ(scheduled.find("path_trace "), std::string::npos) << text;
    }
}

TEST_F(PhotonCli, BadPhotonSettingsNameTheFileAndKey) {
    expectBadInput("integrator.gather_radius=-1", "integrator.gather_radius");
    expectBadInput("integrator.photon_count=0", "integrator.photon_count");
    expectBadInput("integrator.kernel=\"gaussian\"", "integrator.kernel");
    expectBadInput("integrator.direct_lighting=\"sometimes\"", "integrator.direct_lighting");
    expectBadInput("integrator.debias={\"estimator\":\"sum\"}", "integrator.debias.estimator");
}

TEST_F(PhotonCli, BadBlockSettingsNameTheKeyAndTheComputedValue) {
    // q m >= 1: infinite expected cost (q = 1 - r = 0.5, m = 3 gives q m = 1.5).
    expectBadInput("integrator.debias.pmf={\"type\":\"geometric\",\"r\":0.5}", "integrator.debias.photon_growth");
    expectBadInput("integrator.debias.pmf={\"type\":\"geometric\",\"r\":0.5}", "q m = 1.5");
    // m s <= 1: tail index a <= 1, no finite mean (the fixed photon count of the old design, m = 1).
    expectBadInput("integrator.debias.photon_growth=1", "tail index a = ");
    expectBadInput("integrator.debias.area_ratio=0.3", "integrator.debias.photon_growth");
    expectBadInput("integrator.debias.area_ratio=1.5", "integrator.debias.area_ratio");
    expectBadInput("integrator.debias.pmf={\"type\":\"power_law\"}", "integrator.debias.pmf.type");
    expectBadInput("integrator.debias.level_cap=0", "integrator.debias.level_cap");
    expectBadInput("integrator.debias.level_cap=25", "integrator.debias.level_cap");  // 3^24 passes
    expectBadInput("integrator.debias.level_schedule=\"queued\"", "integrator.debias.level_schedule");
    expectBadInput("integrator.debias.levels=3", "integrator.debias.levels");
}

TEST_F(PhotonCli, PlanShowsTheBlockScheduleAndTheTruncation) {
    std::string text, err;
    ASSERT_EQ(run("plan " + scene(), &text, &err), 0) << err;
    for (const char* want : {"photon_growth m = 3", "area_ratio s = 0.707107", "level_cap K = 20", "r = 0.7",
                             "expected 6.15 photon passes per sample", "tail index of the sample error a = 1.45",
                             "s^K = 0.00098 of the base bias", "schedule uniform", "unbiased up to the truncation"})
        EXPECT_NE(text.find(want), std::string::npos) << want << " missing in\n" << text;
    ASSERT_EQ(run("plan " + scene() + " --set integrator.debias.level_schedule='\"per_pixel\"'", &text, &err), 0) << err;
    EXPECT_NE(text.find("consistent, not unbiased"), std::string::npos) << text;
    std::string err2;
    EXPECT_EQ(run("plan " + scene() + " --set integrator.debias.level_schedule='\"per_pixel\"' --set "
                  "integrator.type='\"progressive_photon_map\"'",
                  nullptr, &err2),
              2);
    EXPECT_NE(err2.find("integrator.debias.level_schedule"), std::string::npos) << err2;
}

TEST_F(PhotonCli, ProgressiveTypeIsAccepted) {
    std::string err;
    EXPECT_EQ(run("plan " + scene() + " --set 'integrator.type=\"progressive_photon_map\"'", nullptr, &err), 0) << err;
}

TEST_F(PhotonCli, NegativePixelsSurviveToTheExr) {
    const std::string exr = path("pp.exr"), stats = path("stats.json");
    std::string err;
    ASSERT_EQ(run("render " + scene() + " -o " + exr + " --spp 2 --seed 3 -q --stats-json " + stats +
                      " --set camera.resolution=[32,32] --set integrator.photon_count=20000",
                  nullptr, &err),
              0)
        << err;
    RgbImage img = readExrChannels(exr, {"R", "base.R", "correction.R", "correction_positive.R", "correction_negative.R"});
    size_t negative = 0, negativeParts = 0;
    for (size_t p = 0; p < size_t(img.width) * img.height; ++p) {
        const float* px = &img.pixels[p * 5];
        negative += px[0] < 0.0f;
        negativeParts += px[4] < 0.0f;
        EXPECT_NEAR(px[0], px[1] + px[2], 1e-4f * (1.0f + std::abs(px[0]))) << p;
        EXPECT_NEAR(px[2], px[3] + px[4], 1e-4f * (1.0f + std::abs(px[3]) + std::abs(px[4]))) << p;
    }
    EXPECT_GT(negative, 0u) << "negative pixels must not be clamped";
    EXPECT_GT(negativeParts, 0u);
    std::ifstream in(stats);
    nlohmann::json j = nlohmann::json::parse(in);
    // Two blocks of 3^k photon passes each.
    EXPECT_GE(j["photon_passes"].get<uint64_t>(), 2u);
    EXPECT_EQ(j["photon_paths"].get<uint64_t>(), 20000u * j["photon_passes"].get<uint64_t>());
    EXPECT_GT(j["photons_stored"].get<uint64_t>(), 10000u);
    EXPECT_EQ(j["validation_messages"].get<uint64_t>(), 0u);
}

TEST_F(PhotonCli, TimeLimitsFinishTheBlockOrKeepItInTheCheckpoint) {
    // plan prints the overrun and deadline table for uniform blocks, and with --time the budget in
    // passes it measured; a scene without blocks is refused (exit 2 naming the key).
    std::string text, err;
    ASSERT_EQ(run("plan " + scene(), &text, &err), 0) << err;
    EXPECT_NE(text.find("time limits (uniform blocks"), std::string::npos) << text;
    ASSERT_EQ(run("plan " + scene() + " --set camera.resolution=[16,16] --time 3", &text, &err), 0) << err;
    EXPECT_NE(text.find("--time 3: "), std::string::npos) << text;
    EXPECT_NE(text.find("level weights rho_k of the completed blocks: k0 "), std::string::npos) << text;
    EXPECT_EQ(run("plan " + scene() + " --set integrator.debias=null --time 3", nullptr, &err), 2);
    EXPECT_NE(err.find("integrator.debias"), std::string::npos) << err;

    // A seed whose first block is long (level 4: 81 passes, each over 1 ms).
    const DebiasSettings d = test::loadTestScene("scenes/point-plane-photon.json").integrator.debias;
    uint32_t seed = 1;
    while (photonBlockLevel(d, 0, seed) != 4) ++seed;
    const std::string common = " --set camera.resolution=[16,16] --set integrator.photon_count=20000 -q --no-png --seed " +
                               std::to_string(seed);
    // deadline: stops inside block 0; the checkpoint keeps it, and resumed it completes as an
    // uninterrupted render of one block does.
    ASSERT_EQ(run("render " + scene() + common + " --time 0.02 --time-policy deadline -o " + path("d.exr") +
                      " --checkpoint " + path("d.ckpt"),
                  nullptr, &err),
              0)
        << err;
    const Checkpoint stopped = loadCheckpoint(path("d.ckpt"));
    EXPECT_EQ(stopped.film.samplesPerPixel(), 0u);
    EXPECT_GT(stopped.film.pending().unitsDone, 0u);
    EXPECT_EQ(stopped.film.pending().unitsTotal, 81u);
    ASSERT_EQ(run("render " + scene() + common + " --resume " + path("d.ckpt") + " --spp 1 -o " + path("r.exr") +
                      " --checkpoint " + path("r.ckpt"),
                  nullptr, &err),
              0)
        << err;
    ASSERT_EQ(run("render " + scene() + common + " --spp 1 -o " + path("w.exr") + " --checkpoint " + path("w.ckpt"),
                  nullptr, &err),
              0)
        << err;
    const Film resumed = loadCheckpoint(path("r.ckpt")).film, whole = loadCheckpoint(path("w.ckpt")).film;
    ASSERT_EQ(resumed.samplesPerPixel(), 1u);
    double worst = 0.0;
    for (size_t i = 0; i < whole.pixelCount(); ++i) {
        const glm::dvec4 a = resumed.sums(shader::kChannelEstimate)[i], b = whole.sums(shader::kChannelEstimate)[i];
        worst = std::max(worst, glm::length(a - b) / (glm::length(b) + 1e-3));
    }
    EXPECT_LT(worst, 1e-4) << "the resumed block differs from the uninterrupted one";
    // finish-block (the default): the same limit finishes block 0, all 81 passes.
    ASSERT_EQ(run("render " + scene() + common + " --time 0.02 -o " + path("f.exr") + " --stats-json " + path("f.json"),
                  nullptr, &err),
              0)
        << err;
    std::ifstream statsFile(path("f.json"));
    const nlohmann::json stats = nlohmann::json::parse(statsFile);
    EXPECT_GE(stats["spp"].get<uint64_t>(), 1u);
    EXPECT_GE(stats["photon_passes"].get<uint64_t>(), 81u);
}
