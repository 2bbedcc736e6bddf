// A Renderer owns what it reads of the scene: the Scene it was made from may change or go away
// before the render runs (a caller's temporary, the viewer's orbit camera, a study's per-method
// copy). The control is in the test itself: the scene is replaced by a default one (512x512
// camera, no debiasing), which a Renderer still reading it would render instead.
#include <gtest/gtest.h>

#include <memory>

#include "render_harness.h"

using namespace telescope;

TEST(RenderOwnership, ARenderDoesNotReadTheSceneItWasMadeFrom) {
    auto scene = std::make_unique<Scene>(test::loadTestScene(
        "scenes/tungsten/cornell-box/scene.json",
        {{"camera.resolution", "[16,12]"}, {"integrator.max_bounces", "2"},
         {"integrator.debias", R"({"estimator":"sum","pmf":{"type":"geometric","r":0.5}})"}}));
    const Film expected = test::renderFilm(*scene, 2, 3);

    Renderer renderer(test::sharedContext(), test::resolved(*scene), 3);
    *scene = Scene{};
    scene.reset();
    RenderRequest request;
    request.spp = 2;
    renderer.render(request);
    const Film film = renderer.film();

    ASSERT_EQ(film.width(), 16u);
    ASSERT_EQ(film.height(), 12u);
    ASSERT_EQ(film.samplesPerPixel(), 2u);
    size_t differing = 0;
    for (uint32_t c = 0; c < shader::kChannelCount; ++c)
        for (size_t i = 0; i < film.pixelCount(); ++i) differing += film.sums(c)[i] != expected.sums(c)[i];
    EXPECT_EQ(differing, 0u);
    test::expectNoValidationMessages();
}
