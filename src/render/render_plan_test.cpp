// The table of shader features (shaders/shared/spec_constants.h): the shaders declare their
// specialisation constants only through it, and `telescope plan` names each pipeline's values by it.
#include "render/render_plan.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "render/derivative.h"
#include "render/renderer.h"
#include "shared/gpu_types.h"

using namespace telescope;

namespace {

// Lines of `text` that declare a specialisation constant by hand (a layout with constant_id).
std::vector<std::string> handDeclarations(const std::string& text) {
    std::vector<std::string> found;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
        const size_t code = line.find("//");
        const std::string before = line.substr(0, code);
        if (before.find("layout(constant_id") != std::string::npos || before.find("layout (constant_id") != std::string::npos)
            found.push_back(line);
    }
    return found;
}

}  // namespace

TEST(ShaderFeatures, NoShaderDeclaresASpecialisationConstantOutsideTheTable) {
    // The scan itself finds a declaration where there is one (and not in a comment).
    EXPECT_EQ(handDeclarations("layout(constant_id = kSpecFilter) const uint kFilter = kFilterTent;\n").size(), 1u);
    EXPECT_EQ(handDeclarations("// layout(constant_id = 3) in a comment\n").size(), 0u);

    const std::filesystem::path shaders = std::filesystem::path(TELESCOPE_SOURCE_DIR) / "shaders";
    size_t files = 0;
    for (const auto& entry : std::filesystem::recursive_directory_iterator(shaders)) {
        if (!entry.is_regular_file()) continue;
        const std::string ext = entry.path().extension().string();
        if (ext != ".comp" && ext != ".glsl" && ext != ".h") continue;
        ++files;
        std::ifstream f(entry.path());
        std::stringstream text;
        text << f.rdbuf();
        const std::vector<std::string> lines = handDeclarations(text.str());
        if (entry.path().filename() == "spec_constants.h") {
            EXPECT_EQ(lines.size(), 1u) << "the table's one declaration macro";
            continue;
        }
        for (const std::string& line : lines)
            ADD_FAILURE() << entry.path() << " declares a specialisation constant outside shared/spec_constants.h: "
                          << line;
    }
    EXPECT_GT(files, 20u) << "the shader sources were not found under " << shaders;
}

TEST(ShaderFeatures, PlanNamesEachValueByTheTable) {
    using namespace shader;
    const std::string s = describeSpecialisation(
        {{kSpecPmfR, gpu::specFloat(0.5f)}, {kSpecHasSpheres, 0u}, {kSpecLightCount, 3u}, {kSpecCapLight, 0xffffffffu}});
    // In id order, typed by the table's row.
    EXPECT_NE(s.find("kHasSpheres         false"), std::string::npos) << s;
    EXPECT_NE(s.find("kPmfR               0.5"), std::string::npos) << s;
    EXPECT_NE(s.find("kLightCount         3"), std::string::npos) << s;
    EXPECT_NE(s.find("kCapLight           0xffffffff"), std::string::npos) << s;
    EXPECT_LT(s.find("kPmfR"), s.find("kHasSpheres"));
    EXPECT_LT(s.find("kHasSpheres"), s.find("kLightCount"));
    // An id the table lacks is the host's mistake, not a line without a name.
    EXPECT_THROW(describeSpecialisation({{63u, 1u}}), std::logic_error);
    EXPECT_EQ(specConstantInfo(63u), nullptr);
    ASSERT_NE(specConstantInfo(kSpecGatherSliceLength), nullptr);
    EXPECT_STREQ(specConstantInfo(kSpecGatherSliceLength)->name, "kGatherSliceLength");
}

// The Renderer and the DerivativeRenderer are made from a ResolvedScene only, and only
// resolveScene makes one (render/resolved_scene.h): a scene with a pmf "auto" cannot reach them
// unresolved. Compile-time checks; each fails if a constructor from a plain Scene is added.
static_assert(!std::is_constructible_v<Renderer, gpu::Context&, const Scene&, uint32_t>);
static_assert(!std::is_constructible_v<DerivativeRenderer, gpu::Context&, const Scene&, const DerivativeSettings&, uint32_t>);
static_assert(!std::is_constructible_v<ResolvedScene, Scene>);
static_assert(!std::is_convertible_v<Scene, ResolvedScene>);
static_assert(std::is_constructible_v<Renderer, gpu::Context&, const ResolvedScene&, uint32_t>);
