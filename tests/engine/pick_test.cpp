// Picking: one ray per asked pixel through the committed scene, named with client ids, in
// agreement with the id and depth AOVs of a render of the same size.

#include <cmath>

#include <gtest/gtest.h>

#include "engine/engine.h"
#include "tests/engine/render_test_util.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::instance_edit;
using test::mesh_edit;
using test::project;
using test::render_frame_ok;

class Picking : public ::testing::Test {
protected:
    void SetUp() override {
        engine = test::make_engine();
        cam.eye = Vec3(0.0f, 0.0f, 12.0f);
        cam.target = Vec3(0.0f);
        AddInstance middle = instance_edit("middle", "ball", MIDDLE);
        middle.user_id = 77;
        apply_ok(*engine, mesh_edit("cube", make_box(Vec3(1.5f))),
                 mesh_edit("ball", make_sphere(0.8f, 48)), instance_edit("left", "cube", LEFT),
                 std::move(middle), instance_edit("right", "cube", RIGHT), test::camera_edit(cam));
    }

    PickRequest at(std::initializer_list<Vec3> points) const {
        PickRequest r;
        r.width = W;
        r.height = H;
        for (const Vec3& p : points) {
            const glm::vec2 px = project(cam, W, H, p);
            r.pixels.push_back({uint32_t(px.x), uint32_t(px.y)});
        }
        return r;
    }

    PickResult pick_ok(const PickRequest& r) {
        auto picked = engine->pick(r);
        EXPECT_TRUE(picked.has_value()) << (picked ? "" : picked.error().describe());
        return picked ? picked.value() : PickResult{};
    }

    static constexpr uint32_t W = 160, H = 90;
    static constexpr Vec3 LEFT{-4.0f, 0.0f, 0.0f}, MIDDLE{0.0f, 0.0f, 0.0f},
        RIGHT{4.0f, 0.0f, 0.0f};
    std::unique_ptr<Engine> engine;
    Camera cam;
};

TEST_F(Picking, AgreesWithTheIdAndDepthAovsOfARenderOfTheSameSize) {
    const Frame f = render_frame_ok(
        *engine, test::request(W, H, 1, {Aov::InstanceId, Aov::PrimitiveId, Aov::Depth}));
    PickRequest r;
    r.width = W;
    r.height = H;
    // Every other pixel of every row: both sides of every silhouette edge.
    for (uint32_t y = 0; y < H; ++y)
        for (uint32_t x = y % 2; x < W; x += 2) r.pixels.push_back({x, y});
    const PickResult picked = pick_ok(r);
    ASSERT_EQ(picked.hits.size(), r.pixels.size());
    EXPECT_EQ(picked.version, f.info.version);
    std::size_t hits = 0;
    for (std::size_t i = 0; i < r.pixels.size(); ++i) {
        const std::size_t p = std::size_t(r.pixels[i].y) * W + r.pixels[i].x;
        const uint32_t slot = f.buffers.instance_id[p];
        const auto& hit = picked.hits[i];
        ASSERT_EQ(hit.has_value(), slot != MISS_ID) << "pixel " << p;
        if (!hit) continue;
        ++hits;
        const std::string id =
            engine->read([&](const Scene& s) { return s.instances().at_slot(slot).id; });
        EXPECT_EQ(hit->instance, id) << "pixel " << p;
        EXPECT_EQ(hit->mesh, id == "middle" ? "ball" : "cube");
        EXPECT_EQ(hit->primitive, f.buffers.primitive_id[p]) << "pixel " << p;
        EXPECT_FLOAT_EQ(hit->distance, f.buffers.depth[p]) << "pixel " << p;
    }
    EXPECT_GT(hits, 200u);
    EXPECT_LT(hits, r.pixels.size() / 2);
}

TEST_F(Picking, ReportsWhereAndWhatWasHitWithClientIds) {
    const PickResult picked = pick_ok(at({LEFT, MIDDLE, Vec3(2.0f, 0.0f, 0.0f)}));
    ASSERT_EQ(picked.hits.size(), 3u);
    ASSERT_TRUE(picked.hits[0].has_value());
    const PickHit& left = *picked.hits[0];
    EXPECT_EQ(left.instance, "left");
    EXPECT_EQ(left.mesh, "cube");
    EXPECT_EQ(left.user_id, 0u);
    // The cube's front face, seen head-on: its normal faces the camera, the point lies on it.
    EXPECT_NEAR(left.normal.z, 1.0f, 1e-3f);
    EXPECT_NEAR(glm::length(left.normal), 1.0f, 1e-5f);
    EXPECT_NEAR(left.position.x, LEFT.x, 0.4f);  // within a pixel
    EXPECT_NEAR(glm::length(left.position - cam.eye), left.distance, 1e-3f);
    ASSERT_TRUE(picked.hits[1].has_value());
    EXPECT_EQ(picked.hits[1]->instance, "middle");
    EXPECT_EQ(picked.hits[1]->user_id, 77u);
    EXPECT_NEAR(picked.hits[1]->distance, 12.0f - 0.8f, 0.01f);
    EXPECT_FALSE(picked.hits[2].has_value()) << "the gap between two instances";
}

TEST_F(Picking, CommitsPendingEditsFirstLikeARender) {
    const uint64_t before = pick_ok(at({MIDDLE})).version;
    const Vec3 moved(0.0f, 2.0f, 0.0f);
    const uint64_t v = apply_ok(*engine, SetTransform{"middle", Affine::translation(moved)},
                                UpdateInstance{"left", std::nullopt, std::nullopt, false});
    EXPECT_EQ(v, before + 1);
    const PickResult picked = pick_ok(at({MIDDLE, moved, LEFT}));
    EXPECT_EQ(picked.version, v);
    EXPECT_FALSE(picked.hits[0].has_value());
    ASSERT_TRUE(picked.hits[1].has_value());
    EXPECT_EQ(picked.hits[1]->instance, "middle");
    EXPECT_FALSE(picked.hits[2].has_value()) << "a hidden instance is not picked";
    EXPECT_EQ(engine->counters().picks, 2u);
}

TEST_F(Picking, TheCameraOverrideAimsThePickRays) {
    PickRequest r = at({MIDDLE});
    SetCamera look_away;
    look_away.target = Vec3(0.0f, 0.0f, 24.0f);
    r.camera = look_away;
    EXPECT_FALSE(pick_ok(r).hits[0].has_value());
    look_away.target = LEFT;
    r.camera = look_away;
    r.pixels = {{W / 2, H / 2}};
    const PickResult picked = pick_ok(r);
    ASSERT_TRUE(picked.hits[0].has_value());
    EXPECT_EQ(picked.hits[0]->instance, "left");
}

TEST_F(Picking, RequestsOutsideTheImageOrTooLargeAreRefusedNamingWhy) {
    PickRequest r = at({MIDDLE});
    r.pixels.push_back({W, 0});
    auto refused = engine->pick(r);
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().field, "pixels/1");
    EXPECT_NE(refused.error().message.find("outside the 160x90 image"), std::string::npos);

    r.pixels.assign(MAX_PICK_PIXELS + 1, PickPixel{});
    refused = engine->pick(r);
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().code, ErrorCode::TooLarge);

    r.pixels.clear();
    EXPECT_FALSE(engine->pick(r).has_value());
    r = at({MIDDLE});
    r.height = 0;
    EXPECT_FALSE(engine->pick(r).has_value());
    SetCamera broken;
    broken.eye = Vec3(-3e38f);
    broken.target = Vec3(3e38f);
    r = at({MIDDLE});
    r.camera = broken;
    refused = engine->pick(r);
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().field.rfind("camera/", 0), 0u) << refused.error().field;
    EXPECT_EQ(engine->counters().picks, 0u);
}

}  // namespace
}  // namespace strata
