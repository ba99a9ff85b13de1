// Light ops: add_light, update_light, remove_light.

#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

/// The values both ops carry; `L` is a whole Light (add) or an UpdateLight of optionals.
template <class L>
void read_light_values(OpFields& f, L& l) {
    if (const Json* type = f.get("type")) {
        const std::size_t k =
            f.reader().choice(*type, f.pointer("type"), {"point", "spot", "rect"});
        l.kind = static_cast<LightKind>(k);
    }
    f.read("position", l.position);
    f.read("direction", l.direction);
    f.read("color", l.color);
    f.read("intensity", l.intensity);
    f.read("angle_deg", l.angle_deg);
    f.read("inner_angle_deg", l.inner_angle_deg);
    f.read("width", l.width);
    f.read("height", l.height);
}

Edit parse_add_light(OpFields& f) {
    AddLight e;
    e.id = f.id("id");
    read_light_values(f, e.light);
    return e;
}

Edit parse_update_light(OpFields& f) {
    UpdateLight e;
    e.light = f.id("light");
    read_light_values(f, e);
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
    "id": {"$ref": "#/$defs/id"},
    "type": {"enum": ["point", "spot", "rect"]},
    "position": {"$ref": "#/$defs/vec3"},
    "direction": {"$ref": "#/$defs/vec3"},
    "color": {"$ref": "#/$defs/vec3"},
    "intensity": {"type": "number"},
    "angle_deg": {"type": "number"},
    "inner_angle_deg": {"type": "number"},
    "width": {"type": "number"},
    "height": {"type": "number"}
  },
  "required": ["id"],
  "additionalProperties": false
})json",
     parse_add_light, edit_kinds<AddLight>()},
    {"update_light", "Changes some of a light's values (its type too); the others keep theirs.",
     R"json({
  "type": "object",
  "properties": {
    "light": {"$ref": "#/$defs/id"},
    "type": {"enum": ["point", "spot", "rect"]},
    "position": {"$ref": "#/$defs/vec3"},
    "direction": {"$ref": "#/$defs/vec3"},
    "color": {"$ref": "#/$defs/vec3"},
    "intensity": {"type": "number"},
    "angle_deg": {"type": "number"},
    "inner_angle_deg": {"type": "number"},
    "width": {"type": "number"},
    "height": {"type": "number"}
  },
  "required": ["light"],
  "additionalProperties": false
})json",
     parse_update_light, edit_kinds<UpdateLight>()},
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
