// Tungsten's transform conventions (docs/TUNGSTEN-FORMAT.md section 2): how a "transform" object
// becomes a 4x4 matrix, and how primitives read position, rotation and scale back out of it.
#pragma once

#include <array>
#include <optional>

#include <glm/glm.hpp>

namespace telescope {

// Tungsten's "rotation" in degrees (Mat4f::rotYXZ): R = Ry(-y) Rx(x) Rz(z) acting on column
// vectors, so Z is applied first and the Y angle is negated.
glm::mat3 tungstenRotation(const glm::vec3& degrees);

// The fields of a transform object. An axis that is set is "explicit": Gram-Schmidt keeps it
// first and the handedness fix never negates it.
struct TransformSpec {
    glm::vec3 position{0.0f};
    std::optional<glm::vec3> lookAt;  // sets z = lookAt - position
    std::optional<glm::vec3> up;      // sets y
    std::optional<glm::vec3> xAxis, yAxis, zAxis;
    glm::vec3 scale{1.0f};
    glm::vec3 rotationDegrees{0.0f};
};

// M = T(position) R(rotation) B S(scale), with B the orthonormal, right-handed basis made from
// the explicit axes. Explicit axes must be non-zero and look_at must differ from position.
glm::mat4 buildTransform(const TransformSpec& spec);

// A 16-element array read row by row, as Tungsten stores matrices.
glm::mat4 matrixFromRowMajor(const std::array<float, 16>& rowMajor);

glm::vec3 transformPoint(const glm::mat4& m, const glm::vec3& p);
glm::vec3 transformVector(const glm::mat4& m, const glm::vec3& v);

// Lengths of the columns of the 3x3 part (Tungsten's extractScale).
glm::vec3 columnLengths(const glm::mat4& m);

// The columns of the 3x3 part normalised (Tungsten's extractRotation); shear is ignored.
glm::mat3 columnDirections(const glm::mat4& m);

}  // namespace telescope
