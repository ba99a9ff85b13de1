// Aiming the camera (protocol/framing.h): the framed box is in view, the viewing direction is
// kept, and what cannot be framed is a problem naming the member.

#include <gtest/gtest.h>

#include "engine/render/render_request.h"
#include "engine/scene/shapes.h"
#include "protocol/framing.h"

namespace strata::protocol {
namespace {

/// Whether `p` projects inside the frame of `c` (aspect width / height).
bool in_view(const Camera& c, Vec3 p, float aspect) {
    const Vec3 f = glm::normalize(c.target - c.eye);
    const Vec3 r = glm::normalize(glm::cross(f, c.up));
    const Vec3 u = glm::cross(r, f);
    const Vec3 d = p - c.eye;
    const float z = glm::dot(d, f);
    const float t = std::tan(0.5f * glm::radians(c.fov_y_deg));
    return z > 0.0f && std::abs(glm::dot(d, u)) <= z * t &&
           std::abs(glm::dot(d, r)) <= z * t * aspect;
}

TEST(Framing, TheBoxIsInViewFromTheSameDirection) {
    Camera scene;
    scene.eye = Vec3(0, 2, 8);
    scene.target = Vec3(0, 0, 0);
    scene.fov_y_deg = 40.0f;
    Bounds3 box;
    box.extend(Vec3(90, -3, 40));
    box.extend(Vec3(110, 5, 44));
    for (float aspect : {0.5f, 1.0f, 16.0f / 9.0f}) {
        const SetCamera framed = frame_box(scene, box, aspect);
        Camera c = scene;
        c.eye = *framed.eye;
        c.target = *framed.target;
        EXPECT_EQ(c.target, box.center());
        for (int k = 0; k < 8; ++k) {
            const Vec3 corner((k & 1) ? box.upper.x : box.lower.x,
                              (k & 2) ? box.upper.y : box.lower.y,
                              (k & 4) ? box.upper.z : box.lower.z);
            EXPECT_TRUE(in_view(c, corner, aspect)) << aspect << " corner " << k;
        }
        const Vec3 was = glm::normalize(scene.target - scene.eye);
        EXPECT_NEAR(glm::dot(was, glm::normalize(c.target - c.eye)), 1.0f, 1e-5f);
        // Close: the box fills a good part of the frame (its sphere touches the narrower side).
        EXPECT_LT(glm::length(c.eye - c.target), 3.0f * glm::length(box.extent()) / aspect + 1.0f);
    }
}

TEST(Framing, AGroupsSubtreeIsFramedAndWhatCannotBeIsAProblem) {
    Scene s;
    EditBatch b;
    b.edits.emplace_back(add_mesh_edit("box", make_box(Vec3(1.0f))));
    b.edits.emplace_back(AddGroup{"far", std::nullopt, Affine::translation({50, 0, 0}), true});
    b.edits.emplace_back(AddGroup{"inner", std::string("far"), Affine::translation({0, 10, 0}),
                                  true});
    b.edits.emplace_back(AddGroup{"empty", std::nullopt, Affine{}, true});
    AddInstance a;
    a.id = "a";
    a.mesh = "box";
    a.parent = "inner";
    a.visible = false;  // hidden instances count: bounds are where things are
    b.edits.emplace_back(a);
    ASSERT_TRUE(s.apply(std::move(b)).has_value());

    const Bounds3 box = subtree_bounds(s, s.find_group("far"));
    EXPECT_NEAR(box.center().x, 50.0f, 1e-5f);
    EXPECT_NEAR(box.center().y, 10.0f, 1e-5f);
    EXPECT_TRUE(subtree_bounds(s, s.find_group("empty")).empty());

    auto framed = framed_override(s, {FrameTarget::Kind::Group, "far"}, std::nullopt, 1.0f);
    ASSERT_TRUE(framed.has_value()) << framed.error().detail;
    EXPECT_EQ(*framed->target, box.center());
    // The override's field of view is kept (and checked as the launch checks it).
    SetCamera narrow;
    narrow.fov_y_deg = 10.0f;
    auto far_away = framed_override(s, {FrameTarget::Kind::Instance, "a"}, narrow, 1.0f);
    ASSERT_TRUE(far_away.has_value());
    EXPECT_EQ(far_away->fov_y_deg, 10.0f);
    EXPECT_GT(glm::length(*far_away->eye - *far_away->target),
              glm::length(*framed->eye - *framed->target));

    EXPECT_EQ(framed_override(s, {FrameTarget::Kind::Group, "nope"}, std::nullopt, 1.0f)
                  .error()
                  .type,
              ProblemType::UnknownId);
    const auto empty = framed_override(s, {FrameTarget::Kind::Group, "empty"}, std::nullopt, 1.0f);
    EXPECT_EQ(empty.error().pointer, "/frame/group");
    EXPECT_EQ(empty.error().type, ProblemType::InvalidValue);
    const auto missing =
        framed_override(s, {FrameTarget::Kind::Instance, "nope"}, std::nullopt, 1.0f);
    EXPECT_EQ(missing.error().pointer, "/frame/instance");
    SetCamera eye;
    eye.eye = Vec3(1, 2, 3);
    EXPECT_EQ(framed_override(s, {FrameTarget::Kind::Group, "far"}, eye, 1.0f).error().pointer,
              "/camera");
    SetCamera bad;
    bad.fov_y_deg = 0.0f;
    EXPECT_EQ(framed_override(s, {FrameTarget::Kind::Group, "far"}, bad, 1.0f).error().pointer,
              "/camera/fov_y_deg");
}

}  // namespace
}  // namespace strata::protocol
