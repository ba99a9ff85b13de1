// Instance ops: add_instance, update_instance, set_transform, remove_instance.

#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

/// The members add_instance and update_instance share besides `material` (plain values in one,
/// optionals in the other).
template <class E>
void read_instance_values(OpFields& f, E& e) {
    f.read("transform", e.transform);
    f.read("visible", e.visible);
    f.read("mask", e.mask);
    f.read("user_id", e.user_id);
}

Edit parse_add_instance(OpFields& f) {
    AddInstance e;
    e.id = f.id("id");
    e.mesh = f.id("mesh");
    f.read("material", e.material);
    read_instance_values(f, e);
    return e;
}

Edit parse_update_instance(OpFields& f) {
    UpdateInstance e;
    e.instance = f.id("instance");
    if (const Json* m = f.get("material")) {
        // null: back to the mesh's default material.
        e.material =
            m->is_null() ? std::optional<std::string>() : f.reader().id(*m, f.pointer("material"));
    }
    read_instance_values(f, e);
    return e;
}

Edit parse_set_transform(OpFields& f) {
    SetTransform e;
    e.instance = f.id("instance");
    f.read("transform", e.transform);
    return e;
}

Edit parse_remove_instance(OpFields& f) {
    return RemoveInstance{f.id("instance")};
}

constexpr EditOp OPS[] = {
    {"add_instance",
     "A new instance of a mesh: transform, material, visibility, ray mask and user id.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "mesh": {"$ref": "#/$defs/id"},
    "material": {"$ref": "#/$defs/id"},
    "transform": {"$ref": "#/$defs/transform"},
    "visible": {"type": "boolean"},
    "mask": {"$ref": "#/$defs/u32"},
    "user_id": {"$ref": "#/$defs/u32"}
  },
  "required": ["id", "mesh"],
  "additionalProperties": false
})json",
     parse_add_instance, edit_kinds<AddInstance>()},
    {"update_instance",
     "Changes some of an instance's fields; material null reverts to the mesh's default.",
     R"json({
  "type": "object",
  "properties": {
    "instance": {"$ref": "#/$defs/id"},
    "material": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]},
    "transform": {"$ref": "#/$defs/transform"},
    "visible": {"type": "boolean"},
    "mask": {"$ref": "#/$defs/u32"},
    "user_id": {"$ref": "#/$defs/u32"}
  },
  "required": ["instance"],
  "additionalProperties": false
})json",
     parse_update_instance, edit_kinds<UpdateInstance>()},
    {"set_transform", "Replaces an instance's transform.",
     R"json({
  "type": "object",
  "properties": {
    "instance": {"$ref": "#/$defs/id"},
    "transform": {"$ref": "#/$defs/transform"}
  },
  "required": ["instance", "transform"],
  "additionalProperties": false
})json",
     parse_set_transform, edit_kinds<SetTransform>()},
    {"remove_instance", "Removes an instance.",
     R"json({
  "type": "object",
  "properties": {"instance": {"$ref": "#/$defs/id"}},
  "required": ["instance"],
  "additionalProperties": false
})json",
     parse_remove_instance, edit_kinds<RemoveInstance>()},
};

}  // namespace

std::span<const EditOp> instance_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
