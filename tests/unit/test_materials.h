// Small builders shared by the CPU BSDF tests: directions by angle and GPU materials of one type.
#pragma once

#include <cmath>

#include "render/gpu_scene.h"
#include "shared/lang.h"

namespace telescope::test {

// The unit direction at polar angle thetaDeg from +z (the shading normal) and azimuth phiDeg.
inline shader::vec3 fromAngle(float thetaDeg, float phiDeg = 30.0f) {
    const float t = glm::radians(thetaDeg), p = glm::radians(phiDeg);
    return shader::vec3(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
}

inline shader::MaterialGpu orenNayar(float albedo, float roughness) {
    Material m;
    m.type = BsdfType::OrenNayar;
    m.albedo = glm::vec3(albedo);
    m.roughness = roughness;
    return gpuMaterial(m);
}

}  // namespace telescope::test
