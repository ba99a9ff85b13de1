// Keyframe animation: instances placed by keyframes at the scene's time (set_time), a render's
// own time that leaves the scene alone, blur over the frame, and the least-work rule: stepping
// time costs the animated instances, nothing for the rest.

#include <gtest/gtest.h>

#include "engine/scene/animation.h"
#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;

/// Keys that slide, lift and turn a box, at uneven times.
std::vector<Keyframe> path() {
    return {{0.0f, Affine::trs({-2, 0, 0}, Affine::rotation_euler_deg({0, 0, 0}), Vec3(1.0f))},
            {1.0f, Affine::trs({0, 0.5f, 0}, Affine::rotation_euler_deg({0, 60, 10}), Vec3(1.2f))},
            {3.0f, Affine::trs({2, 0, -1}, Affine::rotation_euler_deg({0, 150, 0}), Vec3(0.8f))}};
}

SetTime clock_at(float time, float frame_duration = 1.0f / 24.0f) {
    return SetTime{time, frame_duration};
}

SetCamera shutter_at(float time) {
    SetCamera c{Vec3(0, 1, 9), Vec3(0, 0.3f, 0), Vec3(0, 1, 0), 40.0f};
    c.shutter_open = c.shutter_close = time;
    return c;
}

/// The scene of these tests: a lifted group holding the animated box, and a floor.
void add_scene(Engine& engine, std::vector<Keyframe> keys, MotionInterpolation how, bool loop) {
    AddGroup lift{"lift", std::nullopt, Affine::translation({0, 0.2f, 0}), true};
    AddInstance box = test::instance_edit("box", "box", {5, 5, 5});  // animation overrides it
    box.parent = "lift";
    box.animation = std::move(keys);
    box.motion_interpolation = how;
    box.animation_loop = loop;
    apply_ok(engine, test::mesh_edit("box", make_box(Vec3(1.0f, 0.6f, 0.4f))),
             test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), lift, box,
             test::instance_edit("floor", "floor", {0, -1, 0}), shutter_at(0.0f));
}

/// The same scene without animation, the box placed at `local` under the group.
test::HitFrame still_frame(TlasKind kind, const Affine& local, float shutter) {
    auto still = test::make_engine(kind);
    AddInstance placed = test::instance_edit("box", "box");
    placed.transform = Affine::translation({0, 0.2f, 0}) * local;
    apply_ok(*still, test::mesh_edit("box", make_box(Vec3(1.0f, 0.6f, 0.4f))),
             test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), placed,
             test::instance_edit("floor", "floor", {0, -1, 0}), shutter_at(shutter));
    return test::render(*still, 0xFFFFFFFFu);
}

void expect_near(const Affine& a, const Affine& b) {
    for (std::size_t i = 0; i < a.m.size(); ++i) EXPECT_NEAR(a.m[i], b.m[i], 1e-5f) << i;
}

class Animation : public ::testing::TestWithParam<TlasKind> {};

TEST_P(Animation, ShowsTheKeyframesInterpolatedAtTheSceneTime) {
    for (const MotionInterpolation how : {MotionInterpolation::Linear, MotionInterpolation::Srt}) {
        for (const bool loop : {false, true}) {
            auto engine = test::make_engine(GetParam());
            ASSERT_NE(engine, nullptr);
            add_scene(*engine, path(), how, loop);
            for (const float t : {-1.0f, 0.0f, 0.4f, 1.0f, 2.2f, 3.0f, 4.5f}) {
                SCOPED_TRACE(testing::Message() << "srt " << (how == MotionInterpolation::Srt)
                                                << " loop " << loop << " time " << t);
                apply_ok(*engine, clock_at(t));
                const Affine local = animation_at(path(), t, how, loop);
                EXPECT_EQ(test::compare(test::render(*engine, 0xFFFFFFFFu),
                                        still_frame(GetParam(), local, 0.0f)),
                          "");
            }
        }
    }
}

TEST_P(Animation, BlursOverTheFrameItSpans) {
    // A frame of 0.5 s from scene time 0.8 spans the key at 1: each ray time u of the frame sees
    // the box where the keys put it at 0.8 + 0.5 u (to the tolerance of the frame's samples).
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    add_scene(*engine, path(), MotionInterpolation::Linear, false);
    apply_ok(*engine, clock_at(0.8f, 0.5f));
    for (const float u : {0.0f, 0.125f, 0.375f, 0.5f, 1.0f}) {  // on the samples: exact
        SCOPED_TRACE(testing::Message() << "frame time " << u);
        apply_ok(*engine, shutter_at(u));
        const Affine local =
            animation_at(path(), 0.8f + 0.5f * u, MotionInterpolation::Linear, false);
        EXPECT_EQ(test::compare(test::render(*engine, 0xFFFFFFFFu),
                                still_frame(GetParam(), local, u)),
                  "");
    }
}

TEST_P(Animation, SteppingTimeCostsTheAnimatedInstancesOnly) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    add_scene(*engine, path(), MotionInterpolation::Srt, false);
    EditBatch statics;
    for (int i = 0; i < 200; ++i)
        statics.edits.emplace_back(
            test::instance_edit("s" + std::to_string(i), "box", {float(i % 20), 3, -float(i)}));
    ASSERT_TRUE(engine->apply(std::move(statics)).has_value());
    commit_ok(*engine);

    apply_ok(*engine, clock_at(0.5f));
    RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
    EXPECT_EQ(r.instances_changed, 1u);
    EXPECT_EQ(r.world_transforms, 1u);  // the animated box alone was evaluated
    // Past the last key the box holds still: a step there moves nothing.
    apply_ok(*engine, clock_at(10.0f));
    EXPECT_EQ(commit_ok(*engine).instances_changed, 1u);
    apply_ok(*engine, clock_at(11.0f));
    r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.world_transforms, 1u);  // evaluated, unmoved
    // Without animated instances, time costs nothing at all.
    UpdateInstance off{"box"};
    off.animation = std::vector<Keyframe>{};
    apply_ok(*engine, off);
    commit_ok(*engine);
    apply_ok(*engine, clock_at(0.5f));
    r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.world_transforms, 0u);
}

TEST_P(Animation, ARendersTimeLeavesTheSceneAlone) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    add_scene(*engine, path(), MotionInterpolation::Srt, true);
    apply_ok(*engine, clock_at(0.25f));
    commit_ok(*engine);
    const uint64_t version = engine->version();
    RenderRequest at_two;
    at_two.width = 48;
    at_two.height = 32;
    at_two.aovs = {Aov::Depth, Aov::InstanceId};
    at_two.format = ImageFormat::Exr;
    at_two.time = 2.0f;
    auto frame = engine->render_frame(at_two);
    ASSERT_TRUE(frame.has_value()) << frame.error().describe();
    EXPECT_EQ(frame->info.report.instances_changed, 1u);
    EXPECT_EQ(engine->version(), version);
    EXPECT_EQ(engine->read([](const Scene& s) { return s.timeline().time; }), 0.25f);
    // The same frame as a scene set to time 2.
    auto twin = test::make_engine(GetParam());
    add_scene(*twin, path(), MotionInterpolation::Srt, true);
    apply_ok(*twin, clock_at(2.0f));
    RenderRequest plain = at_two;
    plain.time.reset();
    auto expected = twin->render_frame(plain);
    ASSERT_TRUE(expected.has_value());
    EXPECT_EQ(frame->buffers.depth, expected->buffers.depth);
    EXPECT_EQ(frame->buffers.instance_id, expected->buffers.instance_id);
    // The next launch without a time shows the scene's again, and costs the box's update.
    auto back = engine->render_frame(plain);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(back->info.report.instances_changed, 1u);
    EXPECT_NE(back->buffers.depth, frame->buffers.depth);
}

TEST_P(Animation, GroupMotionKeysCarryEverythingBelow) {
    // A group's keys (three) and its children's (none, and two of their own) compose: at each
    // ray time the children sit where the group's keys times theirs put them. Exact where the
    // keys are (a product of two interpolations is not an interpolation of products between).
    const std::vector<Affine> group_keys = {Affine::translation({-1, 0, 0}),
                                            Affine::trs({0, 0.5f, 0},
                                                        Affine::rotation_euler_deg({0, 0, 20}),
                                                        Vec3(1.1f)),
                                            Affine::translation({1.5f, 0, 0})};
    const std::vector<Affine> own = {Affine::identity(), Affine::translation({0, 0, -1})};
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    AddGroup cart{"cart", std::nullopt, Affine::translation({0, 0.2f, 0}), true};
    cart.motion = group_keys;
    AddInstance rider = test::instance_edit("rider", "box", {0.8f, 0, 0});
    rider.parent = "cart";
    AddInstance wheel = test::instance_edit("wheel", "box", {-0.8f, -0.5f, 0});
    wheel.parent = "cart";
    wheel.motion = own;
    apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(0.6f))),
             test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), cart, rider, wheel,
             test::instance_edit("floor", "floor", {0, -1, 0}));
    for (const float u : {0.0f, 0.5f, 1.0f}) {
        SCOPED_TRACE(testing::Message() << "frame time " << u);
        apply_ok(*engine, shutter_at(u));
        const Affine g = Affine::translation({0, 0.2f, 0}) * motion_at(group_keys, u);
        auto still = test::make_engine(GetParam());
        AddInstance r = test::instance_edit("rider", "box");
        r.transform = g * Affine::translation({0.8f, 0, 0});
        AddInstance w = test::instance_edit("wheel", "box");
        w.transform = g * Affine::translation({-0.8f, -0.5f, 0}) * motion_at(own, u);
        apply_ok(*still, test::mesh_edit("box", make_box(Vec3(0.6f))),
                 test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), r, w,
                 test::instance_edit("floor", "floor", {0, -1, 0}), shutter_at(u));
        EXPECT_EQ(test::compare(test::render(*engine, 0xFFFFFFFFu),
                                test::render(*still, 0xFFFFFFFFu)),
                  "");
    }
    // Changing the group's keys is one TLAS update of the instances below.
    UpdateGroup stop{"cart"};
    stop.motion = std::vector<Affine>{};
    apply_ok(*engine, stop);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.instances_changed, 2u);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
}

TEST_P(Animation, AGroupsAnimationMovesItsSubtreeAndAStepCostsThatSubtree) {
    // An animated group with an animated instance below it: at each time the instance sits at
    // the group's keyframes times its own; a step touches the group's subtree and nothing else.
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    AddGroup lift{"lift", std::nullopt, {}, true};
    lift.animation = {{0.0f, Affine::translation({0, 0.2f, 0})},
                      {2.0f, Affine::trs({0.5f, 0.8f, -1}, Affine::rotation_euler_deg({0, 90, 0}),
                                         Vec3(1.0f))}};
    lift.motion_interpolation = MotionInterpolation::Srt;
    AddInstance box = test::instance_edit("box", "box");
    box.parent = "lift";
    box.animation = path();
    AddInstance passenger = test::instance_edit("passenger", "box", {0, 1.2f, 0});
    passenger.parent = "lift";
    EditBatch b;
    for (Edit e : std::vector<Edit>{test::mesh_edit("box", make_box(Vec3(1.0f, 0.6f, 0.4f))),
                                    test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), lift,
                                    box, passenger,
                                    test::instance_edit("floor", "floor", {0, -1, 0}),
                                    shutter_at(0.0f)})
        b.edits.push_back(std::move(e));
    for (int i = 0; i < 300; ++i)  // behind the camera: out of the compared frames
        b.edits.emplace_back(
            test::instance_edit("s" + std::to_string(i), "box", {float(i % 30), 6, 20.0f + i}));
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    commit_ok(*engine);
    for (const float t : {0.5f, 1.0f, 2.5f}) {
        SCOPED_TRACE(testing::Message() << "time " << t);
        apply_ok(*engine, clock_at(t));
        const RebuildReport r = commit_ok(*engine);
        EXPECT_EQ(r.tlas_action, TlasAction::Update);
        EXPECT_EQ(r.instances_changed, 2u);
        EXPECT_EQ(r.world_transforms, 3u);  // the group and its two instances
        const Affine g = animation_at(lift.animation, t, MotionInterpolation::Srt, false);
        auto still = test::make_engine(GetParam());
        AddInstance placed = test::instance_edit("box", "box");
        placed.transform = g * animation_at(path(), t, MotionInterpolation::Linear, false);
        AddInstance rider = test::instance_edit("passenger", "box");
        rider.transform = g * Affine::translation({0, 1.2f, 0});
        apply_ok(*still, test::mesh_edit("box", make_box(Vec3(1.0f, 0.6f, 0.4f))),
                 test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)), placed, rider,
                 test::instance_edit("floor", "floor", {0, -1, 0}), shutter_at(0.0f));
        EXPECT_EQ(test::compare(test::render(*engine, 0xFFFFFFFFu),
                                test::render(*still, 0xFFFFFFFFu)),
                  "");
    }
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, Animation,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         test::strategy_name);

TEST(Animation, LoopsWrapAndEndsHold) {
    const std::vector<Keyframe> keys = path();
    for (const MotionInterpolation how : {MotionInterpolation::Linear, MotionInterpolation::Srt}) {
        EXPECT_EQ(animation_at(keys, -5.0f, how, false), keys.front().transform);
        EXPECT_EQ(animation_at(keys, 7.0f, how, false), keys.back().transform);
        EXPECT_EQ(animation_at(keys, 1.0f, how, false), keys[1].transform);
        // The period is 3 s: 4.5 is 1.5 and -1 is 2.
        expect_near(animation_at(keys, 4.5f, how, true), animation_at(keys, 1.5f, how, false));
        expect_near(animation_at(keys, -1.0f, how, true), animation_at(keys, 2.0f, how, false));
    }
    // A linear blend halfway through a half turn is flat: the nearer key stands in.
    const std::vector<Keyframe> turn = {
        {0.0f, Affine::identity()}, {1.0f, Affine::rotation_euler_deg({0, 180, 0})}};
    EXPECT_EQ(animation_at(turn, 0.5f, MotionInterpolation::Linear, false), turn[1].transform);
    EXPECT_EQ(transform_problem(animation_at(turn, 0.5f, MotionInterpolation::Srt, false)),
              nullptr);
}

TEST(Animation, AFrameIsSampledWhereItBends) {
    const std::vector<Keyframe> keys = path();
    // Inside one segment two samples are exact; across a key the frame takes FRAME_SAMPLES.
    EXPECT_EQ(animated_pose(keys, {0.2f, 0.5f}, MotionInterpolation::Srt, false).keys.size(), 2u);
    EXPECT_EQ(animated_pose(keys, {0.8f, 0.5f}, MotionInterpolation::Srt, false).keys.size(),
              FRAME_SAMPLES);
    // Still frames carry no keys: after the end, or with no frame duration.
    EXPECT_TRUE(animated_pose(keys, {4.0f, 0.5f}, MotionInterpolation::Srt, false).keys.empty());
    EXPECT_TRUE(animated_pose(keys, {0.5f, 0.0f}, MotionInterpolation::Srt, false).keys.empty());
    // A loop's wrap inside the frame bends it too.
    EXPECT_EQ(animated_pose(keys, {2.9f, 0.5f}, MotionInterpolation::Srt, true).keys.size(),
              FRAME_SAMPLES);
}

TEST(Animation, BadKeyframesAndClocksAreRefusedAndChangeNothing) {
    auto engine = test::make_engine();
    apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(1.0f))),
             test::instance_edit("a", "box"));
    const uint64_t version = engine->version();
    auto refused = [&](Edit edit, const std::string& field) {
        test::expect_refused(*engine, std::move(edit), field);
    };
    UpdateInstance backwards{"a"};
    backwards.animation = std::vector<Keyframe>{{1.0f, {}}, {1.0f, {}}};
    refused(backwards, "animation/1/time");
    UpdateInstance nan{"a"};
    nan.animation = std::vector<Keyframe>{{std::nanf(""), {}}};
    refused(nan, "animation/0/time");
    UpdateInstance far{"a"};
    far.animation = std::vector<Keyframe>{{2e7f, {}}};
    refused(far, "animation/0/time");
    UpdateInstance flat{"a"};
    flat.animation = std::vector<Keyframe>{{0.0f, {}}, {1.0f, Affine::scaling({1, 0, 1})}};
    refused(flat, "animation/1/transform");
    UpdateInstance both{"a"};
    both.motion = std::vector<Affine>{Affine::identity(), Affine::translation({1, 0, 0})};
    both.animation = path();
    refused(both, "animation");
    AddGroup keyed{"g", std::nullopt, {}, true};
    keyed.motion = both.motion.value();
    keyed.animation = path();
    refused(keyed, "animation");
    AddGroup backwards_group{"g", std::nullopt, {}, true};
    backwards_group.animation = std::vector<Keyframe>{{1.0f, {}}, {0.5f, {}}};
    refused(backwards_group, "animation/1/time");
    refused(SetTime{std::nanf(""), std::nullopt}, "time");
    refused(SetTime{std::nullopt, -1.0f}, "frame_duration");
    EXPECT_EQ(engine->version(), version);
    RenderRequest bad;
    bad.time = std::numeric_limits<float>::infinity();
    auto r = engine->render_frame(bad);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().field, "time");
}

TEST(Animation, UndoTakesTheClockBack) {
    auto engine = test::make_engine();
    apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(1.0f))),
             test::instance_edit("a", "box"));
    apply_ok(*engine, clock_at(4.0f, 0.1f));
    auto undo = engine->undo_batch(engine->version());
    ASSERT_TRUE(undo.has_value()) << undo.error().describe();
    ASSERT_TRUE(engine->apply(std::move(undo.value()), engine->version()).has_value());
    EXPECT_EQ(engine->read([](const Scene& s) { return s.timeline(); }), Timeline{});
    // A scene at a non-default clock writes it into its snapshot batch; one at the default not.
    EXPECT_EQ(engine->read([](const Scene& s) { return s.to_batch(); }).edits.size(), 4u);
    apply_ok(*engine, clock_at(4.0f, 0.1f));
    const EditBatch b = engine->read([](const Scene& s) { return s.to_batch(); });
    ASSERT_EQ(b.edits.size(), 5u);
    EXPECT_EQ(std::get<SetTime>(b.edits.back()).time, 4.0f);
}

}  // namespace
}  // namespace strata
