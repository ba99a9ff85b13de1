// Instance ops: add_instance, update_instance, set_transform, remove_instance.

#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

Edit parse_add_instance(OpFields& f) {
    AddInstance e;
    e.id = f.id("id");
    e.mesh = f.id("mesh");
    f.read("material", e.material);
    read_added<InstanceFields>(f, e);
    std::optional<std::optional<std::string>> parent;
    read_parent(f, parent);
    if (parent) e.parent = *parent;
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
    read_updates<InstanceFields>(f, e);
    read_parent(f, e.parent);
    return e;
}

/// `group` in place of `instance` moves a group: the engine's update_group with a transform.
Edit parse_set_transform(OpFields& f) {
    if (f.get("group")) {
        if (f.get("instance"))
            f.reader().schema_error(f.pointer("group"), "give instance or group, not both");
        UpdateGroup g;
        g.group = f.id("group");
        Affine t;
        f.read("transform", t);
        g.transform = t;
        return g;
    }
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
     "A new instance of a mesh: transform, material, visibility, ray mask, user id and parent "
     "group.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "mesh": {"$ref": "#/$defs/id"},
    "material": {"$ref": "#/$defs/id"},
    "parent": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]}
  },
  "required": ["id", "mesh"],
  "additionalProperties": false
})json",
     parse_add_instance, edit_kinds<AddInstance>(), field_properties<InstanceFields, true>},
    {"update_instance",
     "Changes some of an instance's fields; material null reverts to the mesh's default, parent "
     "null moves it to the root.",
     R"json({
  "type": "object",
  "properties": {
    "instance": {"$ref": "#/$defs/id"},
    "material": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]},
    "parent": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]}
  },
  "required": ["instance"],
  "additionalProperties": false
})json",
     parse_update_instance, edit_kinds<UpdateInstance>(), field_properties<InstanceFields, false>},
    {"set_transform",
     "Replaces the transform of an instance, or of a group (`group` in place of `instance`).",
     R"json({
  "type": "object",
  "properties": {
    "instance": {"$ref": "#/$defs/id"},
    "group": {"$ref": "#/$defs/id"},
    "transform": {"$ref": "#/$defs/transform"}
  },
  "required": ["transform"],
  "oneOf": [{"required": ["instance"]}, {"required": ["group"]}],
  "additionalProperties": false
})json",
     parse_set_transform, edit_kinds<SetTransform, UpdateGroup>()},
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
