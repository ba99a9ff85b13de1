// Material ops: add_material, update_material (with their textures, one per TEXTURE_SLOTS entry,
// and the sampler that reads them), remove_material.

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
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS)
        f.read(slot.field, e.textures[slot_index(slot.slot)]);
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
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        const Json* t = f.get(slot.field);
        if (!t) continue;
        e.textures[slot_index(slot.slot)] =
            t->is_null() ? std::optional<std::string>() : f.reader().id(*t, f.pointer(slot.field));
    }
    read_sampler(f, e.wrap, e.filter);
    return e;
}

Edit parse_remove_material(OpFields& f) {
    RemoveMaterial e;
    e.material = f.id("material");
    return e;
}

/// The material's fields and, after them, one texture id per slot (`Added`: an id; else an id,
/// or null for none).
template <bool Added>
OrderedJson material_properties() {
    OrderedJson properties = field_properties<MaterialFields, Added>();
    const OrderedJson id = {{"$ref", "#/$defs/id"}};
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        OrderedJson p = Added ? id : OrderedJson{{"oneOf", {id, {{"type", "null"}}}}};
        p["description"] = std::string(slot.doc);
        properties[std::string(slot.field)] = std::move(p);
    }
    return properties;
}

constexpr EditOp OPS[] = {
    {"add_material",
     "A new material (glTF 2.0's metallic-roughness model): base colour and alpha, roughness, "
     "metallic, emission, each optionally times a texture, a normal map, occlusion, alpha mode "
     "and unlit.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "sampler": {"$ref": "#/$defs/sampler"}
  },
  "required": ["id"],
  "additionalProperties": false
})json",
     parse_add_material, edit_kinds<AddMaterial>(), material_properties<true>},
    {"update_material", "Changes some of a material's values; the others keep theirs.",
     R"json({
  "type": "object",
  "properties": {
    "material": {"$ref": "#/$defs/id"},
    "sampler": {"$ref": "#/$defs/sampler"}
  },
  "required": ["material"],
  "additionalProperties": false
})json",
     parse_update_material, edit_kinds<UpdateMaterial>(), material_properties<false>},
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
