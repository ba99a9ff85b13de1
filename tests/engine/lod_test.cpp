// Level of detail (engine/scene/lod.h): the children of a group of kind `lod` are levels, each
// drawn for the rays whose LOD distance from the group lies in its [lod_near, lod_far). Hits
// must be those of a scene holding only the levels each ray should see; camera moves cost no
// BVH work, range edits are TLAS work only; both TLAS strategies.

#include <gtest/gtest.h>

#include <cmath>

#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;

AddGroup lod_group(const std::string& id, Vec3 at, std::optional<std::string> parent = {}) {
    AddGroup g{id, std::move(parent), Affine::translation(at), true};
    g.lod = true;
    return g;
}

AddInstance level(const std::string& id, const std::string& mesh, const std::string& group,
                  float near, float far) {
    AddInstance e = test::instance_edit(id, mesh);
    e.parent = group;
    e.lod_near = near;
    e.lod_far = far;
    return e;
}

/// The ids of the instances hit by rays from each of `origins` toward `target`, with LOD groups
/// measuring from `eye` (null: from each ray's origin): traced one by one and as one packet,
/// which must agree ("" for a miss).
std::vector<std::string> hits(Engine& engine, const std::vector<Vec3>& origins, Vec3 target,
                              const Vec3* eye = nullptr) {
    auto slots = engine.launch([&](const FrameState&, const TlasStrategy& tlas,
                                   const RebuildReport&) {
        std::vector<uint32_t> single, packet;
        alignas(64) RayHit16 p{};
        ValidMask16 valid{};
        for (std::size_t i = 0; i < origins.size(); ++i) {
            const Vec3 dir = target - origins[i];
            RayHit1 ray{};
            ray.org_x = origins[i].x, ray.org_y = origins[i].y, ray.org_z = origins[i].z;
            ray.dir_x = dir.x, ray.dir_y = dir.y, ray.dir_z = dir.z;
            ray.tfar = std::numeric_limits<float>::infinity();
            ray.mask = 0xFFFFFFFFu;
            ray.geom_id = ray.inst_id = ray.prim_id = INVALID_ID;
            tlas.intersect1(ray, false, nullptr, eye);
            single.push_back(ray.inst_id);
            p.org_x[i] = ray.org_x, p.org_y[i] = ray.org_y, p.org_z[i] = ray.org_z;
            p.dir_x[i] = ray.dir_x, p.dir_y[i] = ray.dir_y, p.dir_z[i] = ray.dir_z;
            p.tfar[i] = std::numeric_limits<float>::infinity();
            p.mask[i] = ray.mask;
            p.geom_id[i] = p.inst_id[i] = p.prim_id[i] = INVALID_ID;
            valid[i] = -1;
        }
        tlas.intersect16(valid, p, false, nullptr, eye);
        for (std::size_t i = 0; i < origins.size(); ++i) packet.push_back(p.inst_id[i]);
        EXPECT_EQ(single, packet) << "single rays and packets disagree";
        return single;
    });
    EXPECT_TRUE(slots.has_value());
    return engine.read([&](const Scene& s) {
        std::vector<std::string> out;
        for (uint32_t slot : slots.value())
            out.push_back(slot == INVALID_ID ? "" : s.instances().at_slot(slot).id);
        return out;
    });
}

/// Meshes "fine" (a sphere of `radius`, larger than the box, so a ray that wrongly sees it stops
/// earlier) and "coarse" (a unit box), and LOD group "tree" at the origin whose levels are
/// `<prefix>fine` up to `switch_at` and `<prefix>coarse` from there to `coarse_far`.
void add_tree(Engine& engine, float radius, const std::string& prefix, float switch_at,
              float coarse_far) {
    apply_ok(engine, test::mesh_edit("fine", make_sphere(radius, 16)),
             test::mesh_edit("coarse", make_box(Vec3(1.0f))), lod_group("tree", {0, 0, 0}),
             level(prefix + "fine", "fine", "tree", 0.0f, switch_at),
             level(prefix + "coarse", "coarse", "tree", switch_at, coarse_far));
}

class LevelOfDetail : public ::testing::TestWithParam<TlasKind> {};

TEST_P(LevelOfDetail, EachRayDrawsTheLevelItsDistanceSelects) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    add_tree(*engine, 1.5f, "tree.", 10.0f, 40.0f);
    const std::vector<Vec3> from = {{0, 0, 3}, {0, 0, 9.9f}, {0, 0, 10.1f}, {0, 0, 39},
                                    {0, 0, 41}, {3, 0, 0},   {0, -3, 0}};
    EXPECT_EQ(hits(*engine, from, Vec3(0.0f)),
              (std::vector<std::string>{"tree.fine", "tree.fine", "tree.coarse", "tree.coarse", "",
                                        "tree.fine", "tree.fine"}));
    // Rays of a launch measure from its camera, wherever they start: a shadow ray leaving the
    // coarse level sees the coarse level, not the fine one around its origin.
    const Vec3 far_eye(0, 0, 20), beyond(0, 0, 50), near_eye(0, 5, 0);
    EXPECT_EQ(hits(*engine, from, Vec3(0.0f), &far_eye),
              std::vector<std::string>(7, "tree.coarse"));
    EXPECT_EQ(hits(*engine, from, Vec3(0.0f), &beyond), std::vector<std::string>(7, ""));
    EXPECT_EQ(hits(*engine, from, Vec3(0.0f), &near_eye),
              std::vector<std::string>(7, "tree.fine"));
}

TEST_P(LevelOfDetail, NestedGroupsAndMovedGroupsKeepTheRule) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    // An outer LOD group draws the inner one up to 20; the inner one switches at 5. A plain
    // group between them passes its child's range through.
    AddGroup inner = lod_group("inner", {0, 0, 0}, "mid");
    AddGroup mid{"mid", "outer", Affine::identity(), true};
    mid.lod_far = 20.0f;
    apply_ok(*engine, test::mesh_edit("fine", make_sphere(1.5f, 16)),
             test::mesh_edit("coarse", make_box(Vec3(1.0f))), lod_group("outer", {0, 0, 0}),
             mid, inner, level("fine", "fine", "inner", 0.0f, 5.0f),
             level("coarse", "coarse", "inner", 5.0f, LOD_NO_LIMIT));
    const std::vector<Vec3> from = {{0, 0, 3}, {0, 0, 10}, {0, 0, 25}};
    EXPECT_EQ(hits(*engine, from, Vec3(0.0f)),
              (std::vector<std::string>{"fine", "coarse", ""}));

    // Moving the outer group moves the origin both distances are measured from.
    UpdateGroup move;
    move.group = "outer";
    move.transform = Affine::translation({0, 0, 8});
    apply_ok(*engine, move);
    const std::vector<Vec3> moved = {{0, 0, 11}, {0, 0, 18}, {0, 0, 33}};
    EXPECT_EQ(hits(*engine, moved, Vec3(0, 0, 8)),
              (std::vector<std::string>{"fine", "coarse", ""}));

    // A plain group draws everything; making it an LOD group again restores the rule.
    UpdateGroup plain;
    plain.group = "inner";
    plain.lod = false;
    apply_ok(*engine, plain);
    EXPECT_EQ(hits(*engine, moved, Vec3(0, 0, 8)),
              (std::vector<std::string>{"fine", "fine", ""}));
}

/// A field of LOD groups, each with a fine level, a coarse one and nothing beyond.
struct Field {
    static constexpr int SIDE = 24;  // 576 groups, 1152 instances: the incremental tiers work
    static constexpr float SPACING = 3.1f;
    float near_far = 14.0f, coarse_far = 45.0f;

    static Vec3 centre(int i) {
        return {float(i % SIDE) * SPACING, 0.0f, -float(i / SIDE) * SPACING};
    }
};

/// The field as `engine` should show it from `eye`, rebuilt without LOD groups: each group's
/// chosen level as a plain instance with the same id.
std::unique_ptr<Engine> chosen_levels(TlasKind kind, const Field& f, Vec3 offset, Vec3 eye,
                                      const SetCamera& camera) {
    auto reference = test::make_engine(kind);
    EditBatch b;
    b.edits.emplace_back(test::mesh_edit("fine", make_sphere(1.2f, 12)));
    b.edits.emplace_back(test::mesh_edit("coarse", make_box(Vec3(1.0f))));
    for (int i = 0; i < Field::SIDE * Field::SIDE; ++i) {
        const Vec3 c = Field::centre(i) + offset;
        const float d = glm::length(eye - c);
        EXPECT_GT(std::min(std::abs(d - f.near_far), std::abs(d - f.coarse_far)), 1e-3f)
            << "group " << i << " lies on a switch distance: move the eye";
        const std::string id = "g" + std::to_string(i);
        if (d < f.near_far) b.edits.emplace_back(test::instance_edit(id + ".fine", "fine", c));
        else if (d < f.coarse_far)
            b.edits.emplace_back(test::instance_edit(id + ".coarse", "coarse", c));
    }
    b.edits.emplace_back(camera);
    EXPECT_TRUE(reference->apply(std::move(b)).has_value());
    return reference;
}

TEST_P(LevelOfDetail, AFieldMatchesAFreshBuildOfTheChosenLevelsThroughEdits) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    Field f;
    EditBatch b;
    b.edits.emplace_back(test::mesh_edit("fine", make_sphere(1.2f, 12)));
    b.edits.emplace_back(test::mesh_edit("coarse", make_box(Vec3(1.0f))));
    b.edits.emplace_back(AddGroup{"field", std::nullopt, Affine::identity(), true});
    for (int i = 0; i < Field::SIDE * Field::SIDE; ++i) {
        const std::string id = "g" + std::to_string(i);
        b.edits.emplace_back(lod_group(id, Field::centre(i), "field"));
        b.edits.emplace_back(level(id + ".fine", "fine", id, 0.0f, f.near_far));
        b.edits.emplace_back(level(id + ".coarse", "coarse", id, f.near_far, f.coarse_far));
    }
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());

    auto check = [&](Vec3 offset, Vec3 eye, const char* step) {
        SCOPED_TRACE(step);
        const SetCamera camera{eye, eye + Vec3(1.0f, -0.35f, -1.0f), Vec3(0, 1, 0), 70.0f};
        apply_ok(*engine, camera);
        auto reference = chosen_levels(GetParam(), f, offset, eye, camera);
        EXPECT_EQ(test::compare(test::render(*engine, 0xFFFFFFFFu),
                                test::render(*reference, 0xFFFFFFFFu)),
                  "");
    };
    check(Vec3(0.0f), {-4.3f, 6.1f, 4.7f}, "first build");
    commit_ok(*engine);

    // Camera moves choose other levels and cost nothing.
    apply_ok(*engine, SetCamera{Vec3(20.3f, 5.2f, -30.9f), Vec3(0.0f), Vec3(0, 1, 0), 60.0f});
    EXPECT_TRUE(commit_ok(*engine).no_accel_work());
    check(Vec3(0.0f), {20.3f, 5.2f, -30.9f}, "camera moved");

    // Moving the whole field moves every group's origin.
    UpdateGroup move;
    move.group = "field";
    move.transform = Affine::translation({1.3f, 0.0f, -2.2f});
    apply_ok(*engine, move);
    check({1.3f, 0.0f, -2.2f}, {20.3f, 5.2f, -30.9f}, "field moved");

    // New switch distances on every level: TLAS work only.
    f.near_far = 9.0f;
    EditBatch ranges;
    for (int i = 0; i < Field::SIDE * Field::SIDE; ++i) {
        UpdateInstance fine;
        fine.instance = "g" + std::to_string(i) + ".fine";
        fine.lod_far = f.near_far;
        UpdateInstance coarse;
        coarse.instance = "g" + std::to_string(i) + ".coarse";
        coarse.lod_near = f.near_far;
        ranges.edits.emplace_back(fine);
        ranges.edits.emplace_back(coarse);
    }
    ASSERT_TRUE(engine->apply(std::move(ranges)).has_value());
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_TRUE(r.rebuilt.empty() && r.refit.empty());
    check({1.3f, 0.0f, -2.2f}, {20.3f, 5.2f, -30.9f}, "ranges changed");
}

TEST_P(LevelOfDetail, PicksNameTheLevelTheFrameShows) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    add_tree(*engine, 1.0f, "", 10.0f, LOD_NO_LIMIT);
    for (const auto& [eye, expected] :
         {std::pair{Vec3(0, 0, 5), "fine"}, std::pair{Vec3(0, 0, 15), "coarse"}}) {
        apply_ok(*engine, SetCamera{eye, Vec3(0.0f), Vec3(0, 1, 0), 30.0f});
        PickRequest request{64, 48, {{32, 24}}, std::nullopt};
        auto picked = engine->pick(request);
        ASSERT_TRUE(picked.has_value());
        ASSERT_TRUE(picked.value().hits[0].has_value());
        EXPECT_EQ(picked.value().hits[0]->instance, expected);
        const test::HitFrame frame = test::render(*engine, 0xFFFFFFFFu);
        EXPECT_EQ(frame.instance_ids[24 * 64 + 32], expected);
    }
}

TEST_P(LevelOfDetail, RangeAndKindEditsAreTlasWorkOnly) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    add_tree(*engine, 1.0f, "", 10.0f, LOD_NO_LIMIT);
    apply_ok(*engine, test::instance_edit("other", "coarse", {5, 0, 0}));
    commit_ok(*engine);
    UpdateInstance far;
    far.instance = "fine";
    far.lod_far = 12.0f;
    apply_ok(*engine, far);
    RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
    EXPECT_EQ(r.instances_changed, 1u);
    UpdateGroup plain;
    plain.group = "tree";
    plain.lod = false;
    apply_ok(*engine, plain);
    r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.instances_changed, 2u);  // the levels, not "other"
    // A range off an LOD group changes nothing that is drawn, but is still listed.
    UpdateInstance loose;
    loose.instance = "other";
    loose.lod_near = 3.0f;
    apply_ok(*engine, loose);
    EXPECT_EQ(commit_ok(*engine).instances_changed, 1u);
}

TEST_P(LevelOfDetail, LevelMeshEditsAndRemovalsReachTheWrappers) {
    auto engine = test::make_engine(GetParam());
    ASSERT_NE(engine, nullptr);
    apply_ok(*engine, test::mesh_edit("fine", make_box(Vec3(2.0f))),
             test::mesh_edit("coarse", make_box(Vec3(1.0f))), lod_group("tree", {0, 0, 0}),
             level("fine", "fine", "tree", 0.0f, 10.0f),
             level("coarse", "coarse", "tree", 10.0f, LOD_NO_LIMIT));
    commit_ok(*engine);
    // Grow the fine box (a refit): its wrapper's box must grow with it.
    MeshData big = make_box(Vec3(6.0f));
    UpdateMeshPositions grow;
    grow.mesh = "fine";
    grow.positions = big.positions;
    apply_ok(*engine, grow);
    auto distance = [&](Vec3 eye) {
        apply_ok(*engine, SetCamera{eye, Vec3(0.0f), Vec3(0, 1, 0), 30.0f});
        auto picked = engine->pick(PickRequest{64, 48, {{32, 24}}, std::nullopt});
        EXPECT_TRUE(picked.has_value() && picked.value().hits[0].has_value());
        return picked.value().hits[0] ? picked.value().hits[0]->distance : -1.0f;
    };
    EXPECT_NEAR(distance({0, 0, 8}), 5.0f, 1e-3f);
    // A new mesh in its place (a rebuild into a new BLAS), then levels and meshes removed.
    UpdateMeshPositions rebuild;
    rebuild.mesh = "fine";
    rebuild.positions = make_box(Vec3(4.0f)).positions;
    apply_ok(*engine, rebuild, MarkDirty{"fine", DirtyAction::Rebuild});
    EXPECT_NEAR(distance({0, 0, 8}), 6.0f, 1e-3f);
    EXPECT_NEAR(distance({0, 0, 12}), 11.5f, 1e-3f);
    apply_ok(*engine, RemoveInstance{"fine"}, RemoveMesh{"fine"});
    EXPECT_FALSE(engine->pick(PickRequest{64, 48, {{32, 24}}, SetCamera{
                                              Vec3(0, 0, 8), Vec3(0.0f), Vec3(0, 1, 0), 30.0f}})
                     .value()
                     .hits[0]
                     .has_value());
    EXPECT_NEAR(distance({0, 0, 12}), 11.5f, 1e-3f);
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, LevelOfDetail,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         test::strategy_name);

TEST(LevelOfDetail, BadRangesAreRefusedAndChangeNothing) {
    auto engine = test::make_engine();
    apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(1.0f))), lod_group("tree", {0, 0, 0}),
             level("a", "box", "tree", 0.0f, 10.0f));
    const uint64_t version = engine->read([](const Scene& s) { return s.version(); });
    auto refused = [&](Edit edit, const std::string& field) {
        test::expect_refused(*engine, std::move(edit), field);
    };
    UpdateInstance inverted;
    inverted.instance = "a";
    inverted.lod_near = 10.0f;
    refused(inverted, "lod_far");
    UpdateInstance negative;
    negative.instance = "a";
    negative.lod_near = -1.0f;
    refused(negative, "lod_near");
    UpdateInstance nan;
    nan.instance = "a";
    nan.lod_far = std::nanf("");
    refused(nan, "lod_far");
    AddInstance empty = level("b", "box", "tree", 5.0f, 5.0f);
    refused(empty, "lod_far");
    AddGroup group = lod_group("g", {0, 0, 0});
    group.lod_near = 3.0f;
    group.lod_far = 1.0f;
    refused(group, "lod_far");
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), version);
}

}  // namespace
}  // namespace strata
