// Group ops: add_group, update_group, remove_group. Groups form the scene graph: an instance or a
// group under a group moves, shows and hides with it.

#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

void read_parent(OpFields& f, std::optional<std::optional<std::string>>& out) {
    const Json* p = f.get("parent");
    if (!p) return;
    out = p->is_null() ? std::optional<std::string>() : f.reader().id(*p, f.pointer("parent"));
}

namespace {

Edit parse_add_group(OpFields& f) {
    AddGroup e;
    e.id = f.id("id");
    std::optional<std::optional<std::string>> parent;
    read_parent(f, parent);
    if (parent) e.parent = *parent;
    read_added<GroupFields>(f, e);
    return e;
}

Edit parse_update_group(OpFields& f) {
    UpdateGroup e;
    e.group = f.id("group");
    read_parent(f, e.parent);
    read_updates<GroupFields>(f, e);
    return e;
}

Edit parse_remove_group(OpFields& f) {
    RemoveGroup e;
    e.group = f.id("group");
    f.read("recursive", e.recursive);
    return e;
}

constexpr EditOp OPS[] = {
    {"add_group",
     "A new group under the root or under `parent`: its transform and visibility apply to every "
     "group and instance below it.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "parent": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]}
  },
  "required": ["id"],
  "additionalProperties": false
})json",
     parse_add_group, edit_kinds<AddGroup>(), field_properties<GroupFields, true>},
    {"update_group",
     "Changes a group's parent (null: the root), transform or visibility; its whole subtree "
     "follows.",
     R"json({
  "type": "object",
  "properties": {
    "group": {"$ref": "#/$defs/id"},
    "parent": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]}
  },
  "required": ["group"],
  "additionalProperties": false
})json",
     parse_update_group, edit_kinds<UpdateGroup>(), field_properties<GroupFields, false>},
    {"remove_group",
     "Removes a group; refused while it has children unless `recursive`, which removes the whole "
     "subtree, instances included.",
     R"json({
  "type": "object",
  "properties": {
    "group": {"$ref": "#/$defs/id"},
    "recursive": {"type": "boolean"}
  },
  "required": ["group"],
  "additionalProperties": false
})json",
     parse_remove_group, edit_kinds<RemoveGroup>()},
};

}  // namespace

std::span<const EditOp> group_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
