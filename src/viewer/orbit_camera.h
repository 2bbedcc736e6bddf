// The viewer's camera: orbit about a pivot, pan, zoom, written back into the scene as a Tungsten
// camera transform (position, look_at, up), so a saved EXR's scene metadata renders the same
// image with `telescope render`. Header-only maths (tested in orbit_camera_test.cpp).
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "scene/scene.h"
#include "scene/transform.h"

namespace telescope::viewer {

struct OrbitCamera {
    glm::vec3 position{0.0f};
    glm::vec3 pivot{0.0f, 0.0f, 1.0f};  // look_at: the point orbits turn about
    glm::vec3 up{0.0f, 1.0f, 0.0f};     // world up: yaw turns about it

    // The scene's camera, orbiting about the point `distance` ahead of it.
    static OrbitCamera fromCamera(const Camera& c, float distance) {
        OrbitCamera o;
        o.position = c.position;
        o.pivot = c.position + c.forward * std::max(distance, 1e-4f);
        o.up = c.up;
        return o;
    }

    float distance() const { return glm::length(position - pivot); }

    // Turns the camera about the pivot: yaw about `up`, pitch about the camera's right axis,
    // stopping short of the poles so the view never flips.
    void orbit(float yawRadians, float pitchRadians) {
        const glm::vec3 u = glm::normalize(up);
        glm::vec3 offset = position - pivot;
        const float r = glm::length(offset);
        glm::vec3 d = offset / r;
        d = rotate(d, u, yawRadians);
        const float maxPitch = 1.5f;  // radians from the horizon (86 degrees)
        const float pitch = std::asin(std::clamp(glm::dot(d, u), -1.0f, 1.0f));
        const float newPitch = std::clamp(pitch + pitchRadians, -maxPitch, maxPitch);
        const glm::vec3 right = glm::cross(u, d);
        if (glm::length(right) > 1e-6f) d = rotate(d, glm::normalize(right), -(newPitch - pitch));
        position = pivot + d * r;
    }

    // Moves camera and pivot across the view, by fractions of the pivot distance.
    void pan(float dx, float dy) {
        const glm::vec3 f = glm::normalize(pivot - position);
        const glm::vec3 right = glm::normalize(glm::cross(f, up));
        const glm::vec3 camUp = glm::cross(right, f);
        const glm::vec3 shift = (right * dx + camUp * dy) * distance();
        position += shift;
        pivot += shift;
    }

    // Moves the camera towards the pivot (factor < 1) or away from it (> 1).
    void zoom(float factor) { position = pivot + (position - pivot) * std::clamp(factor, 0.01f, 100.0f); }

    // The Tungsten transform object of this camera.
    nlohmann::json transformJson() const {
        return {{"position", {position.x, position.y, position.z}},
                {"look_at", {pivot.x, pivot.y, pivot.z}},
                {"up", {up.x, up.y, up.z}}};
    }

    // The scene camera with this position and orientation, computed as the scene loader computes
    // it from transformJson() (scene_loader.cpp, readCamera), so the two agree bit for bit.
    Camera apply(Camera c) const {
        TransformSpec spec;
        spec.position = position;
        spec.lookAt = pivot;
        spec.up = up;
        const glm::mat4 m = buildTransform(spec);
        const glm::vec3 forward = transformVector(m, {0, 0, 1}), camUp = transformVector(m, {0, 1, 0});
        c.position = glm::vec3(m[3]);
        c.forward = glm::normalize(forward);
        c.right = glm::normalize(glm::cross(forward, camUp));
        c.up = glm::cross(c.right, c.forward);
        return c;
    }

private:
    static glm::vec3 rotate(const glm::vec3& v, const glm::vec3& axis, float angle) {
        // Rodrigues' rotation formula.
        const float c = std::cos(angle), s = std::sin(angle);
        return v * c + glm::cross(axis, v) * s + axis * glm::dot(axis, v) * (1.0f - c);
    }
};

}  // namespace telescope::viewer
