// Tungsten's transform conventions (docs/TUNGSTEN-FORMAT.md section 2).
#include "scene/transform.h"

#include <gtest/gtest.h>

namespace telescope {
namespace {

constexpr float kTol = 1e-5f;

void expectVec(const glm::vec3& actual, const glm::vec3& expected, float tol = kTol) {
    EXPECT_NEAR(actual.x, expected.x, tol) << "x";
    EXPECT_NEAR(actual.y, expected.y, tol) << "y";
    EXPECT_NEAR(actual.z, expected.z, tol) << "z";
}

TEST(TungstenRotation, YAngleIsNegated) {
    // rotation (0, 90, 0) takes local +X to world +Z (a standard Ry(+90) would give -Z)
    expectVec(tungstenRotation({0, 90, 0}) * glm::vec3(1, 0, 0), {0, 0, 1});
    expectVec(tungstenRotation({0, 90, 0}) * glm::vec3(0, 0, 1), {-1, 0, 0});
}

TEST(TungstenRotation, XAndZAreStandard) {
    expectVec(tungstenRotation({90, 0, 0}) * glm::vec3(0, 1, 0), {0, 0, 1});
    expectVec(tungstenRotation({0, 0, 90}) * glm::vec3(1, 0, 0), {0, 1, 0});
}

TEST(TungstenRotation, ZIsAppliedFirstThenXThenY) {
    // Z(90): x -> y; X(90): y -> z; then Tungsten Y(90) = standard Ry(-90): z -> -x
    expectVec(tungstenRotation({90, 0, 90}) * glm::vec3(1, 0, 0), {0, 0, 1});
    expectVec(tungstenRotation({90, 90, 90}) * glm::vec3(1, 0, 0), {-1, 0, 0});
}

TEST(TungstenRotation, IsOrthonormal) {
    const glm::mat3 r = tungstenRotation({23, -71, 130});
    const glm::mat3 identity = glm::transpose(r) * r;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) EXPECT_NEAR(identity[i][j], i == j ? 1.0f : 0.0f, kTol);
    EXPECT_NEAR(glm::determinant(r), 1.0f, kTol);
}

TEST(BuildTransform, IdentityByDefault) {
    const glm::mat4 m = buildTransform({});
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) EXPECT_EQ(m[i][j], i == j ? 1.0f : 0.0f);
}

TEST(BuildTransform, ScaleThenRotateThenTranslate) {
    TransformSpec spec;
    spec.position = {1, 2, 3};
    spec.scale = {2, 3, 4};
    spec.rotationDegrees = {0, 0, 90};
    const glm::mat4 m = buildTransform(spec);
    expectVec(transformVector(m, {1, 0, 0}), {0, 2, 0});   // scaled by 2 along local x, then Rz(90)
    expectVec(transformVector(m, {0, 1, 0}), {-3, 0, 0});
    expectVec(transformVector(m, {0, 0, 1}), {0, 0, 4});
    expectVec(transformPoint(m, {0, 0, 0}), {1, 2, 3});    // the position is not rotated
    expectVec(columnLengths(m), {2, 3, 4});
    expectVec(columnDirections(m)[0], {0, 1, 0});
}

TEST(BuildTransform, LookAtBasisIsRightHandedWithNegatedX) {
    // The Cornell box camera: z = look_at - position, y = up, x negated to be right-handed
    TransformSpec spec;
    spec.position = {0, 1, 6.8f};
    spec.lookAt = glm::vec3(0, 1, 0);
    spec.up = glm::vec3(0, 1, 0);
    const glm::mat4 m = buildTransform(spec);
    expectVec(glm::vec3(m[0]), {-1, 0, 0});
    expectVec(glm::vec3(m[1]), {0, 1, 0});
    expectVec(glm::vec3(m[2]), {0, 0, -1});
    expectVec(glm::vec3(m[3]), {0, 1, 6.8f});
    EXPECT_GT(glm::determinant(glm::mat3(m)), 0.0f);
}

TEST(BuildTransform, UpIsOrthogonalisedAgainstLookAt) {
    TransformSpec spec;
    spec.lookAt = glm::vec3(0, 0, 2);
    spec.up = glm::vec3(0, 1, 1);
    const glm::mat4 m = buildTransform(spec);
    expectVec(glm::vec3(m[2]), {0, 0, 1});
    expectVec(glm::vec3(m[1]), {0, 1, 0});
}

TEST(BuildTransform, UpParallelToLookAtStillGivesABasis) {
    TransformSpec spec;
    spec.lookAt = glm::vec3(0, -3, 0);
    spec.up = glm::vec3(0, 1, 0);
    const glm::mat3 b(buildTransform(spec));
    expectVec(b[2], {0, -1, 0});
    EXPECT_NEAR(glm::dot(b[0], b[1]), 0.0f, kTol);
    EXPECT_NEAR(glm::dot(b[1], b[2]), 0.0f, kTol);
    EXPECT_NEAR(glm::determinant(b), 1.0f, kTol);
}

TEST(BuildTransform, ExplicitAxesAreKept) {
    TransformSpec spec;
    spec.xAxis = glm::vec3(0, 0, 2);
    spec.yAxis = glm::vec3(1, 0, 0);
    const glm::mat3 b(buildTransform(spec));
    expectVec(b[0], {0, 0, 1});
    expectVec(b[1], {1, 0, 0});
    expectVec(b[2], {0, 1, 0});  // z made right-handed from x and y
}

TEST(BuildTransform, LookAtIsRotatedToo) {
    TransformSpec spec;
    spec.lookAt = glm::vec3(1, 0, 0);
    spec.rotationDegrees = {0, 90, 0};
    const glm::mat4 m = buildTransform(spec);
    expectVec(transformVector(m, {0, 0, 1}), tungstenRotation({0, 90, 0}) * glm::vec3(1, 0, 0));
}

TEST(MatrixFromRowMajor, TranslationIsTheLastColumn) {
    const glm::mat4 m = matrixFromRowMajor({1, 0, 0, 5,  0, 2, 0, 6,  0, 0, 3, 7,  0, 0, 0, 1});
    expectVec(transformPoint(m, {1, 1, 1}), {6, 8, 10});
    expectVec(transformVector(m, {1, 1, 1}), {1, 2, 3});
}

}  // namespace
}  // namespace telescope
