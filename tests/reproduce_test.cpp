// A render is reproduced from its own EXR's metadata alone: the scene document, the file it came
// from, the resolved settings, the seed and the sample count. `reference` is the case where the
// settings differ from the document (it patches the integrator), so the settings are needed; the
// positive controls drop the settings, the seed or the sample count and must not reproduce it.
#include <OpenImageIO/imageio.h>  // before anything that may pull in X11

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>

#include "render/image_output.h"
#include "render_harness.h"
#include "scene/settings_json.h"

namespace fs = std::filesystem;
using namespace telescope;

namespace {

const std::vector<std::string> kChannels = {"R",      "G",      "B",      "base.R",       "base.G",       "base.B",
                                            "correction.R", "correction.G", "correction.B", "variance.R",
                                            "variance.G",   "variance.B"};

struct Metadata {
    std::string sceneFile, scene, settings;
    uint32_t seed = 0;
    uint64_t spp = 0;
};

Metadata readMetadata(const std::string& exr) {
    auto in = OIIO::ImageInput::open(exr);
    if (!in) throw std::runtime_error("cannot open " + exr);
    const OIIO::ImageSpec& spec = in->spec();
    Metadata m;
    m.sceneFile = spec.get_string_attribute("telescope:scene_file");
    m.scene = spec.get_string_attribute("telescope:scene");
    m.settings = spec.get_string_attribute("telescope:settings");
    m.seed = uint32_t(std::stoul(spec.get_string_attribute("telescope:seed")));
    m.spp = std::stoull(spec.get_string_attribute("telescope:spp"));
    return m;
}

// Renders what the metadata describes and writes it as an EXR next to the original.
std::string reproduce(const Metadata& m, const std::string& path) {
    const Scene scene = reproduceScene(m.scene, m.sceneFile, m.settings);
    writeExr(path, test::renderFilm(scene, m.spp, m.seed), ImageMetadata{});
    return path;
}

struct Comparison {
    size_t differing = 0;  // pixels that differ in any channel (bit patterns compared)
    size_t lit = 0;        // pixels of the first with any channel not zero
};

Comparison compare(const std::string& a, const std::string& b) {
    const RgbImage x = readExrChannels(a, kChannels), y = readExrChannels(b, kChannels);
    EXPECT_EQ(x.pixels.size(), y.pixels.size());
    Comparison c;
    if (x.pixels.size() != y.pixels.size()) return {x.pixels.size(), x.pixels.size()};
    const std::vector<float> zero(kChannels.size(), 0.0f);
    for (size_t p = 0; p < x.pixels.size(); p += kChannels.size()) {
        c.differing += std::memcmp(&x.pixels[p], &y.pixels[p], kChannels.size() * sizeof(float)) != 0;
        c.lit += std::memcmp(&x.pixels[p], zero.data(), kChannels.size() * sizeof(float)) != 0;
    }
    return c;
}

}  // namespace

TEST(Reproduce, ReferenceFromItsOwnExrMetadataIsBitIdentical) {
    const fs::path dir = fs::temp_directory_path() / "telescope-reproduce";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::string original = (dir / "ref.exr").string();
    const std::string cmd = std::string(TELESCOPE_BINARY) + " reference " +
                            test::sourcePath("scenes/tungsten/cornell-box/scene.json") +
                            " --set camera.resolution=[24,16] --set integrator.max_bounces=2 --spp 6 --seed 7 -q -o " +
                            original;
    const int status = std::system(cmd.c_str());
    ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmd;

    const Metadata m = readMetadata(original);
    ASSERT_EQ(m.seed, 7u);
    ASSERT_EQ(m.spp, 6u);
    const Comparison same = compare(original, reproduce(m, (dir / "same.exr").string()));
    EXPECT_EQ(same.differing, 0u);
    EXPECT_GT(same.lit, 24u * 16u / 4) << "too few lit pixels to tell renders apart";

    // Positive controls: each dropped piece of the metadata changes at least 90% as many pixels as
    // the original has lit (any channel not zero).
    Metadata noSettings = m;
    noSettings.settings = "{}";  // the document alone: no sum estimator (reference added it)
    Metadata noSeed = m;
    noSeed.seed = 1;  // the default seed
    Metadata noSpp = m;
    noSpp.spp = test::loadTestScene("scenes/tungsten/cornell-box/scene.json").renderer.spp;  // the scene's
    ASSERT_NE(noSpp.spp, m.spp);
    for (const auto& [what, changed] : {std::pair{"settings", noSettings}, {"seed", noSeed}, {"spp", noSpp}}) {
        const Comparison c = compare(original, reproduce(changed, (dir / (std::string(what) + ".exr")).string()));
        std::printf("without the %s: %zu of %zu lit pixels differ\n", what, c.differing, c.lit);
        EXPECT_GE(double(c.differing), 0.9 * double(c.lit)) << "without the " << what;
    }
    test::expectNoValidationMessages();
    fs::remove_all(dir);
}
