// The op table (protocol/edit_ops.h): every entry complete, every Edit alternative produced by
// some op, and each op's members checked from its schema, the only place they are listed.

#include <set>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "protocol/edit_ops.h"
#include "protocol/edit_schema.h"

namespace strata::protocol {
namespace {

constexpr EditKinds ALL_KINDS = (EditKinds{1} << std::variant_size_v<Edit>)-1;

Problem fails(const Json& edit) {
    auto r = parse_edit_batch(Json{{"edits", Json::array({edit})}});
    EXPECT_FALSE(r.has_value()) << edit.dump();
    return r.has_value() ? Problem{} : r.error();
}

TEST(EditOps, EveryEntryHasANameADocAParserAndKindsOfEdit) {
    std::set<std::string_view> names;
    for (const EditOp& op : edit_ops()) {
        SCOPED_TRACE(op.name);
        EXPECT_TRUE(names.insert(op.name).second) << "two ops named " << op.name;
        EXPECT_THAT(std::string(op.name), ::testing::MatchesRegex("[a-z]+(_[a-z]+)*"));
        EXPECT_THAT(std::string(op.doc), ::testing::MatchesRegex("[A-Z][^\n|]*\\."));
        EXPECT_NE(op.parse, nullptr);
        EXPECT_NE(op.produces, 0u);
        EXPECT_EQ(op.produces & ~ALL_KINDS, 0u);
        EXPECT_EQ(find_edit_op(op.name), &op);
    }
    EXPECT_EQ(find_edit_op("no_such_op"), nullptr);
}

TEST(EditOps, EveryFragmentIsAClosedObjectSchemaThatLeavesOpAndDescriptionToTheTable) {
    for (const EditOp& op : edit_ops()) {
        SCOPED_TRACE(op.name);
        const OrderedJson fragment = OrderedJson::parse(op.schema, nullptr, false);
        ASSERT_TRUE(fragment.is_object()) << "the fragment is not a JSON object";
        EXPECT_EQ(fragment.value("type", ""), "object");
        EXPECT_EQ(fragment.value("additionalProperties", true), false);
        EXPECT_FALSE(fragment.contains("description"));
        EXPECT_FALSE(fragment.value("properties", OrderedJson::object()).contains("op"));
        for (const OrderedJson& key : fragment.value("required", OrderedJson::array()))
            EXPECT_TRUE(fragment["properties"].contains(key.get<std::string>())) << key;
    }
}

TEST(EditOps, TheSchemaDefinesEachOpWithItsNameAsOpConstAndItsDocAsDescription) {
    const OrderedJson& defs = edit_batch_schema()["$defs"];
    std::vector<std::string> dispatched;
    for (const OrderedJson& c : defs["edit"]["allOf"])
        dispatched.push_back(c["if"]["properties"]["op"]["const"].get<std::string>());
    std::vector<std::string> names;
    for (const EditOp& op : edit_ops()) {
        SCOPED_TRACE(op.name);
        names.emplace_back(op.name);
        const OrderedJson& def = defs[std::string(op.name)];
        EXPECT_EQ(def["properties"]["op"]["const"], std::string(op.name));
        EXPECT_EQ(def["required"][0], "op");
        EXPECT_EQ(def["description"], std::string(op.doc));
    }
    EXPECT_EQ(defs["edit"]["properties"]["op"]["enum"], OrderedJson(names));
    EXPECT_EQ(dispatched, names);
}

TEST(EditOps, EveryEditAlternativeIsProducedBySomeOp) {
    EditKinds produced = 0;
    for (const EditOp& op : edit_ops()) produced |= op.produces;
    for (std::size_t i = 0; i < std::variant_size_v<Edit>; ++i)
        EXPECT_TRUE(produced & (EditKinds{1} << i)) << "no op produces Edit alternative " << i;
    EXPECT_EQ(find_edit_op("update_mesh")->produces,
              (edit_kinds<UpdateMeshPositions, UpdateMeshVertices, ReplaceMeshTopology>()));
}

TEST(EditOps, EachOpAcceptsExactlyTheMembersItsSchemaDeclares) {
    for (const EditOp& op : edit_ops()) {
        SCOPED_TRACE(op.name);
        const MemberRule& members = edit_op_members(op);
        std::vector<std::string> declared;
        for (const auto& [key, value] :
             edit_batch_schema()["$defs"][std::string(op.name)]["properties"].items())
            declared.push_back(key);
        EXPECT_EQ(members.allowed, declared);

        const Problem e = fails({{"op", std::string(op.name)}, {"not_a_member", 1}});
        EXPECT_EQ(e.type, ProblemType::InvalidRequest);
        EXPECT_EQ(e.pointer, "/edits/0/not_a_member");
        for (const std::string& key : declared) EXPECT_THAT(e.detail, ::testing::HasSubstr(key));
    }
}

TEST(EditOps, EachRequiredMemberOfTheSchemaIsRequiredByTheParser) {
    for (const EditOp& op : edit_ops()) {
        SCOPED_TRACE(op.name);
        for (const std::string& key : edit_op_members(op).required) {
            if (key == "op") continue;
            // Every other member present, with a value of the wrong type: the missing one is
            // still the first problem reported.
            Json edit = {{"op", std::string(op.name)}};
            for (const std::string& other : edit_op_members(op).required)
                if (other != key && other != "op") edit[other] = Json::array({Json::object()});
            const Problem e = fails(edit);
            EXPECT_EQ(e.pointer, "/edits/0/" + key) << e.detail;
            EXPECT_THAT(e.detail, ::testing::HasSubstr("missing required member '" + key + "'"));
        }
    }
}

TEST(EditOps, UnknownOpsAreRefusedWithTheListOfOps) {
    const Problem e = fails({{"op", "add_meshes"}});
    EXPECT_EQ(e.pointer, "/edits/0/op");
    std::string list;
    for (const EditOp& op : edit_ops()) list += (list.empty() ? "" : ", ") + std::string(op.name);
    EXPECT_THAT(e.detail, ::testing::HasSubstr("unknown op 'add_meshes' (ops: " + list + ")"));
    EXPECT_THAT(fails({{"op", 3}}).detail, ::testing::HasSubstr("(ops: " + list + ")"));
}

TEST(EditSchema, LimitsAreTheParserConstants) {
    const OrderedJson& defs = edit_batch_schema()["$defs"];
    EXPECT_EQ(defs["id"]["maxLength"], MAX_ID_LENGTH);
    EXPECT_EQ(defs["shape"]["oneOf"][0]["properties"]["segments"]["maximum"], MAX_SPHERE_SEGMENTS);
    EXPECT_EQ(defs["shape"]["oneOf"][2]["properties"]["subdivisions"]["items"]["maximum"],
              MAX_PLANE_SUBDIVISIONS);
}

void expect_refs_resolve(const OrderedJson& schema, const OrderedJson& node) {
    if (node.is_object()) {
        if (const auto ref = node.find("$ref"); ref != node.end()) {
            const std::string target = ref->get<std::string>();
            ASSERT_EQ(target.rfind("#/", 0), 0u) << target;
            EXPECT_TRUE(schema.contains(OrderedJson::json_pointer(target.substr(1)))) << target;
        }
    }
    if (node.is_structured()) {
        for (const OrderedJson& child_node : node) expect_refs_resolve(schema, child_node);
    }
}

TEST(EditSchema, EveryReferenceResolvesAndEverySharedDefinitionIsUsed) {
    const OrderedJson& schema = edit_batch_schema();
    expect_refs_resolve(schema, schema);
    const std::string text = schema.dump();
    for (const auto& [name, def] : schema["$defs"].items())
        EXPECT_NE(text.find("\"#/$defs/" + name + "\""), std::string::npos) << name;
}

TEST(EditSchema, NestedObjectsTakeTheirMembersFromTheSchema) {
    EXPECT_EQ(schema_members("/$defs/build").allowed,
              (std::vector<std::string>{"prefer", "allow_refit", "compact"}));
    EXPECT_EQ(schema_members("").required, std::vector<std::string>{"edits"});
    const Problem e = fails({{"op", "add_mesh"},
                             {"id", "m"},
                             {"shape", {{"type", "box"}, {"size", 1}, {"radius", 2}}}});
    EXPECT_EQ(e.pointer, "/edits/0/shape/radius");
    EXPECT_THAT(e.detail, ::testing::HasSubstr("(allowed: type, size)"));
}

}  // namespace
}  // namespace strata::protocol
