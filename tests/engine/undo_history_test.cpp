// The undo history: inverse batches (inverse_batch.h) and the undo and redo stacks
// (edit_history.h). An inverse applied to the scene its batch left must give back the scene
// before the batch, object for object and field for field; the stacks must follow the rules
// written in edit_history.h; and the batch info must survive the journal's codec.

#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "engine/engine.h"
#include "engine/scene/edit_history.h"
#include "engine/scene/shapes.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::state_of;

/// Applies `batch` to `scene` with its inverse, then the inverse, and checks the state came back.
void expect_inverse_restores(Scene& scene, EditBatch batch, const std::string& what) {
    const std::vector<std::string> before = state_of(scene);
    EditBatch inverse;
    auto applied = scene.apply(std::move(batch), nullptr, &inverse);
    ASSERT_TRUE(applied.has_value()) << what << ": " << applied.error().describe();
    auto undone = scene.apply(std::move(inverse));
    ASSERT_TRUE(undone.has_value())
        << what << ": the inverse was refused: " << undone.error().describe();
    EXPECT_TRUE(state_of(scene) == before) << what;
}

EditBatch batch_of(std::vector<Edit> edits) {
    return EditBatch{std::move(edits)};
}

AddInstance instance(std::string id, std::string mesh, std::optional<std::string> material,
                     const Affine& transform) {
    AddInstance e;
    e.id = std::move(id);
    e.mesh = std::move(mesh);
    e.material = std::move(material);
    e.transform = transform;
    return e;
}

/// A scene with one of everything: a textured material, a mesh with normals and uvs, groups,
/// instances in and out of them, lights, a moved camera.
void fill(Scene& s) {
    MeshData sphere = make_sphere(1.0f, 8);
    AddMesh mesh = test::mesh_edit("ball", sphere);
    mesh.normals = sphere.positions;
    mesh.uvs.assign(sphere.positions.size(), Vec2(0.5f, 0.25f));
    mesh.name = "Ball";
    AddMaterial red{"red", Material{Vec3(0.9f, 0.1f, 0.1f), 0.3f, 0.0f, Vec3(0.0f)}};
    red.material.name = "Red";
    AddGroup car{"car", std::nullopt, Affine::translation({1, 0, 0}), true, "Car"};
    AddGroup wheels{"wheels", std::string("car"), Affine::identity(), true};
    AddInstance a = instance("a", "ball", std::string("red"), Affine::translation({0, 1, 0}));
    AddInstance b{"b", "ball", std::nullopt, Affine::identity(), false, 3, 7, std::string("wheels"),
                  "B"};
    SetCamera cam{Vec3(1, 2, 9), Vec3(0), std::nullopt, 50.0f};
    ASSERT_TRUE(s.apply(batch_of({test::mesh_edit("box", make_box(Vec3(1))), std::move(mesh), red,
                                  car, wheels, a, b, AddLight{"lamp", Light{}}, cam}))
                    .has_value());
}

TEST(InverseBatch, TakesBackEveryKindOfEdit) {
    std::vector<std::pair<std::string, EditBatch>> cases;
    const auto add = [&](std::string what, std::vector<Edit> edits) {
        cases.emplace_back(std::move(what), batch_of(std::move(edits)));
    };
    MeshData sphere = make_sphere(1.0f, 8);
    add("add mesh, material, group, instance",
        {test::mesh_edit("new", make_box(Vec3(2))),
         AddMaterial{"blue", Material{Vec3(0, 0, 1), 0.5f, 0.0f, Vec3(0.0f)}},
         AddGroup{"g", std::string("car"), Affine::identity(), true},
         AddInstance{"c", "new", std::string("blue"), Affine::identity(), true, 1, 2,
                     std::string("g")}});
    add("remove instance and mesh", {RemoveInstance{"a"}, RemoveInstance{"b"}, RemoveMesh{"ball"}});
    add("remove a subtree", {RemoveGroup{"car", true}});
    add("remove material after its users", {RemoveInstance{"a"}, RemoveMaterial{"red"}});
    add("update instance fields, material and parent",
        {UpdateInstance{"a", std::optional<std::string>(), Affine::translation({3, 3, 3}), false,
                        5u, 9u, std::optional<std::string>("wheels"), std::string("renamed")}});
    add("set transform twice", {SetTransform{"a", Affine::translation({1, 2, 3})},
                                SetTransform{"a", Affine::translation({4, 5, 6})}});
    add("move a group", {UpdateGroup{"wheels", std::optional<std::string>(),
                                     Affine::translation({0, 2, 0}), false, std::string("W")}});
    add("update some positions", {UpdateMeshPositions{"ball", 3, {Vec3(9), Vec3(8)}}});
    add("update every position",
        {UpdateMeshPositions{"ball", 0, std::vector<Vec3>(sphere.positions.size(), Vec3(1))}});
    add("update listed vertices, one twice",
        {UpdateMeshVertices{"ball", {4, 2, 4}, {Vec3(1), Vec3(2), Vec3(3)}}});
    add("replace normals and uvs at an offset",
        {UpdateMeshPositions{
            "ball", 1, {}, std::vector<Vec3>{Vec3(0, 1, 0)}, std::vector<Vec2>{Vec2(0.1f, 0.2f)}}});
    add("change topology and vertex count, dropping normals and uvs",
        {ReplaceMeshTopology{"ball",
                             std::vector<Vec3>{Vec3(0), Vec3(1, 0, 0), Vec3(0, 1, 0)},
                             {Triangle(0, 1, 2)},
                             std::vector<Vec3>{},
                             std::vector<Vec2>{}}});
    add("change triangles only", {ReplaceMeshTopology{"box", std::nullopt, {Triangle(0, 1, 2)}}});
    add("update material and light",
        {UpdateMaterial{"red", Vec3(0.2f), 0.9f, 0.5f, Vec3(1.0f)},
         UpdateLight{"lamp", LightKind::Spot, Vec3(1), std::nullopt, Vec3(0.5f), 3.0f, 40.0f,
                     std::nullopt, std::nullopt, std::nullopt}});
    add("remove and re-add with the same id",
        {RemoveInstance{"a"}, instance("a", "box", std::nullopt, Affine::identity())});
    add("add then remove in one batch",
        {instance("tmp", "box", std::nullopt, Affine::identity()), RemoveInstance{"tmp"},
         AddMaterial{"m2", Material{}}, RemoveMaterial{"m2"}});
    add("camera and lighting", {SetCamera{Vec3(5), std::nullopt, std::nullopt, 30.0f},
                                SetLighting{std::nullopt, Vec3(2), std::nullopt, 0.1f}});
    add("light removed", {RemoveLight{"lamp"}});
    add("mark dirty only", {MarkDirty{std::string("ball"), DirtyAction::Rebuild}});
    add("clear everything", {Clear{}});

    for (auto& [what, batch] : cases) {
        Scene scene;
        fill(scene);
        expect_inverse_restores(scene, std::move(batch), what);
    }
}

TEST(InverseBatch, TakesBackRandomBatches) {
    for (uint64_t seed = 1; seed <= 6; ++seed) {
        test::RandomEdits gen(seed);
        Scene scene;
        ASSERT_TRUE(scene.apply(gen.initial_batch(4, 40)).has_value());
        for (int step = 0; step < 60; ++step) {
            EditBatch batch = gen.next_batch(12);
            // Apply it for real (the generator's model follows), checking its inverse on a copy
            // of the state first.
            Scene copy;
            ASSERT_TRUE(copy.apply(scene.to_batch()).has_value());
            EditBatch copy_batch = batch;
            expect_inverse_restores(
                copy, std::move(copy_batch),
                "seed " + std::to_string(seed) + " step " + std::to_string(step));
            ASSERT_TRUE(scene.apply(std::move(batch)).has_value());
        }
    }
}

TEST(RemoveMaterial, RefusedWhileUsed) {
    Scene s;
    fill(s);
    auto used = s.apply(batch_of({RemoveMaterial{"red"}}));
    ASSERT_FALSE(used.has_value());
    EXPECT_EQ(used.error().code, ErrorCode::InUse);
    EXPECT_NE(used.error().message.find("instance 'a'"), std::string::npos) << used.error().message;
    auto unknown = s.apply(batch_of({RemoveMaterial{"nope"}}));
    ASSERT_FALSE(unknown.has_value());
    EXPECT_EQ(unknown.error().code, ErrorCode::UnknownId);
    ASSERT_TRUE(s.apply(batch_of({RemoveInstance{"a"}, RemoveMaterial{"red"}})).has_value());
    EXPECT_TRUE(s.find_material("red").is_null());
}

std::unique_ptr<Engine> engine_with(HistoryLimits limits = {}) {
    EngineConfig config;
    config.history = limits;
    auto engine = test::create_engine(config);
    EXPECT_TRUE(engine.has_value());
    return std::move(engine.value());
}

Result<ApplyResult> undo(Engine& e, bool redo = false) {
    auto batch = redo ? e.redo_batch(e.version()) : e.undo_batch(e.version());
    if (!batch) return Unexpected(batch.error());
    return e.apply(std::move(batch.value()), e.version());
}

TEST(EditHistory, UndoAndRedoWalkTheVersions) {
    auto engine = engine_with();
    std::vector<std::vector<std::string>> states{state_of(*engine)};
    for (int i = 0; i < 4; ++i) {
        EditBatch b = batch_of({test::mesh_edit("m" + std::to_string(i), make_box(Vec3(1)))});
        b.info.message = "step " + std::to_string(i);
        ASSERT_TRUE(engine->apply(std::move(b)).has_value());
        states.push_back(state_of(*engine));
    }
    // Undo twice, redo once, undo once: each lands on the state it names.
    ASSERT_TRUE(undo(*engine).has_value());
    EXPECT_EQ(state_of(*engine), states[3]);
    ASSERT_TRUE(undo(*engine).has_value());
    EXPECT_EQ(state_of(*engine), states[2]);
    ASSERT_TRUE(undo(*engine, true).has_value());
    EXPECT_EQ(state_of(*engine), states[3]);
    ASSERT_TRUE(undo(*engine).has_value());
    EXPECT_EQ(state_of(*engine), states[2]);
    EXPECT_EQ(engine->version(), 8u);

    HistoryPage page = engine->history(100, 0);
    ASSERT_EQ(page.entries.size(), 8u);
    EXPECT_EQ(page.entries[0].info.kind, BatchKind::Undo);
    EXPECT_EQ(page.entries[0].info.target, 7u);  // the redo's version
    EXPECT_EQ(page.entries[1].info.kind, BatchKind::Redo);
    EXPECT_EQ(page.entries[1].info.target, 3u);
    EXPECT_EQ(page.entries[7].info.message, "step 0");
    EXPECT_GT(page.entries[7].info.time_ms, 0);
    EXPECT_EQ(page.undo_depth, 2u);
    EXPECT_EQ(page.next_undo, 2u);
    EXPECT_EQ(page.redo_depth, 2u);
    EXPECT_EQ(page.next_redo, 7u);  // the undo took back v7 (the redo of v3): redo names v7

    // A new edit empties the redo stack.
    ASSERT_TRUE(engine->apply(batch_of({test::mesh_edit("x", make_box(Vec3(1)))})).has_value());
    auto redo = undo(*engine, true);
    ASSERT_FALSE(redo.has_value());
    EXPECT_EQ(redo.error().code, ErrorCode::NothingToUndo);
    // Undo all the way back to the empty scene, then nothing is left.
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(undo(*engine).has_value()) << i;
    EXPECT_EQ(state_of(*engine), states[0]);
    auto none = undo(*engine);
    ASSERT_FALSE(none.has_value());
    EXPECT_EQ(none.error().code, ErrorCode::NothingToUndo);
}

TEST(EditHistory, AnUndoCostsWhatItsInverseChanges) {
    auto engine = engine_with();
    ASSERT_TRUE(
        engine
            ->apply(batch_of({test::mesh_edit("ball", make_sphere(1.0f, 16)),
                              instance("a", "ball", std::nullopt, Affine::identity()),
                              instance("b", "ball", std::nullopt, Affine::translation({3, 0, 0}))}))
            .has_value());
    ASSERT_TRUE(engine->commit().has_value());
    const auto undo_and_commit = [&] {
        EXPECT_TRUE(undo(*engine).has_value());
        auto report = engine->commit();
        EXPECT_TRUE(report.has_value());
        return report.value();
    };

    // A move taken back: a TLAS update of one instance, no BLAS work.
    ASSERT_TRUE(
        engine->apply(batch_of({SetTransform{"a", Affine::translation({0, 2, 0})}})).has_value());
    ASSERT_TRUE(engine->commit().has_value());
    RebuildReport moved_back = undo_and_commit();
    EXPECT_EQ(moved_back.tlas_action, TlasAction::Update) << moved_back.summary();
    EXPECT_EQ(moved_back.instances_changed, 1u);
    EXPECT_TRUE(moved_back.rebuilt.empty() && moved_back.refit.empty()) << moved_back.summary();

    // A few vertices taken back: a refit of that mesh, no rebuild.
    ASSERT_TRUE(
        engine->apply(batch_of({UpdateMeshVertices{"ball", {5, 6}, {Vec3(0.1f), Vec3(0.2f)}}}))
            .has_value());
    ASSERT_TRUE(engine->commit().has_value());
    RebuildReport dented_back = undo_and_commit();
    EXPECT_TRUE(dented_back.rebuilt.empty()) << dented_back.summary();
    ASSERT_EQ(dented_back.refit.size(), 1u) << dented_back.summary();
    EXPECT_EQ(dented_back.refit[0].mesh, "ball");
}

TEST(EditHistory, StaleVersionIsRefused) {
    auto engine = engine_with();
    ASSERT_TRUE(engine->apply(batch_of({test::mesh_edit("m", make_box(Vec3(1)))})).has_value());
    auto stale = engine->undo_batch(0);
    ASSERT_FALSE(stale.has_value());
    EXPECT_EQ(stale.error().code, ErrorCode::VersionMismatch);
}

TEST(EditHistory, DepthAndBytesAreBounded) {
    auto engine = engine_with(HistoryLimits{10, 3, 1 << 20});
    for (int i = 0; i < 6; ++i)
        ASSERT_TRUE(
            engine->apply(batch_of({test::mesh_edit("m" + std::to_string(i), make_box(Vec3(1)))}))
                .has_value());
    HistoryPage page = engine->history(100, 0);
    EXPECT_EQ(page.undo_depth, 3u);
    // An inverse over the byte budget empties the stack: nothing before it can be undone.
    std::vector<Vec3> big(100000, Vec3(1));
    ASSERT_TRUE(engine->apply(batch_of({Clear{}})).has_value());  // inverse: six small meshes
    AddMesh big_mesh;
    big_mesh.id = "big";
    big_mesh.positions = big;
    big_mesh.triangles = {Triangle(0, 1, 2)};
    ASSERT_TRUE(engine->apply(batch_of({std::move(big_mesh)})).has_value());
    ASSERT_TRUE(engine->apply(batch_of({RemoveMesh{"big"}})).has_value());  // inverse: 1.2 MB
    page = engine->history(100, 0);
    EXPECT_EQ(page.undo_depth, 0u);
    EXPECT_EQ(page.held_bytes, 0u);
    EXPECT_FALSE(undo(*engine).has_value());
}

TEST(EditHistory, PagesNewestFirst) {
    auto engine = engine_with(HistoryLimits{5, 100, 1 << 20});
    for (int i = 0; i < 8; ++i)
        ASSERT_TRUE(engine
                        ->apply(batch_of(
                            {SetCamera{std::nullopt, std::nullopt, std::nullopt, float(30 + i)}}))
                        .has_value());
    HistoryPage first = engine->history(2, 0);
    ASSERT_EQ(first.entries.size(), 2u);
    EXPECT_EQ(first.entries[0].version, 8u);
    EXPECT_EQ(first.entries[1].version, 7u);
    EXPECT_EQ(first.oldest, 4u);  // five entries kept
    HistoryPage next = engine->history(10, 7);
    ASSERT_EQ(next.entries.size(), 3u);
    EXPECT_EQ(next.entries[0].version, 6u);
    EXPECT_EQ(next.entries[2].version, 4u);
    ASSERT_EQ(next.entries[0].ops.size(), 1u);
    EXPECT_STREQ(durable::edit_kind_name(next.entries[0].ops[0].first), "set_camera");
}

TEST(EditHistory, BatchInfoSurvivesTheCodec) {
    EditBatch b = batch_of({RemoveMaterial{"m"}});
    b.info = BatchInfo{BatchKind::Redo, 41, 1795000000123, "tidy up \xc3\xa9"};
    std::string bytes;
    durable::encode_batch(b, bytes);
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(durable::edit_count(bytes), 1u);  // the count, without the info bit
    EXPECT_EQ(back.value().info.kind, BatchKind::Redo);
    EXPECT_EQ(back.value().info.target, 41u);
    EXPECT_EQ(back.value().info.time_ms, 1795000000123);
    EXPECT_EQ(back.value().info.message, "tidy up \xc3\xa9");
    ASSERT_EQ(back.value().edits.size(), 1u);
    EXPECT_EQ(std::get<RemoveMaterial>(back.value().edits[0]).material, "m");
    // A batch without info is written exactly as before: a plain count.
    std::string plain;
    durable::encode_batch(batch_of({RemoveMaterial{"m"}}), plain);
    EXPECT_EQ(uint8_t(plain[3]) & 0x80, 0);
    // An info bit with an empty info is not a form any writer produces.
    std::string empty_info = plain;
    empty_info[3] = char(uint8_t(empty_info[3]) | 0x80);
    empty_info.insert(4, std::string(1 + 8 + 8 + 4, '\0'));
    EXPECT_FALSE(durable::decode_batch(empty_info).has_value());
}

TEST(EditHistory, MessageIsCheckedText) {
    auto engine = engine_with();
    EditBatch b = batch_of({});
    b.info.message = "bad \x01 control";
    auto r = engine->apply(std::move(b));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().field, "message");
    EditBatch long_one = batch_of({});
    long_one.info.message.assign(MAX_BATCH_MESSAGE_BYTES + 1, 'x');
    EXPECT_FALSE(engine->apply(std::move(long_one)).has_value());
    EXPECT_EQ(engine->version(), 0u);
}

}  // namespace
}  // namespace strata
