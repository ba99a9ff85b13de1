// Light ops: add_light, update_light, remove_light.

#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

Edit parse_add_light(OpFields& f) {
    AddLight e;
    e.id = f.id("id");
    read_added<LightFields>(f, e.light);
    return e;
}

Edit parse_update_light(OpFields& f) {
    UpdateLight e;
    e.light = f.id("light");
    read_updates<LightFields>(f, e);
    return e;
}

Edit parse_remove_light(OpFields& f) {
    return RemoveLight{f.id("light")};
}

constexpr EditOp OPS[] = {
    {"add_light",
     "A new point, spot or rect light (sampled by next-event estimation; no BVH work).",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"}
  },
  "required": ["id"],
  "additionalProperties": false
})json",
     parse_add_light, edit_kinds<AddLight>(), field_properties<LightFields, true>},
    {"update_light", "Changes some of a light's values (its type too); the others keep theirs.",
     R"json({
  "type": "object",
  "properties": {
    "light": {"$ref": "#/$defs/id"}
  },
  "required": ["light"],
  "additionalProperties": false
})json",
     parse_update_light, edit_kinds<UpdateLight>(), field_properties<LightFields, false>},
    {"remove_light", "Removes a light.",
     R"json({
  "type": "object",
  "properties": {"light": {"$ref": "#/$defs/id"}},
  "required": ["light"],
  "additionalProperties": false
})json",
     parse_remove_light, edit_kinds<RemoveLight>()},
};

}  // namespace

std::span<const EditOp> light_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
