// An instance's rarely set fields live in a box that stays empty until one is set: plain
// instances, bulk-added or moved under plain groups, hold one null pointer; a name, motion keys,
// an animation or an LOD band fill it, and copies of a record copy its box.

#include <string>

#include <gtest/gtest.h>

#include "engine/scene/scene.h"
#include "engine/scene/shapes.h"

namespace strata {
namespace {

bool boxed(const Scene& s, const char* id) {
    return bool(s.instance(s.find_instance(id)).value()->rare);
}

EditBatch plain_scene() {
    EditBatch b;
    b.edits.emplace_back(add_mesh_edit("box", make_box(Vec3(1))));
    AddGroup g;
    g.id = "g";
    g.transform = Affine::translation({1, 0, 0});
    b.edits.emplace_back(std::move(g));
    AddInstances many;
    many.ids.prefix = "p";
    many.ids.count = 100;
    many.meshes = {"box"};
    many.parent = "g";
    b.edits.emplace_back(std::move(many));
    AddInstance one;
    one.id = "one";
    one.mesh = "box";
    one.transform = Affine::translation({0, 2, 0});
    b.edits.emplace_back(std::move(one));
    return b;
}

TEST(InstanceRare, PlainInstancesLeaveTheirBoxEmpty) {
    Scene s;
    ASSERT_TRUE(s.apply(plain_scene()).has_value());
    EditBatch moves;
    moves.edits.emplace_back(SetTransform{"p7", Affine::translation({0, 0, 3})});
    UpdateGroup g;
    g.group = "g";
    g.transform = Affine::translation({0, 5, 0});
    moves.edits.emplace_back(std::move(g));
    ASSERT_TRUE(s.apply(std::move(moves)).has_value());
    s.instances().for_each(
        [&](InstanceHandle, const InstanceRecord& r) { EXPECT_FALSE(r.rare) << r.id; });
    EXPECT_EQ(s.instance(s.find_instance("p7")).value()->world.m[7], 5.0f);
}

TEST(InstanceRare, SettingARareFieldFillsTheBoxAndUndoKeepsTheValue) {
    Scene s;
    ASSERT_TRUE(s.apply(plain_scene()).has_value());
    UpdateInstance named;
    named.instance = "one";
    named.name = "Crate";
    UpdateInstance keyed;
    keyed.instance = "p3";
    keyed.motion = std::vector<Affine>{Affine{}, Affine::translation({1, 0, 0})};
    ASSERT_TRUE(s.apply(EditBatch{{named, keyed}}).has_value());
    EXPECT_TRUE(boxed(s, "one"));
    EXPECT_EQ(s.instance(s.find_instance("one")).value()->rare->name, "Crate");
    const InstanceRecord& p3 = *s.instance(s.find_instance("p3")).value();
    EXPECT_EQ(p3.rare->motion.size(), 2u);
    EXPECT_EQ(p3.rare->world_motion.size(), 2u) << "the flattening composed its world keys";
    EXPECT_FALSE(boxed(s, "p4"));

    // A refused batch restores the value it changed (an unknown id after the update).
    UpdateInstance renamed = named;
    renamed.name = "Barrel";
    ASSERT_FALSE(s.apply(EditBatch{{renamed, SetTransform{"nobody", Affine{}}}}).has_value());
    EXPECT_EQ(s.instance(s.find_instance("one")).value()->rare->name, "Crate");
}

TEST(Boxed, CopiesCopyTheValueAndAnEmptyBoxReadsTheDefaults) {
    Boxed<InstanceRare> empty;
    EXPECT_FALSE(empty);
    EXPECT_EQ(empty->lod_far, LOD_NO_LIMIT);
    Boxed<InstanceRare> a;
    a.mut().name = "a";
    Boxed<InstanceRare> b = a;
    b.mut().name = "b";
    EXPECT_EQ(a->name, "a");
    EXPECT_EQ(b->name, "b");
    b = empty;
    EXPECT_FALSE(b);
    EXPECT_EQ(b->name, "");
}

}  // namespace
}  // namespace strata
