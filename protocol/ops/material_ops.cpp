// Material ops: add_material, update_material (with a base-colour texture and its sampler),
// remove_material.

#include "protocol/edit_schema.h"
#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

/// The `sampler` object: `wrap` and `filter`, each optional.
void read_sampler(OpFields& f, std::optional<TextureWrap>& wrap,
                  std::optional<TextureFilter>& filter) {
    static const MemberRule SAMPLER = schema_members("/$defs/sampler");
    const Json* s = f.get("sampler");
    if (!s) return;
    FieldReader& r = f.reader();
    const std::string ptr = f.pointer("sampler");
    r.expect_object(*s, ptr, SAMPLER);
    if (const Json* w = FieldReader::member(*s, "wrap"))
        wrap = TextureWrap(r.choice(*w, child(ptr, "wrap"), {"repeat", "clamp", "mirror"}));
    if (const Json* fl = FieldReader::member(*s, "filter"))
        filter = TextureFilter(r.choice(*fl, child(ptr, "filter"), {"bilinear", "nearest"}));
}

Edit parse_add_material(OpFields& f) {
    AddMaterial e;
    e.id = f.id("id");
    read_added<MaterialFields>(f, e.material);
    f.read("base_color_texture", e.base_color_texture);
    std::optional<TextureWrap> wrap;
    std::optional<TextureFilter> filter;
    read_sampler(f, wrap, filter);
    if (wrap) e.material.base_color_sampler.wrap = *wrap;
    if (filter) e.material.base_color_sampler.filter = *filter;
    return e;
}

Edit parse_update_material(OpFields& f) {
    UpdateMaterial e;
    e.material = f.id("material");
    read_updates<MaterialFields>(f, e);
    if (const Json* t = f.get("base_color_texture"))
        e.base_color_texture = t->is_null() ? std::optional<std::string>()
                                            : f.reader().id(*t, f.pointer("base_color_texture"));
    read_sampler(f, e.wrap, e.filter);
    return e;
}

Edit parse_remove_material(OpFields& f) {
    RemoveMaterial e;
    e.material = f.id("material");
    return e;
}

constexpr EditOp OPS[] = {
    {"add_material",
     "A new material: base colour (optionally times a texture), roughness, metallic and "
     "emission.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "base_color_texture": {"$ref": "#/$defs/id"},
    "sampler": {"$ref": "#/$defs/sampler"}
  },
  "required": ["id"],
  "additionalProperties": false
})json",
     parse_add_material, edit_kinds<AddMaterial>(), field_properties<MaterialFields, true>},
    {"update_material", "Changes some of a material's values; the others keep theirs.",
     R"json({
  "type": "object",
  "properties": {
    "material": {"$ref": "#/$defs/id"},
    "base_color_texture": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]},
    "sampler": {"$ref": "#/$defs/sampler"}
  },
  "required": ["material"],
  "additionalProperties": false
})json",
     parse_update_material, edit_kinds<UpdateMaterial>(), field_properties<MaterialFields, false>},
    {"remove_material",
     "Removes a material; refused (in-use) while a mesh has it as its default or an instance "
     "overrides with it.",
     R"json({
  "type": "object",
  "properties": {
    "material": {"$ref": "#/$defs/id"}
  },
  "required": ["material"],
  "additionalProperties": false
})json",
     parse_remove_material, edit_kinds<RemoveMaterial>()},
};

}  // namespace

std::span<const EditOp> material_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
