#include "scene/transform.h"

#include <cmath>

namespace telescope {

namespace {

glm::mat3 rotationX(float a) {
    const float c = std::cos(a), s = std::sin(a);
    return glm::mat3(1, 0, 0,  0, c, s,  0, -s, c);  // columns
}

glm::mat3 rotationY(float a) {
    const float c = std::cos(a), s = std::sin(a);
    return glm::mat3(c, 0, -s,  0, 1, 0,  s, 0, c);
}

glm::mat3 rotationZ(float a) {
    const float c = std::cos(a), s = std::sin(a);
    return glm::mat3(c, s, 0,  -s, c, 0,  0, 0, 1);
}

// Some unit vector perpendicular to a (a is unit length).
glm::vec3 anyPerpendicular(const glm::vec3& a) {
    const glm::vec3 helper = std::abs(a.x) > std::abs(a.y) ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
    return glm::normalize(glm::cross(a, helper));
}

// Gram-Schmidt in priority order: a keeps its direction, b loses its a component, c its a and b
// components. Near-degenerate b or c are replaced by a perpendicular or the cross product.
void orthonormalise(glm::vec3& a, glm::vec3& b, glm::vec3& c) {
    constexpr float kDegenerateSq = 1e-5f;
    a = glm::normalize(a);
    b -= a * glm::dot(a, b);
    b = glm::dot(b, b) < kDegenerateSq ? anyPerpendicular(a) : glm::normalize(b);
    c -= a * glm::dot(a, c);
    c -= b * glm::dot(b, c);
    c = glm::dot(c, c) < kDegenerateSq ? glm::cross(a, b) : glm::normalize(c);
}

}  // namespace

glm::mat3 tungstenRotation(const glm::vec3& degrees) {
    const glm::vec3 r = glm::radians(degrees);
    return rotationY(-r.y) * rotationX(r.x) * rotationZ(r.z);
}

glm::mat4 buildTransform(const TransformSpec& spec) {
    // Basis from the explicit axes (identity otherwise)
    glm::vec3 axis[3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    bool isExplicit[3] = {false, false, false};
    if (spec.lookAt) { axis[2] = *spec.lookAt - spec.position; isExplicit[2] = true; }
    if (spec.up) { axis[1] = *spec.up; isExplicit[1] = true; }
    if (spec.xAxis) { axis[0] = *spec.xAxis; isExplicit[0] = true; }
    if (spec.yAxis) { axis[1] = *spec.yAxis; isExplicit[1] = true; }
    if (spec.zAxis) { axis[2] = *spec.zAxis; isExplicit[2] = true; }

    // Orthonormalise: explicit axes first, then the others, each group in the order z, y, x
    static constexpr int kOrder[8][3] = {
        {2, 1, 0}, {0, 2, 1}, {1, 2, 0}, {1, 0, 2}, {2, 1, 0}, {2, 0, 1}, {2, 1, 0}, {2, 1, 0}};
    const int* order = kOrder[(isExplicit[2] ? 4 : 0) | (isExplicit[1] ? 2 : 0) | (isExplicit[0] ? 1 : 0)];
    orthonormalise(axis[order[0]], axis[order[1]], axis[order[2]]);

    // Right-handed: negate the first axis that was not given
    if (glm::dot(glm::cross(axis[0], axis[1]), axis[2]) < 0.0f) {
        const int flip = !isExplicit[0] ? 0 : !isExplicit[1] ? 1 : 2;
        axis[flip] = -axis[flip];
    }

    // Scale along the local axes, then rotate the scaled basis; the position is not rotated
    const glm::mat3 rotation = tungstenRotation(spec.rotationDegrees);
    glm::mat4 m(1.0f);
    for (int i = 0; i < 3; ++i) m[i] = glm::vec4(rotation * (axis[i] * spec.scale[i]), 0.0f);
    m[3] = glm::vec4(spec.position, 1.0f);
    return m;
}

glm::mat4 matrixFromRowMajor(const std::array<float, 16>& rowMajor) {
    glm::mat4 m;
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 4; ++col) m[col][row] = rowMajor[row * 4 + col];
    return m;
}

glm::vec3 transformPoint(const glm::mat4& m, const glm::vec3& p) { return glm::vec3(m * glm::vec4(p, 1.0f)); }

glm::vec3 transformVector(const glm::mat4& m, const glm::vec3& v) { return glm::vec3(m * glm::vec4(v, 0.0f)); }

glm::vec3 columnLengths(const glm::mat4& m) {
    return {glm::length(glm::vec3(m[0])), glm::length(glm::vec3(m[1])), glm::length(glm::vec3(m[2]))};
}

glm::mat3 columnDirections(const glm::mat4& m) {
    glm::mat3 r;
    for (int i = 0; i < 3; ++i) {
        const glm::vec3 c(m[i]);
        const float len = glm::length(c);
        r[i] = len > 0.0f ? c / len : glm::vec3(0.0f);
    }
    return r;
}

}  // namespace telescope
