// The object kinds' field tables (engine/scene/object_fields.h): each row is consistent with
// itself, an update of every field reaches the record, the rebuild batch carries every field, and
// the value rules name the field and its range.

#include <cmath>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "engine/scene/object_fields.h"
#include "tests/changed_values.h"

namespace strata {
namespace {

using test::changed;

template <class K>
void expect_consistent_table() {
    SCOPED_TRACE(std::string(K::KIND));
    std::set<std::string_view> names;
    std::set<int> tags;
    const typename K::Add defaults{};
    for_each_field<K>([&](const auto& row) {
        EXPECT_TRUE(names.insert(row.info.name).second) << "two rows named " << row.info.name;
        if (row.info.tag != 0) {
            EXPECT_TRUE(tags.insert(row.info.tag).second) << "tag " << int(row.info.tag);
        }
        EXPECT_FALSE(row.info.doc.empty()) << row.info.name;
        EXPECT_TRUE(check_value(row.info, defaults.*(row.add)).has_value())
            << row.info.name << ": its default breaks its own rule";
    });
}

TEST(FieldTables, NamesAndTagsAreUniqueAndEveryDefaultKeepsItsOwnRule) {
    expect_consistent_table<LightFields>();
    expect_consistent_table<MaterialFields>();
    expect_consistent_table<InstanceFields>();
    expect_consistent_table<GroupFields>();
    expect_consistent_table<MeshFields>();
    expect_consistent_table<TextureFields>();
    expect_consistent_table<CameraFields>();
    expect_consistent_table<LightingFields>();
}

/// Changes every field of a record, carries the change in an update (update_to) onto a fresh
/// record (apply_update), and expects every field there with every row's dirty bit.
template <class K>
void expect_updates_reach_the_record() {
    SCOPED_TRACE(std::string(K::KIND));
    typename K::Record edited{};
    DirtyBits<typename K::Dirty> every_bit;
    for_each_field<K>([&](const auto& row) {
        set_record_value(edited, row.record, changed(record_value(edited, row.record)));
        every_bit |= row.dirty;
    });
    typename K::Record fresh{};
    const DirtyBits<typename K::Dirty> bits = apply_update<K>(fresh, update_to<K>(edited));
    EXPECT_TRUE(save_fields<K>(fresh) == save_fields<K>(edited));
    EXPECT_EQ(bits, every_bit);
    // And back: the saved values restore the record.
    restore_fields<K>(fresh, save_fields<K>(typename K::Record{}));
    EXPECT_TRUE(save_fields<K>(fresh) == save_fields<K>(typename K::Record{}));
}

TEST(FieldTables, AnUpdateOfEveryFieldReachesTheRecordAndMarksItsBits) {
    expect_updates_reach_the_record<LightFields>();
    expect_updates_reach_the_record<MaterialFields>();
    expect_updates_reach_the_record<InstanceFields>();
    expect_updates_reach_the_record<GroupFields>();
    expect_updates_reach_the_record<CameraFields>();
    expect_updates_reach_the_record<LightingFields>();
}

TEST(FieldTables, AnAddEditCarriesEveryFieldToTheRecordAndBack) {
    AddInstance add;
    for_each_field<InstanceFields>(
        [&](const auto& row) { add.*(row.add) = changed(add.*(row.add)); });
    const AddInstance original = add;
    InstanceRecord r;
    copy_added<InstanceFields>(r, add);
    AddInstance back;
    copy_to_add<InstanceFields>(back, r);
    for_each_field<InstanceFields>([&](const auto& row) {
        EXPECT_TRUE(back.*(row.add) == original.*(row.add)) << row.info.name;
    });
}

TEST(FieldTables, AValueOutsideItsRuleNamesTheFieldAndTheRange) {
    Light l;
    l.intensity = -1;
    Status s = check_light(l);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().code, ErrorCode::InvalidArgument);
    EXPECT_EQ(s.error().field, "intensity");
    EXPECT_EQ(s.error().message, "intensity must be in [0, 1e12]");

    l = Light{};
    l.angle_deg = 0;
    s = check_light(l);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().message, "angle_deg must be in (0, 90]");

    l = Light{};
    l.color = Vec3(1, -0.5f, 1);
    s = check_light(l);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().message, "color components must be >= 0");

    l = Light{};
    l.position = Vec3(0, NAN, 0);
    s = check_light(l);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().code, ErrorCode::NotFinite);
    EXPECT_EQ(s.error().field, "position");

    Camera c;
    c.fov_y_deg = 180;
    s = check_camera(c);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().message, "fov_y_deg must be in (0, 180)");

    Material m;
    m.roughness = 1.5f;
    s = check_material(m);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().message, "roughness must be in [0, 1]");
}

TEST(FieldTables, LimitsReadAsPeopleWriteThem) {
    EXPECT_EQ(limits_text(closed(0, 1)), "[0, 1]");
    EXPECT_EQ(limits_text(above_up_to(0, 1e6)), "(0, 1e6]");
    EXPECT_EQ(limits_text(at_least(0)), ">= 0");
    EXPECT_EQ(limits_text(closed(-1e15, 1e15)), "[-1e15, 1e15]");
    EXPECT_EQ(limits_text(closed(0.25, 4294967295.0)), "[0.25, 4294967295]");
}

}  // namespace
}  // namespace strata
