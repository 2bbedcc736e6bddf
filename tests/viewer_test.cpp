// telescope view under Xvfb: the window shows the Renderer's film (a screenshot equals the PNG
// `render` writes for the same scene, seed and samples), channel keys change what is shown (the
// negative correction of a biased render is black, of unbiased photon mapping it is not), moving
// the camera restarts the samples, the save key writes the EXR `render` writes for the camera and
// samples shown, SIGINT and Escape end it cleanly, and without a display it fails with one line.
#include <OpenImageIO/imageio.h>  // before anything that may pull in X11

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "render/image_output.h"
#include "render_harness.h"

namespace fs = std::filesystem;
using namespace telescope;

namespace {

struct Result {
    int exitCode = -1;
    std::string out, err;
};

std::string readText(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

struct Image8 {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;
    int at(int x, int y, int c) const { return rgb[(size_t(y) * width + x) * 3 + c]; }
};

Image8 readPng(const std::string& path) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw std::runtime_error("cannot open " + path);
    Image8 img;
    img.width = in->spec().width;
    img.height = in->spec().height;
    if (in->spec().nchannels != 3) throw std::runtime_error(path + ": not RGB");
    img.rgb.resize(size_t(img.width) * img.height * 3);
    if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, img.rgb.data())) throw std::runtime_error("cannot read " + path);
    return img;
}

// Largest and mean absolute byte difference between the film area (top-left w x h) of a
// screenshot and a w x h image.
std::pair<int, double> compareFilmArea(const Image8& shot, const Image8& image) {
    int maxDiff = 0;
    double sum = 0.0;
    for (int y = 0; y < image.height; ++y)
        for (int x = 0; x < image.width; ++x)
            for (int c = 0; c < 3; ++c) {
                int d = std::abs(shot.at(x, y, c) - image.at(x, y, c));
                maxDiff = std::max(maxDiff, d);
                sum += d;
            }
    return {maxDiff, sum / (3.0 * image.width * image.height)};
}

// Samples per pixel shown at each frame, from the "frame N: channel, S spp, ..." lines.
std::map<int, int> sppByFrame(const std::string& out) {
    std::map<int, int> m;
    std::regex line(R"(frame (\d+): [a-z_]+, (\d+) spp)");
    for (std::sregex_iterator it(out.begin(), out.end(), line), end; it != end; ++it)
        m[std::stoi((*it)[1])] = std::stoi((*it)[2]);
    return m;
}

std::string exrAttribute(const std::string& path, const std::string& name) {
    auto in = OIIO::ImageInput::open(path);
    if (!in) throw std::runtime_error("cannot open " + path);
    return in->spec().get_string_attribute(name);
}

// Largest |a - b| / (1e-3 + |b|) over the estimate channels of two EXRs of the same size.
double maxRelativeDifference(const std::string& a, const std::string& b) {
    RgbImage x = readExrChannels(a, {"R", "G", "B"}), y = readExrChannels(b, {"R", "G", "B"});
    if (x.pixels.size() != y.pixels.size()) return 1e30;
    double worst = 0.0;
    for (size_t i = 0; i < x.pixels.size(); ++i)
        worst = std::max(worst, double(std::abs(x.pixels[i] - y.pixels[i])) / (1e-3 + std::abs(y.pixels[i])));
    return worst;
}

class Viewer : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("telescope-view-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        if (!HasFailure()) fs::remove_all(dir_);
    }

    Result run(const std::string& command) {
        const std::string out = (dir_ / "stdout.txt").string(), err = (dir_ / "stderr.txt").string();
        int status = std::system((command + " >" + out + " 2>" + err).c_str());
        Result r;
        r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        r.out = readText(out);
        r.err = readText(err);
        return r;
    }
    // The telescope binary under a virtual X server (its own display number, so tests may run in
    // parallel), with a small screen.
    Result view(const std::string& args) {
        const int display = 100 + int(getpid() % 5000);
        return run(fmt::format("xvfb-run -a -n {} -s '-screen 0 320x240x24' {} view {}", display, TELESCOPE_BINARY, args));
    }
    Result telescope(const std::string& args) { return run(std::string(TELESCOPE_BINARY) + " " + args); }

    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    fs::path dir_;
};

void expectClean(const Result& r) {
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_EQ(r.err.find("[vulkan"), std::string::npos) << "validation messages:\n" << r.err;
}

}  // namespace

// Biased path tracing (the Cornell box at 48x48, seed 5): screenshot against `render`, the black
// negative view, the plan, a camera move and the save key.
TEST_F(Viewer, PathTracerScreenshotChannelsCameraAndSave) {
    const std::string scene = test::sourcePath("scenes/cornell-box.json");
    const std::string sets = "--set 'camera.resolution=[48,48]'";
    Result v = view(scene + " " + sets + " --seed 5 --spp 8 --frames 100 -o " + path("a.exr") + " --screenshot " +
                    path("s.png") + " --keys 'shot@9,5@10,shot@11,Left@13,s@21,Escape@22'");
    expectClean(v);

    // ---- The plan it prints is the plan `telescope plan` prints ----
    Result plan = telescope("plan " + scene + " " + sets);
    ASSERT_EQ(plan.exitCode, 0) << plan.err;
    EXPECT_EQ(v.out.rfind(plan.out, 0), 0u) << "viewer:\n" << v.out << "\nplan:\n" << plan.out;

    // ---- Samples shown: 8 by frame 12 (each frame adds at least 1); the camera move at frame
    // 13 starts again at 1, and 8 are back by frame 20 ----
    auto spp = sppByFrame(v.out);
    EXPECT_EQ(spp[12], 8);
    EXPECT_EQ(spp[13], 1) << "moving the camera must restart the samples";
    EXPECT_EQ(spp[20], 8);
    EXPECT_EQ(spp.count(22), 0u) << "Escape at frame 22 closes the window before it renders";

    // ---- Estimate screenshot (frame 9, 8 spp) = render's PNG of the same samples ----
    Result r = telescope("render " + scene + " " + sets + " --seed 5 --spp 8 -q -o " + path("r.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    Image8 shot = readPng(path("s-9.png")), rendered = readPng(path("r.png"));
    ASSERT_EQ(shot.width, 48);
    ASSERT_EQ(shot.height, 48 + 12) << "film above a 12-row legend";
    auto [maxDiff, meanDiff] = compareFilmArea(shot, rendered);
    EXPECT_LE(maxDiff, 1) << "the display pass tone-maps as the PNG preview does (1: rounding)";
    EXPECT_LT(meanDiff, 0.05);

    // ---- Negative correction of a biased render: black ----
    Image8 negative = readPng(path("s-11.png"));
    int lit = 0;
    for (int y = 0; y < 48; ++y)
        for (int x = 0; x < 48; ++x)
            for (int c = 0; c < 3; ++c) lit += negative.at(x, y, c) > 0;
    EXPECT_EQ(lit, 0);

    // ---- Saved at frame 21: the samples shown at frame 20, the moved camera in the metadata ----
    const std::string saved = path("a.exr");
    ASSERT_TRUE(fs::exists(saved)) << v.err;
    EXPECT_EQ(exrAttribute(saved, "telescope:spp"), "8");
    EXPECT_EQ(exrAttribute(saved, "telescope:seed"), "5");
    nlohmann::json doc = nlohmann::json::parse(exrAttribute(saved, "telescope:scene"));
    EXPECT_NE(doc["camera"]["transform"]["position"], nlohmann::json::parse("[0, 1, 6.8]")) << "the camera moved";
    std::ofstream(path("moved.json")) << doc.dump();
    // Rendering the saved scene gives the saved image: no samples of the first camera are in it.
    ASSERT_EQ(telescope("render " + path("moved.json") + " --spp 8 --seed 5 -q -o " + path("m.exr")).exitCode, 0);
    EXPECT_LT(maxRelativeDifference(saved, path("m.exr")), 1e-4);
    // Control: the same seed and samples from the first camera fail the same comparisons.
    EXPECT_GT(maxRelativeDifference(saved, path("r.exr")), 1e-2);
    EXPECT_GT(compareFilmArea(shot, readPng(path("m.png"))).first, 1);
}

// Unbiased photon mapping (signed corrections): the correction view differs from the estimate,
// the negative view is not black, a camera move changes the camera in place, SIGINT ends it.
TEST_F(Viewer, PhotonChannelsCameraAndInterrupt) {
    const std::string scene = test::sourcePath("scenes/point-plane-photon.json");
    const std::string sets = "--set 'camera.resolution=[32,32]'";
    Result v = view(scene + " " + sets + " --seed 3 --spp 4 --frames 100 -o " + path("b.exr") + " --screenshot " +
                    path("p.png") + " --keys 'shot@6,3@7,shot@8,5@9,shot@10,Left@11,s@13,resize:80:60@13,interrupt@14'");
    expectClean(v);
    EXPECT_NE(v.err.find("(interrupted)"), std::string::npos) << v.err;
    auto spp = sppByFrame(v.out);
    EXPECT_EQ(spp.count(15), 0u) << "SIGINT at frame 14 ends the loop after that frame";
    EXPECT_EQ(spp[11], 1) << "moving the camera must restart the samples";
    EXPECT_NE(v.err.find("same pipelines"), std::string::npos) << "photon passes change the camera in place";
    // Resized at frame 13: the swapchain follows the window, the film is scaled to fit above the legend.
    Image8 resized = readPng(path("p.png"));
    EXPECT_EQ(resized.width, 80);
    EXPECT_EQ(resized.height, 60);

    // ---- Correction view differs from the estimate view ----
    Image8 estimate = readPng(path("p-6.png")), correction = readPng(path("p-8.png")), negative = readPng(path("p-10.png"));
    Image8 crop = estimate;
    crop.height = 32;
    EXPECT_GT(compareFilmArea(correction, crop).second, 5.0) << "correction and estimate views look the same";

    // ---- Negative correction of unbiased photon mapping: not black (the control of the black test) ----
    int lit = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) lit += negative.at(x, y, 2) > 0;
    EXPECT_GT(lit, 0);

    // ---- Saved after the move: `render` of its scene gives the same image ----
    const std::string saved = path("b.exr");
    ASSERT_TRUE(fs::exists(saved)) << v.err;
    EXPECT_EQ(exrAttribute(saved, "telescope:spp"), std::to_string(spp[12]));
    std::ofstream(path("moved.json")) << exrAttribute(saved, "telescope:scene");
    ASSERT_EQ(telescope("render " + path("moved.json") + " --spp " + std::to_string(spp[12]) + " --seed 3 -q -o " +
                        path("m.exr"))
                  .exitCode,
              0);
    EXPECT_LT(maxRelativeDifference(saved, path("m.exr")), 1e-4);
}

TEST_F(Viewer, WithoutDisplayFailsWithOneLine) {
    Result r = run(std::string("env -u DISPLAY -u WAYLAND_DISPLAY ") + TELESCOPE_BINARY + " view " +
                   test::sourcePath("scenes/cornell-box.json") + " -o " + path("x.exr"));
    EXPECT_EQ(r.exitCode, 1) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find("xvfb-run"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("telescope render"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(path("x.exr")));
}

TEST_F(Viewer, BadScriptingInputIsBadInput) {
    const std::string scene = test::sourcePath("scenes/cornell-box.json");
    for (const char* args : {"--keys 'Left@0'", "--keys 'nokey@3,s@4'", "--keys 'shot@2'", "--channel nope"}) {
        Result r = run(std::string("env -u DISPLAY ") + TELESCOPE_BINARY + " view " + scene + " " + args);  // no window
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.err;
        EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << args << "\n" << r.err;
        EXPECT_TRUE(r.err.find("--keys") != std::string::npos || r.err.find("--channel") != std::string::npos) << r.err;
    }
}

// Derivative images (--derivative): the signed view (blue where raising the light dims the plane,
// red far out), the plan's derivative lines, and the save key's EXR = `render --derivative`.
TEST_F(Viewer, DerivativeViewIsSignedAndSavesTheRenderedDerivative) {
    const std::string scene = test::sourcePath("scenes/point-plane.json");
    const std::string args = "--set 'camera.resolution=[32,32]' --derivative 'primitives[1].transform.position[1]' --seed 4";
    Result v = view(scene + " " + args + " --spp 6 --frames 12 -o " + path("d.exr") + " --screenshot " + path("s.png") +
                    " --keys 's@11'");
    expectClean(v);
    EXPECT_NE(v.out.find("parameter   primitives[1].transform.position[1] = 1"), std::string::npos) << v.out;
    Image8 shot = readPng(path("s.png"));
    ASSERT_EQ(shot.width, 32);
    EXPECT_GT(shot.at(16, 16, 2), shot.at(16, 16, 0) + 50) << "under the light the derivative is negative: blue";
    int red = 0;
    for (int y = 0; y < 32; ++y)
        for (int x = 0; x < 32; ++x) red += shot.at(x, y, 0) > shot.at(x, y, 2);
    EXPECT_GT(red, 0) << "beyond sqrt(2) z it is positive: red";
    const std::string saved = path("d.exr");
    ASSERT_TRUE(fs::exists(saved)) << v.err;
    EXPECT_EQ(exrAttribute(saved, "telescope:derivative_key"), "primitives[1].transform.position[1]");
    EXPECT_EQ(exrAttribute(saved, "telescope:spp"), "6");
    ASSERT_EQ(telescope("render " + scene + " " + args + " --spp 6 -q -o " + path("r.exr")).exitCode, 0);
    EXPECT_LT(maxRelativeDifference(saved, path("r.exr")), 1e-6);
}
