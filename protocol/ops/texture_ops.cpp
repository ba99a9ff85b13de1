// Texture ops: add_texture, remove_texture. The image travels as base64 PNG or JPEG bytes; the
// engine decodes it when the edit is applied (engine/image/texture_decode.h).

#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

Edit parse_add_texture(OpFields& f) {
    AddTexture e;
    e.id = f.id("id");
    e.data = f.reader().bytes_b64(f.at("data"), f.pointer("data"));
    read_added<TextureFields>(f, e);
    return e;
}

Edit parse_remove_texture(OpFields& f) {
    RemoveTexture e;
    e.texture = f.id("texture");
    return e;
}

constexpr EditOp OPS[] = {
    {"add_texture",
     "A texture from PNG or JPEG bytes (base64), decoded to linear RGB (from sRGB, or as stored "
     "for color_space linear) with its alpha; materials name it in their texture slots.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "data": {"$ref": "#/$defs/image_base64"}
  },
  "required": ["id", "data"],
  "additionalProperties": false
})json",
     parse_add_texture, edit_kinds<AddTexture>(), field_properties<TextureFields, true>},
    {"remove_texture", "Removes a texture; refused (in-use) while a material refers to it.",
     R"json({
  "type": "object",
  "properties": {
    "texture": {"$ref": "#/$defs/id"}
  },
  "required": ["texture"],
  "additionalProperties": false
})json",
     parse_remove_texture, edit_kinds<RemoveTexture>()},
};

}  // namespace

std::span<const EditOp> texture_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
