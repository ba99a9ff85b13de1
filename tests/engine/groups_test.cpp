// The scene graph: world transforms and visibility through groups, the rules of the group ops
// (cycles, depth, in-use, recursive removal), atomic rollback of group edits, and the flattening's
// cost following the dirtied subtree.

#include <gtest/gtest.h>

#include "engine/scene/scene.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::instance_edit;
using test::mesh_edit;

AddGroup group_edit(const std::string& id, std::optional<std::string> parent = std::nullopt,
                    Vec3 at = Vec3(0.0f)) {
    AddGroup g;
    g.id = id;
    g.parent = std::move(parent);
    g.transform = Affine::translation(at);
    return g;
}

AddInstance child_instance(const std::string& id, const std::string& parent, Vec3 at = Vec3(0.0f)) {
    AddInstance e = instance_edit(id, "box", at);
    e.parent = parent;
    return e;
}

UpdateGroup move_group(const std::string& id, Vec3 to) {
    UpdateGroup u;
    u.group = id;
    u.transform = Affine::translation(to);
    return u;
}

UpdateGroup reparent_group(const std::string& id, std::optional<std::string> parent) {
    UpdateGroup u;
    u.group = id;
    u.parent = std::move(parent);
    return u;
}

template <class... Edits>
Result<uint64_t> apply(Scene& s, Edits&&... edits) {
    EditBatch b;
    (b.edits.emplace_back(std::forward<Edits>(edits)), ...);
    return s.apply(std::move(b));
}

/// car (at x=10) > wheels (at y=1) > w0, w1; car > body; lamp at the root.
class Groups : public ::testing::Test {
protected:
    void SetUp() override {
        auto r = apply(scene, mesh_edit("box", make_box(Vec3(1.0f))), group_edit("car", {}, {10, 0, 0}),
                       group_edit("wheels", "car", {0, 1, 0}), child_instance("w0", "wheels", {1, 0, 0}),
                       child_instance("w1", "wheels", {-1, 0, 0}), child_instance("body", "car"),
                       instance_edit("lamp", "box", {0, 5, 0}));
        ASSERT_TRUE(r.has_value()) << r.error().describe();
        scene.clear_changes();
    }

    const InstanceRecord& inst(const std::string& id) {
        return *scene.instance(scene.find_instance(id)).value();
    }
    Vec3 origin(const std::string& id) { return inst(id).world.transform_point(Vec3(0.0f)); }

    Scene scene;
};

TEST_F(Groups, WorldTransformIsTheProductOfTheAncestorsAndItsOwn) {
    EXPECT_EQ(origin("w0"), Vec3(11, 1, 0));
    EXPECT_EQ(origin("w1"), Vec3(9, 1, 0));
    EXPECT_EQ(origin("body"), Vec3(10, 0, 0));
    EXPECT_EQ(origin("lamp"), Vec3(0, 5, 0));
    EXPECT_EQ(scene.group_path(inst("w0").parent), (std::vector<std::string>{"car", "wheels"}));
    EXPECT_TRUE(scene.group_path(inst("lamp").parent).empty());
}

TEST_F(Groups, MovingAGroupRecomputesItsSubtreeOnly) {
    ASSERT_TRUE(apply(scene, move_group("wheels", {0, 2, 0})).has_value());
    EXPECT_EQ(origin("w0"), Vec3(11, 2, 0));
    EXPECT_EQ(origin("body"), Vec3(10, 0, 0));
    // wheels, w0, w1: the car, the body and the lamp are not visited.
    EXPECT_EQ(scene.changes().world_transforms(), 3u);
    EXPECT_EQ(scene.changes().instances().size(), 2u);
}

TEST_F(Groups, MovingAnOuterAndAnInnerGroupInOneBatchVisitsEachNodeOnce) {
    ASSERT_TRUE(apply(scene, move_group("wheels", {0, 3, 0}), move_group("car", {0, 0, 0})).has_value());
    EXPECT_EQ(origin("w1"), Vec3(-1, 3, 0));
    EXPECT_EQ(origin("body"), Vec3(0, 0, 0));
    EXPECT_EQ(scene.changes().world_transforms(), 5u);  // car, wheels, w0, w1, body
}

TEST_F(Groups, AHiddenGroupHidesItsWholeSubtree) {
    UpdateGroup hide;
    hide.group = "car";
    hide.visible = false;
    ASSERT_TRUE(apply(scene, hide).has_value());
    EXPECT_FALSE(inst("w0").world_visible);
    EXPECT_TRUE(inst("w0").visible);  // its own flag is unchanged
    EXPECT_FALSE(inst("body").world_visible);
    EXPECT_TRUE(inst("lamp").world_visible);
    EXPECT_TRUE(inst("w0").dirty.has(InstanceDirty::Visibility));
    // Showing the car again, with w0 hidden on its own, shows all but w0.
    UpdateGroup show = hide;
    show.visible = true;
    UpdateInstance w0;
    w0.instance = "w0";
    w0.visible = false;
    ASSERT_TRUE(apply(scene, show, w0).has_value());
    EXPECT_FALSE(inst("w0").world_visible);
    EXPECT_TRUE(inst("w1").world_visible);
}

TEST_F(Groups, ReparentingMovesTheSubtreeAndKeepsLocalTransforms) {
    ASSERT_TRUE(apply(scene, reparent_group("wheels", std::nullopt)).has_value());
    EXPECT_EQ(origin("w0"), Vec3(1, 1, 0));
    UpdateInstance lamp;
    lamp.instance = "lamp";
    lamp.parent = std::optional<std::string>("wheels");
    ASSERT_TRUE(apply(scene, lamp).has_value());
    EXPECT_EQ(origin("lamp"), Vec3(0, 6, 0));
    EXPECT_EQ(scene.children(scene.find_group("wheels")).instances.size(), 3u);
    EXPECT_TRUE(scene.children(GroupHandle{}).instances.empty());
}

TEST_F(Groups, ACycleIsRefusedNamingIt) {
    auto r = apply(scene, reparent_group("car", "wheels"));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::Cycle);
    EXPECT_EQ(r.error().field, "parent");
    EXPECT_NE(r.error().message.find("'car' > 'wheels' > 'car'"), std::string::npos)
        << r.error().message;
    auto self = apply(scene, reparent_group("car", "car"));
    ASSERT_FALSE(self.has_value());
    EXPECT_EQ(self.error().code, ErrorCode::Cycle);
}

TEST_F(Groups, NestingBeyondTheDepthLimitIsRefused) {
    EditBatch chain;
    std::optional<std::string> parent;
    for (uint32_t d = 0; d < MAX_GROUP_DEPTH; ++d) {
        chain.edits.emplace_back(group_edit("g" + std::to_string(d), parent));
        parent = "g" + std::to_string(d);
    }
    ASSERT_TRUE(scene.apply(std::move(chain)).has_value());
    auto deeper = apply(scene, group_edit("too-deep", parent));
    ASSERT_FALSE(deeper.has_value());
    EXPECT_EQ(deeper.error().code, ErrorCode::InvalidArgument);
    EXPECT_NE(deeper.error().message.find("limit is 64"), std::string::npos);
    // Moving a two-level subtree (car > wheels) under g62 would reach 65.
    auto moved = apply(scene, reparent_group("car", "g62"));
    ASSERT_FALSE(moved.has_value());
    EXPECT_TRUE(apply(scene, reparent_group("car", "g61")).has_value());
}

/// `levels` nested groups "s0" > "s1" > ..., each scaled by `factor`, under `parent`.
EditBatch scaled_chain(uint32_t levels, float factor, std::optional<std::string> parent = {}) {
    EditBatch chain;
    for (uint32_t d = 0; d < levels; ++d) {
        AddGroup g = group_edit("s" + std::to_string(d), parent);
        g.transform = Affine::scaling(Vec3(factor));
        chain.edits.emplace_back(std::move(g));
        parent = "s" + std::to_string(d);
    }
    return chain;
}

TEST_F(Groups, AWorldTransformBeyondFloatRangeIsRefusedNamingTheChain) {
    // Each group's own scale is fine; eight of 1e6 compose to 1e48, past float's 3.4e38.
    EditBatch chain = scaled_chain(8, 1e6f);
    chain.edits.emplace_back(child_instance("far", "s7"));
    const std::size_t edits_before = scene.to_batch().edits.size();
    auto r = scene.apply(std::move(chain));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::NotFinite);
    EXPECT_NE(r.error().message.find("'s0' > 's1' > 's2'"), std::string::npos) << r.error().message;
    EXPECT_TRUE(scene.find_group("s0").is_null());
    EXPECT_EQ(scene.to_batch().edits.size(), edits_before);
    EXPECT_TRUE(scene.changes().empty());
}

TEST_F(Groups, AnInstancesWorldTransformKeepsTheRuleOfARootInstancesTransform) {
    // Two groups of 5e5 (a finite 2.5e11 world) hold an instance scaled back to 5e5: allowed.
    EditBatch chain = scaled_chain(2, 5e5f);
    AddInstance deep = child_instance("deep", "s1");
    deep.transform = Affine::scaling(Vec3(2e-6f));
    chain.edits.emplace_back(std::move(deep));
    auto held = scene.apply(std::move(chain));
    ASSERT_TRUE(held.has_value()) << held.error().describe();
    scene.clear_changes();
    // Unscaled, its world would scale by 2.5e11, which no root instance may: refused.
    UpdateInstance unscaled;
    unscaled.instance = "deep";
    unscaled.transform = Affine::identity();
    auto r = apply(scene, unscaled);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::DegenerateTransform);
    EXPECT_NE(r.error().message.find("instance 'deep'"), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("'s0' > 's1'"), std::string::npos) << r.error().message;
    EXPECT_NE(r.error().message.find("beyond 1e6"), std::string::npos) << r.error().message;
    EXPECT_TRUE(scene.changes().empty());
    // Moved 1e4 along x inside a 2.5e11 chain, it would sit at 2.5e15, where no ray is traced.
    UpdateInstance offset;
    offset.instance = "deep";
    offset.transform = Affine::translation(Vec3(1e4f, 0.0f, 0.0f)) * Affine::scaling(Vec3(2e-6f));
    auto moved = apply(scene, offset);
    ASSERT_FALSE(moved.has_value());
    EXPECT_NE(moved.error().message.find("beyond 1e15"), std::string::npos) << moved.error().message;
    // Scaling the chain down in the same batch makes the unscaled instance fine.
    UpdateGroup shrink;
    shrink.group = "s0";
    shrink.transform = Affine::scaling(Vec3(2e-6f));
    ASSERT_TRUE(apply(scene, shrink, unscaled).has_value());
    EXPECT_NEAR(inst("deep").world.transform_point(Vec3(1.0f, 0.0f, 0.0f)).x, 1.0f, 1e-4f);
}

TEST_F(Groups, ASnapshotWhoseWorldTransformsOverflowDoesNotLoad) {
    EditBatch chain = scaled_chain(8, 1e6f);
    chain.edits.emplace_back(child_instance("far", "s7"));
    Scene loaded;
    ASSERT_TRUE(loaded.load(mesh_edit("box", make_box(Vec3(1.0f)))));
    for (Edit& e : chain.edits) ASSERT_TRUE(loaded.load(std::move(e)));
    Status s = loaded.finish_load(7);
    ASSERT_FALSE(s);
    EXPECT_EQ(s.error().code, ErrorCode::NotFinite);
}

TEST_F(Groups, RemovingAGroupWithChildrenNeedsRecursive) {
    auto r = apply(scene, RemoveGroup{"car", false});
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::InUse);
    ASSERT_TRUE(apply(scene, RemoveGroup{"car", true}).has_value());
    EXPECT_EQ(scene.groups().size(), 0u);
    EXPECT_EQ(scene.instances().size(), 1u);  // the lamp
    EXPECT_TRUE(scene.find_instance("w0").is_null());
    EXPECT_EQ(scene.meshes().at(scene.find_mesh("box")).users.size(), 1u);
}

TEST_F(Groups, ARefusedBatchLeavesTheGraphExactlyAsBefore) {
    const EditBatch before = scene.to_batch();
    const std::vector<InstanceHandle> wheels_before =
        scene.children(scene.find_group("wheels")).instances;
    UpdateInstance lamp;
    lamp.instance = "lamp";
    lamp.parent = std::optional<std::string>("wheels");
    UpdateInstance w0;
    w0.instance = "w0";
    w0.parent = std::optional<std::string>();
    auto r = apply(scene, move_group("car", {1, 1, 1}), lamp, w0, RemoveGroup{"wheels", true},
                   group_edit("new", "car"), reparent_group("car", "new"));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().edit_index, 5u);
    EXPECT_EQ(scene.children(scene.find_group("wheels")).instances, wheels_before);
    EXPECT_EQ(origin("w0"), Vec3(11, 1, 0));
    EXPECT_TRUE(scene.find_group("new").is_null());
    EXPECT_TRUE(scene.changes().empty());
    // The same state, edit for edit (ids, parents, transforms).
    const EditBatch after = scene.to_batch();
    ASSERT_EQ(after.edits.size(), before.edits.size());
    for (std::size_t i = 0; i < after.edits.size(); ++i) {
        if (const auto* a = std::get_if<AddInstance>(&after.edits[i])) {
            const auto& b = std::get<AddInstance>(before.edits[i]);
            EXPECT_EQ(a->id, b.id);
            EXPECT_EQ(a->parent, b.parent);
            EXPECT_EQ(a->transform, b.transform);
        }
    }
    // A later valid batch hands out the same handles as if nothing had been tried.
    ASSERT_TRUE(apply(scene, group_edit("again", "car")).has_value());
}

TEST_F(Groups, ToBatchRebuildsTheSameGraph) {
    ASSERT_TRUE(apply(scene, reparent_group("wheels", std::nullopt), group_edit("a", "wheels"),
                      reparent_group("car", "a"))
                    .has_value());
    Scene copy;
    ASSERT_TRUE(copy.apply(scene.to_batch()).has_value());
    scene.instances().for_each([&](InstanceHandle, const InstanceRecord& i) {
        const InstanceRecord& c = *copy.instance(copy.find_instance(i.id)).value();
        EXPECT_EQ(c.world, i.world) << i.id;
        EXPECT_EQ(copy.group_path(c.parent), scene.group_path(i.parent)) << i.id;
    });
    EXPECT_EQ(copy.groups().size(), scene.groups().size());
}

TEST_F(Groups, ClearRemovesGroupsToo) {
    ASSERT_TRUE(apply(scene, Clear{}).has_value());
    EXPECT_EQ(scene.groups().size(), 0u);
    EXPECT_TRUE(scene.find_group("car").is_null());
    EXPECT_TRUE(scene.children(GroupHandle{}).empty());
}

TEST_F(Groups, AnUnknownParentIsRefused) {
    auto r = apply(scene, child_instance("x", "nope"));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::UnknownId);
    EXPECT_EQ(r.error().field, "parent");
}

}  // namespace
}  // namespace strata
