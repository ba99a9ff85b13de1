// Material ops: add_material, update_material.

#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

/// The values both ops carry; `M` is a whole Material (add) or an UpdateMaterial of optionals.
template <class M>
void read_material_values(OpFields& f, M& m) {
    f.read("base_color", m.base_color);
    f.read("roughness", m.roughness);
    f.read("metallic", m.metallic);
    f.read("emission", m.emission);
}

Edit parse_add_material(OpFields& f) {
    AddMaterial e;
    e.id = f.id("id");
    read_material_values(f, e.material);
    return e;
}

Edit parse_update_material(OpFields& f) {
    UpdateMaterial e;
    e.material = f.id("material");
    read_material_values(f, e);
    return e;
}

constexpr EditOp OPS[] = {
    {"add_material", "A new material: base colour, roughness, metallic and emission.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "base_color": {"$ref": "#/$defs/vec3"},
    "roughness": {"type": "number"},
    "metallic": {"type": "number"},
    "emission": {"$ref": "#/$defs/vec3"}
  },
  "required": ["id"],
  "additionalProperties": false
})json",
     parse_add_material, edit_kinds<AddMaterial>()},
    {"update_material", "Changes some of a material's values; the others keep theirs.",
     R"json({
  "type": "object",
  "properties": {
    "material": {"$ref": "#/$defs/id"},
    "base_color": {"$ref": "#/$defs/vec3"},
    "roughness": {"type": "number"},
    "metallic": {"type": "number"},
    "emission": {"$ref": "#/$defs/vec3"}
  },
  "required": ["material"],
  "additionalProperties": false
})json",
     parse_update_material, edit_kinds<UpdateMaterial>()},
};

}  // namespace

std::span<const EditOp> material_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
