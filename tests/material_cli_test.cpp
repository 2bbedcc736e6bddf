// The material families on the command line: `plan` lists which glossy families are compiled into
// the path tracer, and photon mapping refuses a bsdf it does not implement (exit 2, the file and
// the bsdf's key named, no output written).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <regex>

#include "cli_process.h"

using namespace telescope;
using namespace telescope::test;

namespace {

class MaterialCli : public ScratchTest {
protected:
    MaterialCli() : ScratchTest("material-cli-" + std::to_string(::getpid())) {}
};

}  // namespace

TEST_F(MaterialCli, PlanListsTheGlossyFamiliesOfTheScene) {
    const std::string outFile = out("plan.txt");
    const int status = std::system(
        (std::string(TELESCOPE_BINARY) + " plan " + sourcePath("scenes/rough-plastic.json") + " > " + outFile).c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    const std::string text = readText(outFile);
    EXPECT_TRUE(std::regex_search(text, std::regex("rough_plastic +on +rough_plastic materials present"))) << text;
    for (const char* family : {"rough_conductor", "plastic", "oren_nayar", "rough_dielectric"})
        EXPECT_TRUE(std::regex_search(text, std::regex(std::string("\n  ") + family + " +off +no " + family))) << family << "\n" << text;
    // The Cornell box has none of them.
    const int cornell = std::system(
        (std::string(TELESCOPE_BINARY) + " plan " + sourcePath("scenes/cornell-box.json") + " > " + outFile).c_str());
    ASSERT_TRUE(WIFEXITED(cornell) && WEXITSTATUS(cornell) == 0);
    EXPECT_EQ(readText(outFile).find(" on   rough"), std::string::npos) << readText(outFile);
}

// The thin materials' families: scenes/mixed.json has mixed (and its rough_conductor component),
// no thinsheet or transparency.
TEST_F(MaterialCli, PlanListsTheThinMaterialFamilies) {
    const std::string outFile = out("plan-mixed.txt");
    const int status = std::system(
        (std::string(TELESCOPE_BINARY) + " plan " + sourcePath("scenes/mixed.json") + " > " + outFile).c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    const std::string text = readText(outFile);
    EXPECT_TRUE(std::regex_search(text, std::regex("\n  mixed +on +mixed materials present"))) << text;
    EXPECT_TRUE(std::regex_search(text, std::regex("\n  rough_conductor +on"))) << text;
    for (const char* family : {"thinsheet", "transparency"})
        EXPECT_TRUE(std::regex_search(text, std::regex(std::string("\n  ") + family + " +off +no " + family))) << family << "\n" << text;
    const int sheet = std::system(
        (std::string(TELESCOPE_BINARY) + " plan " + sourcePath("scenes/thinsheet.json") + " > " + outFile).c_str());
    ASSERT_TRUE(WIFEXITED(sheet) && WEXITSTATUS(sheet) == 0);
    EXPECT_TRUE(std::regex_search(readText(outFile), std::regex("\n  thinsheet +on"))) << readText(outFile);
    EXPECT_TRUE(std::regex_search(readText(outFile), std::regex("\n  mixed +off"))) << readText(outFile);
}

TEST_F(MaterialCli, PhotonMappingRendersEveryBsdfIncludingTheRoughDielectric) {
    // The photon plane with a rough glass floor, then a gold one: photon mapping implements both
    // (their images against the path tracer: tests/photon_material_test.cpp, photon_refraction_test.cpp).
    for (const char* floor : {"--set bsdfs[0].type=rough_dielectric --set bsdfs[0].roughness=0.3",
                              "--set bsdfs[0].type=rough_conductor --set bsdfs[0].material=Au"}) {
        const std::string exr = out("photons.exr");
        std::filesystem::remove(exr);
        const CommandResult ok = run("render " + sourcePath("scenes/point-plane-photon.json") + " -o " + exr + " " +
                                     floor + " --set camera.resolution=[8,8] --spp 1 -q --no-png");
        EXPECT_EQ(ok.exitCode, 0) << floor << "\n" << ok.stderrText;
        EXPECT_TRUE(std::filesystem::exists(exr)) << floor;
    }
}
