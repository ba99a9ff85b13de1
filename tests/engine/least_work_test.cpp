// One test per row of the least-work table in the README: each pins the exact BLAS and TLAS work
// a kind of edit causes at the next commit.

#include <gtest/gtest.h>

#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using test::ids;
using test::instance_edit;
using test::mesh_edit;
using ::testing::ElementsAre;

/// Two meshes ("ball" with 3 instances, "crate" with 1) and a mesh nothing instances ("spare"),
/// committed once so later commits start clean.
class LeastWork : public ::testing::Test {
protected:
    void SetUp() override {
        engine = test::make_engine();
        apply_ok(*engine, mesh_edit("ball", make_sphere(1.0f, 16)), mesh_edit("crate", make_box(Vec3(1.0f))),
                 mesh_edit("spare", make_plane(Vec3(2.0f), 4, 4)), AddMaterial{"red", {}},
                 instance_edit("b0", "ball", {-3, 0, 0}), instance_edit("b1", "ball", {0, 0, 0}),
                 instance_edit("b2", "ball", {3, 0, 0}), instance_edit("c0", "crate", {0, 3, 0}));
        const RebuildReport first = commit_ok(*engine);
        ASSERT_EQ(first.blas_rebuilds, 3u);
        ASSERT_EQ(first.tlas_action, TlasAction::Update);
    }

    std::unique_ptr<Engine> engine;
};

TEST_F(LeastWork, NothingChangedDoesNothing) {
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::None);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_EQ(r.primitives_built + r.primitives_refit, 0u);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.tlas_instances, 4u);
}

TEST_F(LeastWork, CameraLightingAndMaterialEditsRebuildNothing) {
    SetCamera cam;
    cam.eye = Vec3(1, 2, 9);
    SetLighting light;
    light.sky_intensity = 0.2f;
    UpdateMaterial mat;
    mat.material = "red";
    mat.base_color = Vec3(1, 0, 0);
    UpdateInstance shading_only;
    shading_only.instance = "b0";
    shading_only.material = std::optional<std::string>("red");
    apply_ok(*engine, cam, light, mat, shading_only);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::None);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_TRUE(r.no_accel_work());
}

TEST_F(LeastWork, NormalsAndUvsEditsRebuildNothing) {
    const std::size_t n = make_sphere(1.0f, 16).positions.size();
    UpdateMeshPositions whole;
    whole.mesh = "ball";
    whole.normals = std::vector<Vec3>(n, Vec3(0, 1, 0));
    whole.uvs = std::vector<Vec2>(n, Vec2(0.5f));
    apply_ok(*engine, whole);
    RebuildReport r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.tlas_action, TlasAction::None);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);

    UpdateMeshPositions part;
    part.mesh = "ball";
    part.offset = 3;
    part.normals = std::vector<Vec3>{Vec3(1, 0, 0), Vec3(0, 0, 1)};
    UpdateMeshPositions removed;
    removed.mesh = "ball";
    removed.uvs = std::vector<Vec2>{};
    apply_ok(*engine, part, removed);
    r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
    EXPECT_EQ(r.tlas_action, TlasAction::None);
}

TEST_F(LeastWork, PositionsWithNormalsRefitLikePositionsAlone) {
    UpdateMeshPositions move;
    move.mesh = "ball";
    move.offset = 2;
    move.positions = {Vec3(0.1f, 0.99f, 0.0f)};
    const std::size_t n = make_sphere(1.0f, 16).positions.size();
    move.normals = std::vector<Vec3>(n - 2, Vec3(0, 1, 0));
    // A mesh without normals takes them only whole: refused, and nothing changes.
    EditBatch refused;
    refused.edits.emplace_back(move);
    EXPECT_FALSE(engine->apply(std::move(refused)).has_value());
    EXPECT_TRUE(commit_ok(*engine).no_accel_work());

    move.offset = 0;
    move.positions = make_sphere(1.0f, 16).positions;
    move.normals = std::vector<Vec3>(n, Vec3(0, 1, 0));
    apply_ok(*engine, move);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_THAT(ids(r.refit), ElementsAre("ball"));
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
}

TEST_F(LeastWork, InstanceChangesAreOneTlasUpdateHoweverMany) {
    UpdateInstance hide;
    hide.instance = "b1";
    hide.visible = false;
    UpdateInstance mask;
    mask.instance = "b2";
    mask.mask = 0x2;
    apply_ok(*engine, SetTransform{"b0", Affine::translation({-4, 0, 0})}, hide, mask,
             instance_edit("b3", "ball", {6, 0, 0}), RemoveInstance{"c0"});
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_EQ(r.primitives_built + r.primitives_refit, 0u);
    EXPECT_EQ(r.tlas_instances, 4u);
}

TEST_F(LeastWork, MovedPositionsRefitOnlyThatMeshAndUpdateTheTlas) {
    const uint64_t tris = make_sphere(1.0f, 16).triangles.size();
    UpdateMeshPositions move;
    move.mesh = "ball";
    move.offset = 2;
    move.positions = {Vec3(0.1f, 0.99f, 0.0f), Vec3(0.0f, 0.98f, 0.1f)};
    apply_ok(*engine, move);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.blas_refits, 1u);
    EXPECT_THAT(ids(r.refit), ElementsAre("ball"));
    EXPECT_EQ(r.refit[0].reason, BuildReason::PositionsChanged);
    EXPECT_EQ(r.primitives_refit, tris);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
}

TEST_F(LeastWork, MovedPositionsOfAnUninstancedMeshLeaveTheTlasAlone) {
    MeshData plane = make_plane(Vec3(2.0f), 4, 4);
    for (Vec3& p : plane.positions) p.y += 0.01f;
    UpdateMeshPositions move;
    move.mesh = "spare";
    move.positions = plane.positions;
    apply_ok(*engine, move);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_THAT(ids(r.refit), ElementsAre("spare"));
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.tlas_action, TlasAction::None);
}

TEST_F(LeastWork, TopologyChangeRebuildsOnlyThatMesh) {
    MeshData finer = make_sphere(1.0f, 24);
    ReplaceMeshTopology topo;
    topo.mesh = "ball";
    topo.positions = finer.positions;
    topo.triangles = finer.triangles;
    apply_ok(*engine, topo);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_THAT(ids(r.rebuilt), ElementsAre("ball"));
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::TopologyChanged);
    EXPECT_EQ(r.blas_rebuilds, 1u);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_EQ(r.primitives_built, finer.triangles.size());
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
}

TEST_F(LeastWork, AddedMeshIsBuiltAloneAndTouchesTheTlasOnlyWhenInstanced) {
    apply_ok(*engine, mesh_edit("lonely", make_box(Vec3(2.0f))));
    RebuildReport r = commit_ok(*engine);
    EXPECT_THAT(ids(r.rebuilt), ElementsAre("lonely"));
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Added);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_EQ(r.tlas_action, TlasAction::None);

    apply_ok(*engine, mesh_edit("used", make_box(Vec3(2.0f))), instance_edit("u0", "used", {0, -3, 0}));
    r = commit_ok(*engine);
    EXPECT_THAT(ids(r.rebuilt), ElementsAre("used"));
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
}

TEST_F(LeastWork, MarkDirtyOnAMeshDoesWhatWasAskedToThatMeshOnly) {
    apply_ok(*engine, MarkDirty{std::string("crate"), DirtyAction::Refit});
    RebuildReport r = commit_ok(*engine);
    EXPECT_THAT(ids(r.refit), ElementsAre("crate"));
    EXPECT_EQ(r.refit[0].reason, BuildReason::RefitRequested);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);

    apply_ok(*engine, MarkDirty{std::string("crate"), DirtyAction::Rebuild});
    r = commit_ok(*engine);
    EXPECT_THAT(ids(r.rebuilt), ElementsAre("crate"));
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::RebuildRequested);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);

    apply_ok(*engine, MarkDirty{std::string("spare"), DirtyAction::Rebuild});
    r = commit_ok(*engine);
    EXPECT_THAT(ids(r.rebuilt), ElementsAre("spare"));
    EXPECT_EQ(r.tlas_action, TlasAction::None);
}

TEST_F(LeastWork, MarkDirtyOnTheTlasRebuildsTheTlasOnly) {
    apply_ok(*engine, MarkDirty{std::nullopt, DirtyAction::Rebuild});
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Rebuild);
    EXPECT_EQ(r.tlas_instances, 4u);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(r.blas_refits, 0u);
}

TEST_F(LeastWork, PlanPredictsTheCommitExactly) {
    UpdateMeshPositions move;
    move.mesh = "ball";
    move.positions = {Vec3(0.0f, 1.01f, 0.0f)};
    apply_ok(*engine, move, SetTransform{"c0", Affine::translation({1, 3, 0})},
             mesh_edit("new", make_box(Vec3(1.0f))));
    const RebuildReport plan = engine->plan();
    const RebuildReport done = commit_ok(*engine);
    EXPECT_TRUE(plan.planned);
    EXPECT_FALSE(done.planned);
    EXPECT_EQ(plan.tlas_action, done.tlas_action);
    EXPECT_EQ(ids(plan.rebuilt), ids(done.rebuilt));
    EXPECT_EQ(ids(plan.refit), ids(done.refit));
    EXPECT_EQ(plan.primitives_built, done.primitives_built);
    EXPECT_EQ(plan.primitives_refit, done.primitives_refit);
    // Planning changes nothing: after the commit the plan is empty again.
    EXPECT_TRUE(engine->plan().no_accel_work());
}

TEST_F(LeastWork, AddingAndRemovingWithinOneCommitWindowCostsNothing) {
    apply_ok(*engine, mesh_edit("ghost", make_box(Vec3(1.0f))), instance_edit("g0", "ghost"));
    apply_ok(*engine, RemoveInstance{"g0"}, RemoveMesh{"ghost"});
    const RebuildReport r = commit_ok(*engine);
    EXPECT_TRUE(r.no_accel_work());
}

TEST_F(LeastWork, RemovingTheLastInstanceAndTheMeshReleasesItsBlas) {
    apply_ok(*engine, RemoveInstance{"c0"}, RemoveMesh{"crate"});
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_THAT(r.released, ElementsAre("crate"));
    EXPECT_EQ(r.tlas_instances, 3u);
}

TEST_F(LeastWork, CountersAccumulateAcrossCommits) {
    const EngineCounters before = engine->counters();
    apply_ok(*engine, MarkDirty{std::string("ball"), DirtyAction::Rebuild});
    commit_ok(*engine);
    commit_ok(*engine);
    const EngineCounters after = engine->counters();
    EXPECT_EQ(after.commits - before.commits, 2u);
    EXPECT_EQ(after.noop_commits - before.noop_commits, 1u);
    EXPECT_EQ(after.blas_rebuilds - before.blas_rebuilds, 1u);
    EXPECT_EQ(after.tlas_updates - before.tlas_updates, 1u);
}

TEST_F(LeastWork, MemoryIsReportedAndShrinksWhenMeshesGo) {
    const RebuildReport before = commit_ok(*engine);
    EXPECT_GT(before.memory_blas_bytes, 0);
    EXPECT_GT(before.memory_tlas_bytes, 0);
    apply_ok(*engine, RemoveInstance{"b0"}, RemoveInstance{"b1"}, RemoveInstance{"b2"},
             RemoveMesh{"ball"});
    const RebuildReport after = commit_ok(*engine);
    EXPECT_LT(after.memory_blas_bytes, before.memory_blas_bytes);
}

// Groups: "car" holds b0 and "wheels", which holds b1; b2 and c0 stay at the root. Each test
// runs with both TLAS strategies.
class LeastWorkGroups : public ::testing::TestWithParam<TlasKind> {
protected:
    void SetUp() override {
        engine = test::make_engine(GetParam());
        ASSERT_NE(engine, nullptr);
        AddGroup car{"car", std::nullopt, Affine::translation({0, 0, -2}), true};
        AddGroup wheels{"wheels", std::string("car"), Affine::translation({0, -1, 0}), true};
        AddInstance b0 = instance_edit("b0", "ball", {-3, 0, 0});
        b0.parent = "car";
        AddInstance b1 = instance_edit("b1", "ball", {0, 0, 0});
        b1.parent = "wheels";
        apply_ok(*engine, mesh_edit("ball", make_sphere(1.0f, 16)),
                 mesh_edit("crate", make_box(Vec3(1.0f))), car, wheels, b0, b1,
                 instance_edit("b2", "ball", {3, 0, 0}), instance_edit("c0", "crate", {0, 3, 0}));
        const RebuildReport first = commit_ok(*engine);
        ASSERT_EQ(first.blas_rebuilds, 2u);
        ASSERT_EQ(first.tlas_instances, 4u);
    }

    void expect_tlas_update_only(const RebuildReport& r, uint64_t instances) {
        EXPECT_EQ(r.tlas_action, TlasAction::Update);
        EXPECT_EQ(r.blas_rebuilds, 0u);
        EXPECT_EQ(r.blas_refits, 0u);
        EXPECT_EQ(r.primitives_built + r.primitives_refit, 0u);
        EXPECT_EQ(r.instances_changed, instances);
    }

    std::unique_ptr<Engine> engine;
};

TEST_P(LeastWorkGroups, MovingAGroupIsOneTlasUpdateOverTheInstancesBelowIt) {
    apply_ok(*engine, UpdateGroup{"car", std::nullopt, Affine::translation({1, 0, -2}), std::nullopt});
    const RebuildReport r = commit_ok(*engine);
    expect_tlas_update_only(r, 2);     // b0, b1
    EXPECT_EQ(r.world_transforms, 4u);  // car, wheels, b0, b1
    const Vec3 b1 = engine->read([](const Scene& s) {
        return s.instance(s.find_instance("b1")).value()->world.transform_point(Vec3(0.0f));
    });
    EXPECT_EQ(b1, Vec3(1, -1, -2));
}

TEST_P(LeastWorkGroups, SetTransformOnAGroupIsTheSameAsUpdateGroup) {
    apply_ok(*engine, UpdateGroup{"wheels", std::nullopt, Affine::translation({0, 1, 0}), std::nullopt});
    expect_tlas_update_only(commit_ok(*engine), 1);  // b1
}

TEST_P(LeastWorkGroups, ReparentingAGroupUpdatesOnlyTheInstancesBelowIt) {
    apply_ok(*engine, UpdateGroup{"wheels", std::optional<std::string>(), std::nullopt, std::nullopt});
    const RebuildReport r = commit_ok(*engine);
    expect_tlas_update_only(r, 1);     // b1
    EXPECT_EQ(r.world_transforms, 2u);  // wheels, b1
}

TEST_P(LeastWorkGroups, ReparentingWhereTheWorldTransformStaysCostsNoTlasWork) {
    // An identity group at the root: b2's world transform does not change.
    apply_ok(*engine, AddGroup{"empty", std::nullopt, Affine::identity(), true});
    commit_ok(*engine);
    UpdateInstance move;
    move.instance = "b2";
    move.parent = std::optional<std::string>("empty");
    apply_ok(*engine, move);
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::None);
    EXPECT_TRUE(r.no_accel_work());
}

TEST_P(LeastWorkGroups, HidingAndShowingAGroupIsOneTlasUpdateOverItsSubtree) {
    apply_ok(*engine, UpdateGroup{"car", std::nullopt, std::nullopt, false});
    RebuildReport r = commit_ok(*engine);
    expect_tlas_update_only(r, 2);
    PrimarySettings settings;
    settings.width = 32;
    settings.height = 24;
    auto frame = engine->render_primary(settings);
    ASSERT_TRUE(frame.has_value());
    const auto hidden = engine->read([](const Scene& s) {
        return std::pair(s.find_instance("b0").index, s.find_instance("b1").index);
    });
    for (uint32_t id : frame->buffers.instance_id) {
        EXPECT_NE(id, hidden.first);
        EXPECT_NE(id, hidden.second);
    }
    apply_ok(*engine, UpdateGroup{"car", std::nullopt, std::nullopt, true});
    expect_tlas_update_only(commit_ok(*engine), 2);
    // Shown again: the same view does see them (so the check above could have failed).
    auto shown = engine->render_primary(settings);
    ASSERT_TRUE(shown.has_value());
    int seen = 0;
    for (uint32_t id : shown->buffers.instance_id) seen += id == hidden.first || id == hidden.second;
    EXPECT_GT(seen, 0);
}

TEST_P(LeastWorkGroups, AddingAGroupWithoutInstancesDoesNothing) {
    apply_ok(*engine, AddGroup{"new", std::string("car"), Affine::translation({5, 5, 5}), true});
    EXPECT_TRUE(commit_ok(*engine).no_accel_work());
}

TEST_P(LeastWorkGroups, TheCounterSumsWorldTransforms) {
    const EngineCounters before = engine->counters();
    apply_ok(*engine, UpdateGroup{"car", std::nullopt, Affine::translation({2, 0, 0}), std::nullopt});
    commit_ok(*engine);
    EXPECT_EQ(engine->counters().world_transforms - before.world_transforms, 4u);
}

TEST_P(LeastWorkGroups, ACompactedMeshIsItsOwnBuildTwiceAndRefitsInPlace) {
    BuildOptions compact;
    compact.compact = true;
    AddInstance gem = instance_edit("g0", "gem", {0, 1, 0});
    gem.parent = "car";
    apply_ok(*engine, mesh_edit("gem", make_sphere(0.5f, 24), compact), gem);
    RebuildReport r = commit_ok(*engine);
    ASSERT_EQ(ids(r.rebuilt), std::vector<std::string>{"gem"});
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Added);
    EXPECT_EQ(r.primitives_built, sphere_triangle_count(24));  // two passes, one mesh's triangles
    EXPECT_GT(r.rebuilt[0].uncompacted_bytes, r.rebuilt[0].bytes);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.instances_changed, 1u);

    MeshData moved = make_sphere(0.6f, 24);
    apply_ok(*engine, UpdateMeshPositions{"gem", 0, moved.positions});
    r = commit_ok(*engine);
    EXPECT_EQ(r.blas_rebuilds, 0u);
    ASSERT_EQ(ids(r.refit), std::vector<std::string>{"gem"});
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.instances_changed, 1u);

    apply_ok(*engine, UpdateGroup{"car", std::nullopt, Affine::translation({1, 0, -2}), std::nullopt});
    expect_tlas_update_only(commit_ok(*engine), 3);
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, LeastWorkGroups,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         test::strategy_name);

/// Points ("dots", two instances) and curves ("hair", one) beside a triangle mesh ("crate"):
/// the README's rows for points and curves, under both TLAS strategies.
class LeastWorkPointsAndCurves : public ::testing::TestWithParam<TlasKind> {
protected:
    void SetUp() override {
        engine = test::make_engine(GetParam());
        ASSERT_NE(engine, nullptr);
        AddMesh dots;
        dots.id = "dots";
        dots.kind = MeshKind::Points;
        dots.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
        dots.radii = {0.2f, 0.2f, 0.2f};
        AddMesh hair;
        hair.id = "hair";
        hair.kind = MeshKind::Curves;
        hair.basis = CurveBasis::Bezier;
        hair.positions = {{0, 0, 0}, {0, 1, 0}, {0, 2, 0}, {0, 3, 0}};
        hair.radii.assign(4, 0.05f);
        hair.strands = {4};
        apply_ok(*engine, dots, hair, mesh_edit("crate", make_box(Vec3(1.0f))),
                 instance_edit("d0", "dots"), instance_edit("d1", "dots", {0, 2, 0}),
                 instance_edit("h0", "hair", {3, 0, 0}), instance_edit("c0", "crate", {0, 3, 0}));
        ASSERT_EQ(commit_ok(*engine).blas_rebuilds, 3u);
    }

    /// `r` rebuilt exactly `mesh` for `reason`, with `primitives`, and updated the TLAS.
    static void expect_rebuilt_alone(const RebuildReport& r, const std::string& mesh,
                                     BuildReason reason, uint64_t primitives) {
        EXPECT_THAT(ids(r.rebuilt), ElementsAre(mesh));
        EXPECT_TRUE(r.refit.empty());
        if (!r.rebuilt.empty()) EXPECT_EQ(r.rebuilt[0].reason, reason);
        EXPECT_EQ(r.primitives_built, primitives);
        EXPECT_EQ(r.tlas_action, TlasAction::Update);
    }

    std::unique_ptr<Engine> engine;
};

TEST_P(LeastWorkPointsAndCurves, MovedPointsRebuildOnlyThatMesh) {
    apply_ok(*engine, UpdateMeshPositions{"dots", 1, {{1, 1, 0}}});
    expect_rebuilt_alone(commit_ok(*engine), "dots", BuildReason::PositionsChanged, 3);
}

TEST_P(LeastWorkPointsAndCurves, NewRadiiRebuildOnlyThatMesh) {
    UpdateMeshPositions thicker{"hair", 2, {}};
    thicker.radii = std::vector<float>{0.1f, 0.1f};
    apply_ok(*engine, thicker);
    expect_rebuilt_alone(commit_ok(*engine), "hair", BuildReason::PositionsChanged, 1);
}

TEST_P(LeastWorkPointsAndCurves, ANewPointCountOrNewStrandsRebuildOnlyThatMesh) {
    ReplaceMeshTopology four{"dots", std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}},
                             {}};
    four.radii = std::vector<float>(4, 0.3f);
    apply_ok(*engine, four);
    expect_rebuilt_alone(commit_ok(*engine), "dots", BuildReason::TopologyChanged, 4);

    ReplaceMeshTopology longer{"hair", std::vector<Vec3>(7, Vec3(0.5f)), {}};
    longer.radii = std::vector<float>(7, 0.05f);
    longer.strands = std::vector<uint32_t>{7};
    apply_ok(*engine, longer);
    expect_rebuilt_alone(commit_ok(*engine), "hair", BuildReason::TopologyChanged, 2);
}

TEST_P(LeastWorkPointsAndCurves, MovingAnInstanceOfPointsIsATlasUpdateOnly) {
    apply_ok(*engine, SetTransform{"d1", Affine::translation({0, 4, 0})});
    const RebuildReport r = commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(r.blas_rebuilds + r.blas_refits, 0u);
    EXPECT_EQ(r.instances_changed, 1u);
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, LeastWorkPointsAndCurves,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         test::strategy_name);

}  // namespace
}  // namespace strata
