#include <gtest/gtest.h>

#include "engine/core/math.h"
#include "engine/core/srt.h"
#include "engine/scene/types.h"

namespace strata {
namespace {

void expect_near(const Vec3& a, const Vec3& b, float eps = 1e-5f) {
    EXPECT_NEAR(a.x, b.x, eps);
    EXPECT_NEAR(a.y, b.y, eps);
    EXPECT_NEAR(a.z, b.z, eps);
}

TEST(Affine, TrsAppliesScaleThenRotationThenTranslation) {
    const Affine t = Affine::trs({1, 2, 3}, Affine::rotation_euler_deg({0, 0, 90}), Vec3(2.0f));
    expect_near(t.transform_point({1, 0, 0}), {1, 4, 3});
    expect_near(t.transform_vector({0, 1, 0}), {-2, 0, 0});
}

TEST(Affine, EulerAnglesApplyXThenYThenZ) {
    const Affine r = Affine::rotation_euler_deg({90, 90, 0});
    // X first takes +Y to +Z, then Y takes +Z to +X.
    expect_near(r.transform_vector({0, 1, 0}), {1, 0, 0});
}

TEST(Affine, QuaternionMatchesEulerForTheSameRotation) {
    const float h = std::sqrt(0.5f);
    const Affine q = Affine::rotation_quaternion({0, 0, h, h});  // 90 degrees about Z
    const Affine e = Affine::rotation_euler_deg({0, 0, 90});
    for (int i = 0; i < 12; ++i) EXPECT_NEAR(q.m[i], e.m[i], 1e-6f);
}

TEST(Srt, DecomposingAndComposingGivesTheTransformBack) {
    for (const Affine& a :
         {Affine::trs({1, -2, 3}, Affine::rotation_euler_deg({30, -50, 110}), {0.5f, 2.0f, 1.5f}),
          Affine::scaling({1, 1, -2}) * Affine::rotation_euler_deg({10, 20, 30}),  // a mirror
          Affine{{1, 0.4f, 0, 0, 0, 1, 0.2f, 0, 0, 0, 1, 0}}}) {  // skewed
        const SrtParts p = decompose_srt(a);
        const Affine back = compose_srt(p);
        for (std::size_t k = 0; k < 12; ++k) EXPECT_NEAR(back.m[k], a.m[k], 1e-5f) << k;
    }
}

TEST(Srt, HalfwayBetweenTwoTurnsIsTheHalfTurnRigidly) {
    const std::vector<Affine> keys = {Affine::rotation_euler_deg({0, 0, 0}),
                                      Affine::rotation_euler_deg({0, 170, 0})};
    const Affine half = motion_at(keys, 0.5f, MotionInterpolation::Srt);
    const Affine expected = Affine::rotation_euler_deg({0, 85, 0});
    for (std::size_t k = 0; k < 12; ++k) EXPECT_NEAR(half.m[k], expected.m[k], 1e-5f) << k;
    // A linear blend of the same keys shrinks the object halfway.
    EXPECT_LT(motion_at(keys, 0.5f).determinant(), 0.01f);
    // 190 degrees is the shorter way round as -170: SRT turns through -85.
    const std::vector<Affine> past = {Affine::identity(), Affine::rotation_euler_deg({0, 190, 0})};
    const Affine back = motion_at(past, 0.5f, MotionInterpolation::Srt);
    const Affine minus = Affine::rotation_euler_deg({0, -85, 0});
    for (std::size_t k = 0; k < 12; ++k) EXPECT_NEAR(back.m[k], minus.m[k], 1e-5f) << k;
}

TEST(Affine, InverseUndoesTheTransform) {
    const Affine t = Affine::trs({3, -1, 2}, Affine::rotation_euler_deg({10, 20, 30}), {1, 2, 0.5f});
    const Affine i = t.inverse();
    expect_near(i.transform_point(t.transform_point({0.3f, -2, 5})), {0.3f, -2, 5}, 1e-4f);
    const Affine id = t * i;
    for (int k = 0; k < 12; ++k) EXPECT_NEAR(id.m[k], Affine::identity().m[k], 1e-5f);
}

TEST(Affine, NormalMatrixKeepsNormalsPerpendicular) {
    const Affine t = Affine::scaling({4, 1, 1});
    const Vec3 tangent = t.transform_vector(glm::normalize(Vec3(1, 1, 0)));
    const Vec3 normal = t.normal_matrix() * glm::normalize(Vec3(1, -1, 0));
    EXPECT_NEAR(glm::dot(tangent, normal), 0.0f, 1e-5f);
}

TEST(Affine, TransformProblemsAreDetected) {
    EXPECT_EQ(transform_problem(Affine::identity()), nullptr);
    EXPECT_EQ(transform_problem(Affine::scaling(Vec3(1e-3f))), nullptr);
    EXPECT_EQ(transform_problem(Affine::scaling({1e3f, 1.0f, 2.0f})), nullptr);
    EXPECT_NE(transform_problem(Affine::scaling({1, 1, 0})), nullptr);
    EXPECT_NE(transform_problem(Affine::scaling({1, 1, 1e-9f})), nullptr);
    EXPECT_NE(transform_problem(Affine::scaling(Vec3(1e7f))), nullptr);
    Affine coplanar;
    coplanar.m = {1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0};  // x and y axes identical
    EXPECT_NE(transform_problem(coplanar), nullptr);
    Affine nan;
    nan.m[5] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_NE(transform_problem(nan), nullptr);
}

TEST(Affine, HugeOrTinyQuaternionsNormaliseToTheirRotation) {
    // In float, the squared length of a quaternion overflows beyond ~1.8e19 and used to
    // normalise to the identity; the rotation of (1, 1, 1, 1) is 120 degrees about (1, 1, 1).
    const Affine unit = Affine::rotation_quaternion(Vec4(0.5f));
    for (float scale : {1e19f, 3e30f, 1e-25f}) {
        const Affine r = Affine::rotation_quaternion(Vec4(scale));
        for (int i = 0; i < 12; ++i) EXPECT_NEAR(r.m[i], unit.m[i], 1e-6f) << scale;
    }
    expect_near(unit.transform_vector({1, 0, 0}), {0, 1, 0});
}

TEST(Affine, TranslationsBeyondTheRayRangeAndTransformsWithoutFiniteInverseAreProblems) {
    EXPECT_EQ(transform_problem(Affine::translation({1e14f, -1e14f, 0})), nullptr);
    EXPECT_NE(transform_problem(Affine::translation({0, 1e19f, 0})), nullptr);
    EXPECT_NE(transform_problem(Affine::translation({-3e38f, 0, 0})), nullptr);
    // Axes of 1e6 at a 1e-6 angle pass the scale checks one by one, not the inverse.
    Affine sheared = Affine::scaling(Vec3(1e6f));
    sheared.m[1] = 1e6f * (1.0f - 1e-7f);
    EXPECT_NE(transform_problem(sheared), nullptr);
}

TEST(Bounds, TransformedBoxContainsTheTransformedCorners) {
    Bounds3 b;
    b.extend({-1, -1, -1});
    b.extend({1, 1, 1});
    const Affine t = Affine::trs({5, 0, 0}, Affine::rotation_euler_deg({0, 45, 0}), Vec3(1.0f));
    const Bounds3 w = t.transform_bounds(b);
    EXPECT_NEAR(w.upper.x, 5.0f + std::sqrt(2.0f), 1e-5f);
    EXPECT_NEAR(w.lower.y, -1.0f, 1e-5f);
    EXPECT_FLOAT_EQ(b.surface_area(), 24.0f);
    EXPECT_TRUE(Bounds3{}.empty());
    EXPECT_EQ(Bounds3{}.surface_area(), 0.0f);
}

}  // namespace
}  // namespace strata
