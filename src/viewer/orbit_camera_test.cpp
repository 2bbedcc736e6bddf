// The viewer's camera: written back as a transform, the scene loader reads the same camera bit
// for bit (so a saved EXR's scene renders the viewer's image); orbits keep the distance to the
// pivot and stop short of the poles; pans move camera and pivot together.
#include <gtest/gtest.h>

#include <glm/gtc/constants.hpp>

#include "scene/scene_loader.h"
#include "viewer/orbit_camera.h"

using namespace telescope;
using telescope::viewer::OrbitCamera;

namespace {

Scene cornellBox(const std::vector<SceneOverride>& overrides = {}) {
    return loadScene(std::string(TELESCOPE_SOURCE_DIR) + "/scenes/cornell-box.json", overrides);
}

void expectSameCamera(const Camera& a, const Camera& b) {
    for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(a.position[i], b.position[i]) << i;
        EXPECT_EQ(a.forward[i], b.forward[i]) << i;
        EXPECT_EQ(a.up[i], b.up[i]) << i;
        EXPECT_EQ(a.right[i], b.right[i]) << i;
    }
}

}  // namespace

TEST(OrbitCamera, AppliedCameraEqualsTheLoadedTransform) {
    const Scene scene = cornellBox();
    OrbitCamera cam = OrbitCamera::fromCamera(scene.camera, 6.8f);
    for (int step = 0; step < 4; ++step) {
        cam.orbit(0.3f, -0.2f);
        cam.pan(0.1f, 0.05f);
        cam.zoom(0.8f);
        const Scene reloaded = cornellBox({{"camera.transform", cam.transformJson().dump()}});
        expectSameCamera(cam.apply(scene.camera), reloaded.camera);
    }
}

TEST(OrbitCamera, UnmovedCameraIsTheScenesCamera) {
    // The Cornell box looks along -z from (0, 1, 6.8) at (0, 1, 0).
    const Scene scene = cornellBox();
    const Camera c = OrbitCamera::fromCamera(scene.camera, 6.8f).apply(scene.camera);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(c.position[i], scene.camera.position[i], 1e-6f);
        EXPECT_NEAR(c.forward[i], scene.camera.forward[i], 1e-6f);
        EXPECT_NEAR(c.up[i], scene.camera.up[i], 1e-6f);
    }
}

TEST(OrbitCamera, OrbitKeepsDistanceAndTurnsByTheAngle) {
    OrbitCamera cam;
    cam.position = {0, 0, 5};
    cam.pivot = {0, 0, 0};
    cam.up = {0, 1, 0};
    cam.orbit(glm::half_pi<float>(), 0.0f);  // a quarter turn about +y: +z goes to +x
    EXPECT_NEAR(cam.position.x, 5.0f, 1e-5f);
    EXPECT_NEAR(cam.position.z, 0.0f, 1e-5f);
    EXPECT_NEAR(cam.distance(), 5.0f, 1e-5f);
    cam.orbit(0.0f, 0.5f);  // pitch up: the camera rises
    EXPECT_NEAR(cam.position.y, 5.0f * std::sin(0.5f), 1e-5f);
    EXPECT_NEAR(cam.distance(), 5.0f, 1e-5f);
    cam.orbit(0.0f, 10.0f);  // never over the pole
    EXPECT_LT(cam.position.y / cam.distance(), std::sin(1.5f) + 1e-5f);
    EXPECT_GT(glm::length(glm::cross(glm::normalize(cam.pivot - cam.position), cam.up)), 0.05f);
}

TEST(OrbitCamera, PanMovesCameraAndPivotTogetherAcrossTheView) {
    OrbitCamera cam;
    cam.position = {0, 0, 5};
    cam.pivot = {0, 0, 0};
    cam.up = {0, 1, 0};
    cam.pan(0.2f, 0.0f);  // right is forward x up = (-z) x y = +x, by 0.2 of the distance
    EXPECT_NEAR(cam.position.x, 1.0f, 1e-5f);
    EXPECT_NEAR(cam.pivot.x, 1.0f, 1e-5f);
    EXPECT_NEAR(cam.distance(), 5.0f, 1e-5f);
    cam.zoom(0.5f);
    EXPECT_NEAR(cam.distance(), 2.5f, 1e-5f);
    EXPECT_NEAR(cam.pivot.x, 1.0f, 1e-5f);
}
