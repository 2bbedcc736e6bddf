#include "render_harness.h"

namespace telescope::test {

gpu::Context& sharedContext() {
    static gpu::Context context{gpu::ContextOptions{}};
    return context;
}

std::string sourcePath(const std::string& relative) { return std::string(TELESCOPE_SOURCE_DIR) + "/" + relative; }

Scene loadTestScene(const std::string& relative, const std::vector<SceneOverride>& overrides) {
    return loadScene(sourcePath(relative), overrides);
}

Film renderFilm(const Scene& scene, uint64_t spp, uint32_t seed) {
    Renderer renderer(sharedContext(), scene, seed);
    RenderRequest request;
    request.spp = spp;
    renderer.render(request);
    expectLoopsComplete(renderer.stats());
    return renderer.film();
}

void expectLoopsComplete(const RenderStats& stats) {
    EXPECT_EQ(stats.loops.capHits, 0u) << "lavapipe's loop cap was reached: loops ended early";
    EXPECT_EQ(stats.loops.overlong, 0u) << "samples dropped by the loop budget";
}

void expectNoValidationMessages() {
    EXPECT_EQ(sharedContext().validationMessageCount(), 0u) << "Vulkan validation reported problems";
}

}  // namespace telescope::test
