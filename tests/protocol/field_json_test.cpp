// The field tables on the wire (protocol/field_json.h): what the JSON writer writes for an object
// the parser reads back into the same values, for every field of every kind with an op.

#include <string>

#include <gtest/gtest.h>

#include "protocol/edit_parser.h"
#include "protocol/field_json.h"
#include "tests/changed_values.h"

namespace strata::protocol {
namespace {

using test::changed;

/// Record `K` with every field changed, written as JSON into `op` and parsed back as one edit.
template <class K>
std::pair<typename K::Record, Edit> round_trip(Json op) {
    typename K::Record r{};
    for_each_field<K>([&](const auto& row) {
        set_record_value(r, row.record, changed(record_value(r, row.record)));
    });
    write_fields<K>(op, r);
    Json body = {{"edits", Json::array({op})}};
    auto parsed = parse_edit_batch(body);
    EXPECT_TRUE(parsed.has_value()) << body.dump() << ": " << (parsed ? "" : parsed.error().detail);
    if (!parsed) return {r, Edit{}};
    return {r, parsed.value().batch.edits.at(0)};
}

template <class K, class V>
void expect_fields(const typename K::Record& want, const V& got) {
    for_each_field<K>([&](const auto& row) {
        if constexpr (std::is_same_v<V, typename K::Update>) {
            ASSERT_TRUE((got.*(row.update)).has_value()) << row.info.name;
            EXPECT_TRUE(*(got.*(row.update)) == record_value(want, row.record)) << row.info.name;
        } else {
            EXPECT_TRUE(field_in(row, got) == record_value(want, row.record)) << row.info.name;
        }
    });
}

TEST(FieldJson, EveryFieldAnAddOpTakesReadsBackAsWritten) {
    {
        auto [want, edit] = round_trip<LightFields>({{"op", "add_light"}, {"id", "l"}});
        expect_fields<LightFields>(want, std::get<AddLight>(edit).light);
    }
    {
        auto [want, edit] = round_trip<MaterialFields>({{"op", "add_material"}, {"id", "m"}});
        expect_fields<MaterialFields>(want, std::get<AddMaterial>(edit).material);
    }
    {
        auto [want, edit] =
            round_trip<InstanceFields>({{"op", "add_instance"}, {"id", "i"}, {"mesh", "m"}});
        InstanceRecord got;
        copy_added<InstanceFields>(got, std::get<AddInstance>(edit));
        expect_fields<InstanceFields>(want, got);
    }
    {
        auto [want, edit] = round_trip<GroupFields>({{"op", "add_group"}, {"id", "g"}});
        GroupRecord got;
        copy_added<GroupFields>(got, std::get<AddGroup>(edit));
        expect_fields<GroupFields>(want, got);
    }
}

TEST(FieldJson, EveryFieldAnUpdateOpTakesReadsBackAsWritten) {
    {
        auto [want, edit] = round_trip<LightFields>({{"op", "update_light"}, {"light", "l"}});
        expect_fields<LightFields>(want, std::get<UpdateLight>(edit));
    }
    {
        auto [want, edit] =
            round_trip<MaterialFields>({{"op", "update_material"}, {"material", "m"}});
        expect_fields<MaterialFields>(want, std::get<UpdateMaterial>(edit));
    }
    {
        auto [want, edit] =
            round_trip<InstanceFields>({{"op", "update_instance"}, {"instance", "i"}});
        expect_fields<InstanceFields>(want, std::get<UpdateInstance>(edit));
    }
    {
        auto [want, edit] = round_trip<GroupFields>({{"op", "update_group"}, {"group", "g"}});
        expect_fields<GroupFields>(want, std::get<UpdateGroup>(edit));
    }
    {
        auto [want, edit] = round_trip<CameraFields>({{"op", "set_camera"}});
        expect_fields<CameraFields>(want, std::get<SetCamera>(edit));
    }
    {
        auto [want, edit] = round_trip<LightingFields>({{"op", "set_lighting"}});
        expect_fields<LightingFields>(want, std::get<SetLighting>(edit));
    }
}

TEST(FieldJson, TheSchemaDescribesEveryFieldWithItsRangeAndDefault) {
    const OrderedJson& light = edit_batch_schema()["$defs"]["add_light"]["properties"];
    EXPECT_EQ(light["intensity"]["minimum"], 0.0);
    EXPECT_EQ(light["intensity"]["maximum"], 1e12);
    EXPECT_EQ(light["intensity"]["default"], 10.0);
    EXPECT_EQ(light["angle_deg"]["exclusiveMinimum"], 0.0);
    EXPECT_EQ(light["type"]["default"], "point");
    EXPECT_FALSE(light["intensity"]["description"].get<std::string>().empty());
    const OrderedJson& update = edit_batch_schema()["$defs"]["update_light"]["properties"];
    EXPECT_FALSE(update["intensity"].contains("default")) << "absent means unchanged there";
    const std::string table = fields_markdown<LightFields>();
    EXPECT_NE(table.find("| `intensity` | number | `10` | [0, 1e12] | no BVH work |"),
              std::string::npos)
        << table;
    EXPECT_NE(fields_markdown<InstanceFields>().find("| `transform` | transform | identity |  | "
                                                     "TLAS update |"),
              std::string::npos)
        << fields_markdown<InstanceFields>();
}

}  // namespace
}  // namespace strata::protocol
