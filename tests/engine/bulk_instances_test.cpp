// Bulk instance edits (edits.h: AddInstances, UpdateInstances, RemoveInstances): the same scene
// and the same hits as the single edits they stand for, the same rules item by item with errors
// that name the item, atomic refusal, compact inverses and a journal layout that reads back.

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/durable/edit_codec.h"
#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "tests/engine/bulk_singles.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::state_of;

EditBatch batch_of(std::vector<Edit> edits) {
    return EditBatch{std::move(edits)};
}

/// Two meshes, two materials and a group, in `engine`.
void base_scene(Engine& engine) {
    AddGroup park{"park", std::nullopt, Affine::translation({0, 0, -2}), true};
    test::apply_ok(engine, test::mesh_edit("ball", make_sphere(0.4f, 12)),
                   test::mesh_edit("box", make_box(Vec3(0.3f))),
                   AddMaterial{"red", Material{Vec3(0.9f, 0.1f, 0.1f), 0.5f, 0.0f, Vec3(0.0f)}},
                   AddMaterial{"blue", Material{Vec3(0.1f, 0.1f, 0.9f), 0.5f, 0.0f, Vec3(0.0f)}},
                   park, SetCamera{Vec3(0, 0, 12), Vec3(0), std::nullopt, 60.0f});
}

/// `count` instances of `mesh` numbered `prefix`0, `prefix`1, ... at the origin.
AddInstances numbered(const std::string& prefix, uint64_t count, const std::string& mesh) {
    AddInstances add;
    add.ids.prefix = prefix;
    add.ids.count = count;
    add.meshes = {mesh};
    return add;
}

Affine random_place(std::mt19937& rng) {
    std::uniform_real_distribution<float> at(-4.0f, 4.0f);
    std::uniform_real_distribution<float> turn(0.0f, 180.0f);
    return Affine::translation({at(rng), at(rng), at(rng)}) *
           Affine::rotation_euler_deg({turn(rng), turn(rng), 0.0f});
}

/// Applies `bulk` to one engine and its single edits to the other, commits both, and checks
/// the scenes and their hits agree.
template <class Bulk>
void apply_both(Engine& bulk_engine, Engine& single_engine, const Bulk& bulk,
                const std::string& what) {
    auto a = bulk_engine.apply(batch_of({bulk}));
    ASSERT_TRUE(a.has_value()) << what << ": " << a.error().describe();
    auto b = single_engine.apply(batch_of(test::singles(bulk)));
    ASSERT_TRUE(b.has_value()) << what << ": " << b.error().describe();
    test::commit_ok(bulk_engine);
    test::commit_ok(single_engine);
    EXPECT_TRUE(state_of(bulk_engine) == state_of(single_engine)) << what;
    EXPECT_TRUE(test::hits(bulk_engine) == test::hits(single_engine)) << what;
}

TEST(BulkInstances, SameSceneAndHitsAsSingleEdits) {
    auto bulk_engine = test::make_engine();
    auto single_engine = test::make_engine();
    base_scene(*bulk_engine);
    base_scene(*single_engine);
    std::mt19937 rng(7);

    AddInstances trees;  // a numbered range, one mesh and material for all
    trees.ids.prefix = "tree-";
    trees.ids.first = 10;
    trees.ids.count = 300;
    trees.meshes = {"ball"};
    trees.materials = {"red"};
    for (int i = 0; i < 300; ++i) trees.transforms.push_back(random_place(rng));
    apply_both(*bulk_engine, *single_engine, trees, "add a range");

    AddInstances rocks;  // listed ids, a mesh and a material per item, under a group
    for (int i = 0; i < 50; ++i) {
        rocks.ids.list.push_back("rock/" + std::to_string(i));
        rocks.meshes.push_back(i % 2 ? "ball" : "box");
        rocks.materials.push_back(i % 3 ? "blue" : "red");
        rocks.transforms.push_back(random_place(rng));
    }
    rocks.parent = "park";
    apply_both(*bulk_engine, *single_engine, rocks, "add a list under a group");

    AddInstances hidden;  // identity transforms, hidden, the mesh's default material
    hidden.ids.prefix = "h";
    hidden.ids.count = 5;
    hidden.meshes = {"box"};
    hidden.visible = false;
    apply_both(*bulk_engine, *single_engine, hidden, "add hidden");

    UpdateInstances move;  // every third tree moves
    for (int i = 10; i < 310; i += 3) {
        move.ids.list.push_back("tree-" + std::to_string(i));
        move.transforms.push_back(random_place(rng));
    }
    apply_both(*bulk_engine, *single_engine, move, "move a list");

    UpdateInstances hide;  // a range hides
    hide.ids.prefix = "tree-";
    hide.ids.first = 100;
    hide.ids.count = 80;
    hide.visible = false;
    apply_both(*bulk_engine, *single_engine, hide, "hide a range");

    UpdateInstances show_and_move;  // both at once, hidden ones shown again
    show_and_move.ids.prefix = "h";
    show_and_move.ids.count = 5;
    show_and_move.visible = true;
    for (int i = 0; i < 5; ++i) show_and_move.transforms.push_back(random_place(rng));
    apply_both(*bulk_engine, *single_engine, show_and_move, "show and move");

    RemoveInstances cut;
    cut.ids.prefix = "tree-";
    cut.ids.first = 200;
    cut.ids.count = 110;
    apply_both(*bulk_engine, *single_engine, cut, "remove a range");
    RemoveInstances cut_list;
    for (int i = 0; i < 50; i += 2) cut_list.ids.list.push_back("rock/" + std::to_string(i));
    apply_both(*bulk_engine, *single_engine, cut_list, "remove a list");
}

/// Random bulk adds, moves, hides, shows and removals over a pool of numbered ids, some of which
/// name missing instances or repeat: each batch must be accepted or refused as its single edits
/// are, and leave the same scene and the same hits.
TEST(BulkInstances, RandomBulkBatchesMatchTheirSingleEdits) {
    auto bulk_engine = test::make_engine();
    auto single_engine = test::make_engine();
    base_scene(*bulk_engine);
    base_scene(*single_engine);
    std::mt19937 rng(2026);
    const auto pick = [&](int n) { return int(rng() % uint32_t(n)); };
    uint64_t next = 0;  // adds mostly take fresh numbers; one in six reuses some
    const auto some_ids = [&](BulkIds& ids, bool fresh) {
        const uint64_t count = uint64_t(1 + pick(40));
        if (fresh && pick(6)) {
            ids.prefix = "p";
            ids.first = next;
            ids.count = count;
            next += count;
        } else if (pick(2)) {
            ids.prefix = "p";
            ids.first = uint64_t(pick(int(next) + 1));
            ids.count = count / 4 + 1;
        } else {
            for (int k = 1 + pick(8); k > 0; --k)
                ids.list.push_back("p" + std::to_string(pick(int(next) + 5)));
        }
    };
    int accepted = 0;
    for (int round = 0; round < 60; ++round) {
        std::vector<Edit> edits;
        for (int k = 1 + pick(2); k > 0; --k) {
            switch (pick(4)) {
                case 0: {
                    AddInstances e;
                    some_ids(e.ids, true);
                    const std::size_t n = e.ids.size();
                    if (pick(2)) {
                        e.meshes = {pick(2) ? "ball" : "box"};
                    } else {
                        for (std::size_t i = 0; i < n; ++i)
                            e.meshes.push_back(pick(2) ? "ball" : "box");
                    }
                    if (pick(2)) e.materials = {pick(2) ? "red" : "blue"};
                    if (pick(3)) {
                        for (std::size_t i = 0; i < n; ++i)
                            e.transforms.push_back(random_place(rng));
                    }
                    if (pick(4) == 0) e.parent = "park";
                    e.visible = pick(5) != 0;
                    edits.emplace_back(std::move(e));
                    break;
                }
                case 1:
                case 2: {
                    UpdateInstances e;
                    some_ids(e.ids, false);
                    if (pick(3)) {
                        for (std::size_t i = 0; i < e.ids.size(); ++i)
                            e.transforms.push_back(random_place(rng));
                    }
                    if (e.transforms.empty() || pick(2)) e.visible = pick(2) != 0;
                    edits.emplace_back(std::move(e));
                    break;
                }
                default: {
                    RemoveInstances e;
                    some_ids(e.ids, false);
                    edits.emplace_back(std::move(e));
                }
            }
        }
        auto twin = test::with_singles(edits);
        ASSERT_TRUE(twin.has_value());
        auto a = bulk_engine->apply(batch_of(std::move(edits)));
        auto b = single_engine->apply(batch_of(std::move(*twin)));
        ASSERT_EQ(a.has_value(), b.has_value())
            << "round " << round << ": " << (a ? b.error().describe() : a.error().describe());
        if (!a) {
            EXPECT_EQ(a.error().code, b.error().code) << round;
            continue;
        }
        ++accepted;
        if (round % 10 == 9) {
            test::commit_ok(*bulk_engine);
            test::commit_ok(*single_engine);
            EXPECT_TRUE(test::hits(*bulk_engine) == test::hits(*single_engine)) << round;
        }
        EXPECT_TRUE(state_of(*bulk_engine) == state_of(*single_engine)) << round;
    }
    EXPECT_GT(accepted, 10);  // the batches must not all be refused
}

/// A bulk edit refused with `code` at `field` whose message names `item`; the scene unchanged.
void expect_refused(Engine& engine, Edit edit, ErrorCode code, const std::string& field,
                    const std::string& in_message) {
    const std::vector<std::string> before = state_of(engine);
    const uint64_t version = engine.read([](const Scene& s) { return s.version(); });
    auto r = engine.apply(batch_of({test::instance_edit("first", "ball"), std::move(edit)}));
    ASSERT_FALSE(r.has_value()) << field;
    EXPECT_EQ(r.error().code, code) << r.error().describe();
    EXPECT_EQ(r.error().edit_index, 1u);
    EXPECT_EQ(r.error().field, field) << r.error().describe();
    EXPECT_NE(r.error().message.find(in_message), std::string::npos) << r.error().describe();
    EXPECT_TRUE(state_of(engine) == before) << field;
    EXPECT_EQ(engine.read([](const Scene& s) { return s.version(); }), version);
}

TEST(BulkInstances, RefusedItemIsNamedAndChangesNothing) {
    auto engine = test::make_engine();
    base_scene(*engine);
    test::apply_ok(*engine, numbered("t", 10, "ball"));

    const auto adds = [](std::vector<std::string> ids) {
        AddInstances e;
        e.ids.list = std::move(ids);
        e.meshes = {"ball"};
        return e;
    };
    AddInstances twice = adds({"x", "y", "x"});
    expect_refused(*engine, twice, ErrorCode::DuplicateId, "ids/2", "item 2 ('x')");
    AddInstances taken = adds({"x", "t3"});
    expect_refused(*engine, taken, ErrorCode::DuplicateId, "ids/1", "'t3' already exists");
    AddInstances bad_id = adds({"x", ""});
    expect_refused(*engine, bad_id, ErrorCode::InvalidArgument, "ids/1", "item 1");
    AddInstances mesh_each = adds({"x", "y", "z"});
    mesh_each.meshes = {"ball", "box", "cone"};
    expect_refused(*engine, mesh_each, ErrorCode::UnknownId, "mesh/2", "unknown mesh 'cone'");
    AddInstances no_mesh = adds({"x"});
    no_mesh.meshes = {"cone"};
    expect_refused(*engine, no_mesh, ErrorCode::UnknownId, "mesh", "unknown mesh 'cone'");
    AddInstances material_each = adds({"x", "y"});
    material_each.materials = {"red", "green"};
    expect_refused(*engine, material_each, ErrorCode::UnknownId, "material/1", "'green'");
    AddInstances nan = adds({"x", "y"});
    nan.transforms = {Affine::identity(), Affine::identity()};
    nan.transforms[1].m[3] = std::numeric_limits<float>::quiet_NaN();
    expect_refused(*engine, nan, ErrorCode::NotFinite, "transforms/1", "item 1 ('y')");
    AddInstances flat = adds({"x", "y"});
    flat.transforms = {Affine::identity(), Affine::scaling({1, 0, 1})};
    expect_refused(*engine, flat, ErrorCode::DegenerateTransform, "transforms/1", "item 1");
    AddInstances short_list = adds({"x", "y", "z"});
    short_list.transforms = {Affine::identity()};
    expect_refused(*engine, short_list, ErrorCode::InvalidArgument, "transforms",
                   "1 values for 3 ids");
    AddInstances both = adds({"x"});
    both.ids.count = 3;
    expect_refused(*engine, both, ErrorCode::InvalidArgument, "ids", "not both");
    AddInstances huge;
    huge.ids.count = MAX_BULK_ITEMS + 1;
    huge.meshes = {"ball"};
    expect_refused(*engine, huge, ErrorCode::TooLarge, "ids", "over the limit");
    AddInstances wraps;
    wraps.ids.first = std::numeric_limits<uint64_t>::max() - 1;
    wraps.ids.count = 3;
    wraps.meshes = {"ball"};
    expect_refused(*engine, wraps, ErrorCode::OutOfRange, "ids", "2^64");
    AddInstances orphan = adds({"x"});
    orphan.parent = "nowhere";
    expect_refused(*engine, orphan, ErrorCode::UnknownId, "parent", "nowhere");

    UpdateInstances unknown;
    unknown.ids.prefix = "t";
    unknown.ids.first = 5;
    unknown.ids.count = 10;  // t10 .. t14 do not exist
    unknown.visible = false;
    expect_refused(*engine, unknown, ErrorCode::UnknownId, "ids/5", "item 5 ('t10')");
    UpdateInstances nothing;
    nothing.ids.list = {"t1"};
    expect_refused(*engine, nothing, ErrorCode::InvalidArgument, "", "nothing to change");
    RemoveInstances gone;
    gone.ids.list = {"t1", "t1"};
    expect_refused(*engine, gone, ErrorCode::UnknownId, "ids/1", "item 1 ('t1')");
}

TEST(BulkInstances, EmptyBulkEditsDoNothing) {
    auto engine = test::make_engine();
    base_scene(*engine);
    test::commit_ok(*engine);
    const std::vector<std::string> before = state_of(*engine);
    AddInstances none;
    none.meshes = {"ball"};
    RemoveInstances none_removed;
    test::apply_ok(*engine, none, none_removed);
    EXPECT_TRUE(state_of(*engine) == before);
    EXPECT_TRUE(test::commit_ok(*engine).no_accel_work());
}

TEST(BulkInstances, InstanceBudgetRefusesTheBatch) {
    EngineConfig config;
    config.budget.max_instances = 100;
    auto made = test::create_engine(config);
    ASSERT_TRUE(made.has_value());
    Engine& engine = *made.value();
    base_scene(engine);
    AddInstances many;
    many.ids.prefix = "i";
    many.ids.count = 101;
    many.meshes = {"ball"};
    auto r = engine.apply(batch_of({many}));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_NE(r.error().message.find("max_scene_instances"), std::string::npos);
    many.ids.count = 100;
    test::apply_ok(engine, many);
    // A removal and an add in one batch stay within it.
    RemoveInstances one;
    one.ids.list = {"i0"};
    test::apply_ok(engine, one, test::instance_edit("other", "ball"));
}

TEST(BulkInstances, MovesAreATlasUpdateOnly) {
    auto engine = test::make_engine();
    base_scene(*engine);
    AddInstances trees;
    trees.ids.prefix = "t";
    trees.ids.count = 1000;
    trees.meshes = {"ball"};
    test::apply_ok(*engine, trees);
    test::commit_ok(*engine);
    UpdateInstances move;
    move.ids.prefix = "t";
    move.ids.first = 100;
    move.ids.count = 10;
    move.transforms.assign(10, Affine::translation({1, 2, 3}));
    test::apply_ok(*engine, move);
    const RebuildReport report = test::commit_ok(*engine);
    EXPECT_TRUE(report.rebuilt.empty());
    EXPECT_TRUE(report.refit.empty());
    EXPECT_EQ(report.instances_changed, 10u);
}

TEST(BulkInstances, InverseIsOneBulkEditAndRestores) {
    auto engine = test::make_engine();
    base_scene(*engine);
    Scene scene;
    ASSERT_TRUE(scene.apply(engine->read([](const Scene& s) { return s.to_batch(); })).has_value());
    const std::vector<std::string> empty = state_of(scene);

    AddInstances trees;
    trees.ids.prefix = "t";
    trees.ids.count = 500;
    trees.meshes = {"ball"};
    trees.transforms.assign(500, Affine::translation({0, 1, 0}));
    EditBatch inverse;
    ASSERT_TRUE(scene.apply(batch_of({trees}), nullptr, &inverse).has_value());
    ASSERT_EQ(inverse.edits.size(), 1u);
    ASSERT_TRUE(std::holds_alternative<RemoveInstances>(inverse.edits[0]));
    const BulkIds& undone = std::get<RemoveInstances>(inverse.edits[0]).ids;
    EXPECT_EQ(undone.size(), 500u);
    // The ids are a numbered range: the inverse keeps the range, not 500 strings.
    EXPECT_TRUE(undone.list.empty());
    EXPECT_EQ(undone.prefix, "t");
    EXPECT_EQ(undone.first, 0u);
    const std::vector<std::string> planted = state_of(scene);

    UpdateInstances move;
    move.ids.prefix = "t";
    move.ids.count = 500;
    move.transforms.assign(500, Affine::translation({5, 0, 0}));
    EditBatch move_back;
    ASSERT_TRUE(scene.apply(batch_of({move}), nullptr, &move_back).has_value());
    ASSERT_EQ(move_back.edits.size(), 1u);
    ASSERT_TRUE(std::holds_alternative<UpdateInstances>(move_back.edits[0]));
    ASSERT_TRUE(scene.apply(std::move(move_back)).has_value());
    EXPECT_TRUE(state_of(scene) == planted);

    RemoveInstances cut;
    cut.ids.prefix = "t";
    cut.ids.count = 500;
    EditBatch put_back;
    ASSERT_TRUE(scene.apply(batch_of({cut}), nullptr, &put_back).has_value());
    ASSERT_EQ(put_back.edits.size(), 1u);
    ASSERT_TRUE(std::holds_alternative<AddInstances>(put_back.edits[0]));
    EXPECT_EQ(std::get<AddInstances>(put_back.edits[0]).meshes.size(), 1u);
    ASSERT_TRUE(scene.apply(std::move(put_back)).has_value());
    EXPECT_TRUE(state_of(scene) == planted);

    // Instances whose fields a bulk add cannot carry come back one by one, between bulk runs.
    UpdateInstance masked;
    masked.instance = "t7";
    masked.mask = 2;
    UpdateInstance named;
    named.instance = "t300";
    named.name = "a named tree";
    AddInstance other = test::instance_edit("box-1", "box", Vec3(1, 2, 3));
    other.material = "red";
    ASSERT_TRUE(scene.apply(batch_of({masked, named, other})).has_value());
    const std::vector<std::string> mixed = state_of(scene);
    RemoveInstances cut_mixed;
    cut_mixed.ids.list = {"t0", "t7", "box-1", "t1", "t300", "t2"};
    ASSERT_TRUE(scene.apply(batch_of({cut_mixed}), nullptr, &put_back).has_value());
    EXPECT_GT(put_back.edits.size(), 1u);
    ASSERT_TRUE(scene.apply(std::move(put_back)).has_value());
    EXPECT_TRUE(state_of(scene) == mixed);
    RemoveInstances cut_extra;
    cut_extra.ids.list = {"box-1"};
    ASSERT_TRUE(scene.apply(batch_of({cut_extra})).has_value());

    ASSERT_TRUE(scene.apply(std::move(inverse)).has_value());
    EXPECT_TRUE(state_of(scene) == empty);
}

TEST(BulkInstances, OnlyExactNumberedRangesBecomeRanges) {
    auto engine = test::make_engine();
    base_scene(*engine);
    Scene scene;
    ASSERT_TRUE(scene.apply(engine->read([](const Scene& s) { return s.to_batch(); })).has_value());
    const std::vector<std::string> before = state_of(scene);
    const std::vector<std::vector<std::string>> lists = {
        {"p1", "p01", "p2"},      // a leading zero: not the canonical spelling of a number
        {"p1", "p3", "p4"},       // a gap
        {"p1", "q2", "p3"},       // another prefix
        {"p", "p1", "p2"},        // no number
        {"p7", "p5", "p6", "p8"}  // any order: the range p5 .. p8
    };
    for (const auto& ids : lists) {
        AddInstances add;
        add.ids.list = ids;
        add.meshes = {"ball"};
        for (std::size_t i = 0; i < ids.size(); ++i)
            add.transforms.push_back(Affine::translation({float(i), 0, 0}));
        EditBatch inverse;
        ASSERT_TRUE(scene.apply(batch_of({add}), nullptr, &inverse).has_value());
        ASSERT_EQ(inverse.edits.size(), 1u);
        const BulkIds& undo = std::get<RemoveInstances>(inverse.edits[0]).ids;
        EXPECT_EQ(undo.list.empty(), ids.front() == "p7") << ids.front();
        EXPECT_EQ(undo.size(), ids.size());

        // And the moves' inverse keeps each transform with its own instance.
        const std::vector<std::string> placed = state_of(scene);
        UpdateInstances move;
        move.ids.list = ids;
        move.transforms.assign(ids.size(), Affine::translation({0, 9, 0}));
        EditBatch move_back;
        ASSERT_TRUE(scene.apply(batch_of({move}), nullptr, &move_back).has_value());
        ASSERT_TRUE(scene.apply(std::move(move_back)).has_value());
        EXPECT_TRUE(state_of(scene) == placed) << ids.front();

        ASSERT_TRUE(scene.apply(std::move(inverse)).has_value());
        EXPECT_TRUE(state_of(scene) == before) << ids.front();
    }
}

TEST(BulkInstances, ASnapshotPacksRunsOfInstancesIntoFewBulkAddsAndRebuildsTheSameScene) {
    auto engine = test::make_engine();
    base_scene(*engine);
    std::mt19937 rng(9);
    EditBatch b;
    for (int i = 0; i < 3000; ++i) {
        AddInstance e;
        e.id = "ball" + std::to_string(i);
        e.mesh = "ball";
        e.transform = random_place(rng);
        b.edits.emplace_back(std::move(e));
    }
    for (int i = 0; i < 500; ++i) {
        AddInstance e;
        e.id = "crate-" + std::to_string(i);
        e.mesh = "box";
        e.material = i % 3 ? "red" : "blue";  // per item
        e.parent = "park";
        e.transform = random_place(rng);
        if (i % 100 == 7) e.user_id = 7;  // a field a bulk add does not carry: on its own
        b.edits.emplace_back(std::move(e));
    }
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    test::commit_ok(*engine);

    const EditBatch numbered = engine->read([](const Scene& s) { return s.to_batch(); });
    std::size_t bulk = 0, single = 0, items = 0;
    for (const Edit& e : numbered.edits) {
        if (const auto* add = std::get_if<AddInstances>(&e)) {
            ++bulk;
            items += add->ids.size();
        }
        single += std::holds_alternative<AddInstance>(e);
    }
    EXPECT_EQ(items + single, 3500u);
    EXPECT_EQ(single, 5u) << "the five with a user id";
    EXPECT_LE(bulk, 7u);

    // A removal leaves a hole the next add fills: slot order is no longer the numbering, so that
    // run stays a list; the scene rebuilt from the snapshot is the same, in the same order.
    test::apply_ok(*engine, RemoveInstance{"ball17"}, AddInstance{"late", "ball"});
    test::commit_ok(*engine);
    const EditBatch image = engine->read([](const Scene& s) { return s.to_batch(); });
    auto restored = test::make_engine();
    ASSERT_TRUE(restored->apply(EditBatch(image)).has_value());
    test::commit_ok(*restored);
    EXPECT_EQ(test::encoded(restored->read([](const Scene& s) { return s.to_batch(); })),
              test::encoded(image));
    EXPECT_TRUE(state_of(*restored) == state_of(*engine));
    EXPECT_TRUE(test::hits(*restored) == test::hits(*engine));
    EXPECT_LT(test::encoded(image).size(), 3500u * 80u)
        << "no id map or per-item defaults repeated";
}

TEST(BulkInstances, NumberedInstancesInSlotOrderAreWrittenAsARange) {
    auto engine = test::make_engine();
    base_scene(*engine);
    test::apply_ok(*engine, numbered("tree-", 100000, "ball"));
    const EditBatch image = engine->read([](const Scene& s) { return s.to_batch(); });
    std::size_t ranges = 0;
    for (const Edit& e : image.edits) {
        if (const auto* bulk = std::get_if<AddInstances>(&e)) {
            EXPECT_TRUE(bulk->ids.list.empty());
            EXPECT_EQ(bulk->ids.prefix, "tree-");
            EXPECT_EQ(bulk->ids.count, 100000u);
            ++ranges;
        }
    }
    EXPECT_EQ(ranges, 1u);
    EXPECT_LT(test::encoded(image).size(), 100000u * 52u) << "the transforms, and little beside";
}

TEST(BulkInstances, AFirstCommitOfManyRefreshesTheirShadingInParallelAndCountsEmitters) {
    // Past a few thousand listed instances the launch state refreshes them in parallel: every
    // instance's shade and emitter flag must come out as one by one, and the emitter table must
    // hold each emitting instance's triangles once.
    auto engine = test::make_engine();
    Material glow;
    glow.emission = Vec3(2.0f);
    constexpr uint32_t N = 9000;
    AddInstances plain, lit;
    plain.ids.prefix = "p";
    lit.ids.prefix = "e";
    plain.meshes = lit.meshes = {"quad"};
    lit.materials = {"glow"};
    for (uint32_t i = 0; i < N; ++i) {
        AddInstances& to = i % 3 == 0 ? lit : plain;
        to.transforms.push_back(Affine::translation(Vec3(float(i % 100), 0.0f, float(i / 100))));
    }
    plain.ids.count = plain.transforms.size();
    lit.ids.count = lit.transforms.size();
    // The material first: a batch that adds an emissive material recounts every instance.
    test::apply_ok(*engine, test::mesh_edit("quad", make_plane(Vec3(0.4f, 0.0f, 0.4f), 1, 1)),
                   AddMaterial{"glow", glow});
    test::commit_ok(*engine);
    test::apply_ok(*engine, plain, lit);
    auto check = [&](std::size_t emitting) {
        const auto launched =
            engine->launch([&](const FrameState& f, const TlasStrategy&, const RebuildReport&) {
                std::size_t flagged = 0;
                for (uint32_t slot = 0; slot < f.instances.size(); ++slot) {
                    const bool glows =
                        !f.instance_ids[slot].empty() && f.instance_ids[slot][0] == 'e';
                    EXPECT_EQ(f.is_emitter(slot), glows) << f.instance_ids[slot];
                    EXPECT_EQ(f.instances[slot].material != DEFAULT_MATERIAL, glows);
                    flagged += f.is_emitter(slot);
                }
                EXPECT_EQ(flagged, emitting);
                EXPECT_EQ(f.emitter_instances(), emitting);
                EXPECT_EQ(f.lights.emitter_count(), 2 * emitting) << "two triangles an instance";
                return true;
            });
        ASSERT_TRUE(launched.has_value());
    };
    check(lit.ids.count);
    RemoveInstances gone;
    gone.ids.prefix = "e";
    gone.ids.count = lit.ids.count / 2;
    test::apply_ok(*engine, gone);
    check(lit.ids.count - gone.ids.count);
}

TEST(BulkInstances, JournalLayoutReadsBack) {
    AddInstances add;
    add.ids.list = {"a", "b"};
    add.meshes = {"m1", "m2"};
    add.materials = {"red"};
    add.transforms = {Affine::translation({1, 2, 3}), Affine::scaling({2, 2, 2})};
    add.parent = "g";
    add.visible = false;
    UpdateInstances update;
    update.ids.prefix = "tree-";
    update.ids.first = 40;
    update.ids.count = 2;
    update.transforms = {Affine::identity(), Affine::translation({0, 0, 1})};
    update.visible = true;
    RemoveInstances remove;
    remove.ids.prefix = "r";
    remove.ids.count = 1u << 20;
    const std::string bytes = test::encoded(batch_of({add, update, remove}));
    auto back = durable::decode_batch(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(test::encoded(back.value()), bytes);
    const auto& a = std::get<AddInstances>(back.value().edits[0]);
    EXPECT_EQ(a.ids.list, add.ids.list);
    EXPECT_EQ(a.meshes, add.meshes);
    EXPECT_EQ(a.transforms[1].m, add.transforms[1].m);
    EXPECT_EQ(a.parent, add.parent);
    EXPECT_FALSE(a.visible);
    EXPECT_EQ(std::get<UpdateInstances>(back.value().edits[1]).ids.at(1), "tree-41");
    // A range of a million ids is a few bytes, not a million strings.
    EXPECT_LT(bytes.size(), 400u);
    // Truncated anywhere: an error, never a crash.
    for (std::size_t cut = 0; cut < bytes.size(); ++cut)
        EXPECT_FALSE(durable::decode_batch(std::string_view(bytes).substr(0, cut)).has_value());
}

}  // namespace
}  // namespace strata
