// Motion blur: instance transform keys over frame time and the camera's shutter. Hits at a ray
// time must be those of a static scene whose instances sit where their keys say at that time;
// key edits are TLAS work only, under both strategies.

#include <cmath>

#include <gtest/gtest.h>

#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;

/// Keys that move and turn an instance over the frame.
std::vector<Affine> wobble(int keys) {
    std::vector<Affine> out;
    for (int k = 0; k < keys; ++k) {
        const float t = float(k) / float(keys - 1);
        out.push_back(Affine::trs({2.0f * t - 1.0f, 0.5f * t, 0.0f},
                                  Affine::rotation_euler_deg({0.0f, 0.0f, 40.0f * t}),
                                  Vec3(1.0f + 0.3f * t)));
    }
    return out;
}

SetCamera shutter_at(float time) {
    SetCamera c{Vec3(0, 1, 9), Vec3(0, 0.3f, 0), Vec3(0, 1, 0), 40.0f};
    c.shutter_open = c.shutter_close = time;
    return c;
}

class Motion : public ::testing::TestWithParam<TlasKind> {};

TEST_P(Motion, HitsAtARayTimeAreThoseOfTheKeysInterpolatedThere) {
    for (const int keys : {2, 5}) {
        const std::vector<Affine> motion = wobble(keys);
        auto moving = test::make_engine(GetParam());
        ASSERT_NE(moving, nullptr);
        AddGroup lift{"lift", std::nullopt, Affine::translation({0, 0.2f, 0}), true};
        AddInstance box = test::instance_edit("box", "box", {0.5f, 0, 0});
        box.parent = "lift";
        box.motion = motion;
        apply_ok(*moving, test::mesh_edit("box", make_box(Vec3(1.0f))),
                 test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), lift, box,
                 test::instance_edit("floor", "floor", {0, -1, 0}));
        for (const float t : {0.0f, 0.3f, 0.5f, 0.85f, 1.0f}) {
            SCOPED_TRACE(testing::Message() << keys << " keys at time " << t);
            apply_ok(*moving, shutter_at(t));
            const test::HitFrame blurred = test::render(*moving, 0xFFFFFFFFu);
            // The same scene without motion, the box placed where its keys say at t.
            auto still = test::make_engine(GetParam());
            AddInstance placed = test::instance_edit("box", "box");
            placed.transform = Affine::translation({0, 0.2f, 0}) *
                               Affine::translation({0.5f, 0, 0}) * motion_at(motion, t);
            apply_ok(*still, test::mesh_edit("box", make_box(Vec3(1.0f))),
                     test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), placed,
                     test::instance_edit("floor", "floor", {0, -1, 0}), shutter_at(t));
            EXPECT_EQ(test::compare(blurred, test::render(*still, 0xFFFFFFFFu)), "");
        }
    }
}

TEST_P(Motion, SrtKeysTurnRigidlyWhereLinearKeysShrink) {
    // Two keys a half turn apart less a little: SRT turns the box through its keys rigidly
    // (hits at each time are those of the box turned by the interpolated angle), linear ones
    // blend the matrices, so the box shrinks towards the middle of the frame.
    const std::vector<Affine> keys = {
        Affine::trs({-1, 0, 0}, Affine::rotation_euler_deg({0, 0, 0}), Vec3(1.0f)),
        Affine::trs({1, 0, 0}, Affine::rotation_euler_deg({0, 170, 20}), Vec3(1.2f))};
    auto moving = test::make_engine(GetParam());
    ASSERT_NE(moving, nullptr);
    AddInstance box = test::instance_edit("box", "box");
    box.motion = keys;
    box.motion_interpolation = MotionInterpolation::Srt;
    apply_ok(*moving, test::mesh_edit("box", make_box(Vec3(1.5f, 1.0f, 0.5f))), box);
    for (const float t : {0.0f, 0.25f, 0.5f, 0.8f, 1.0f}) {
        SCOPED_TRACE(testing::Message() << "time " << t);
        apply_ok(*moving, shutter_at(t));
        auto still = test::make_engine(GetParam());
        AddInstance placed = test::instance_edit("box", "box");
        placed.transform = motion_at(keys, t, MotionInterpolation::Srt);
        // Rigid but for the uniform scale, which goes linearly from 1 to 1.2.
        EXPECT_NEAR(placed.transform.determinant(), std::pow(1.0f + 0.2f * t, 3.0f), 1e-4f);
        apply_ok(*still, test::mesh_edit("box", make_box(Vec3(1.5f, 1.0f, 0.5f))), placed,
                 shutter_at(t));
        EXPECT_EQ(test::compare(test::render(*moving, 0xFFFFFFFFu),
                                test::render(*still, 0xFFFFFFFFu)),
                  "");
    }
    // Back to linear: one TLAS update, and the middle of the frame differs.
    apply_ok(*moving, shutter_at(0.5f));
    const test::HitFrame srt = test::render(*moving, 0xFFFFFFFFu);
    UpdateInstance linear;
    linear.instance = "box";
    linear.motion_interpolation = MotionInterpolation::Linear;
    apply_ok(*moving, linear);
    RebuildReport r;
    const test::HitFrame blended = test::render(*moving, 0xFFFFFFFFu, &r);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
    EXPECT_NE(test::compare(srt, blended), "");
}

TEST_P(Motion, KeyEditsAreTlasWorkOnly) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(1.0f))),
             test::instance_edit("a", "box"), test::instance_edit("b", "box", {3, 0, 0}));
    commit_ok(*engine);
    UpdateInstance keys;
    keys.instance = "a";
    keys.motion = wobble(3);
    apply_ok(*engine, keys);
    RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
    EXPECT_EQ(r.instances_changed, 1u);
    keys.motion = std::vector<Affine>{};  // motion removed
    apply_ok(*engine, keys);
    r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.instances_changed, 1u);
    apply_ok(*engine, shutter_at(0.5f));  // the shutter is the camera's: no BVH work
    EXPECT_TRUE(commit_ok(*engine).no_accel_work());
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, Motion,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         test::strategy_name);

TEST(Motion, BadKeysAndShuttersAreRefusedAndChangeNothing) {
    auto engine = test::make_engine();
    apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(1.0f))),
             test::instance_edit("a", "box"));
    const uint64_t version = engine->read([](const Scene& s) { return s.version(); });
    auto refused = [&](Edit edit, const std::string& field) {
        test::expect_refused(*engine, std::move(edit), field);
    };
    UpdateInstance one{"a"};
    one.motion = std::vector<Affine>{Affine::identity()};
    refused(one, "motion");
    UpdateInstance flat{"a"};
    flat.motion = std::vector<Affine>{Affine::identity(), Affine::scaling({1, 0, 1})};
    refused(flat, "motion/1");
    UpdateInstance many{"a"};
    many.motion = std::vector<Affine>(MAX_MOTION_KEYS + 1, Affine::identity());
    refused(many, "motion");
    SetCamera backwards;
    backwards.shutter_open = 0.8f;
    backwards.shutter_close = 0.2f;
    refused(backwards, "shutter_close");
    SetCamera late;
    late.shutter_close = 1.5f;
    refused(late, "shutter_close");
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), version);
}

}  // namespace
}  // namespace strata
