#include "protocol/edit_schema.h"

#include "engine/core/check.h"
#include "protocol/edit_ops.h"

namespace strata::protocol {

namespace {

/// Everything but the ops: the batch envelope.
constexpr std::string_view ENVELOPE = R"json({
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "$id": "https://strata.dev/schemas/edit-batch.schema.json",
  "title": "Strata edit batch",
  "description": "The body of POST /v1/edits. Structural rules only: value rules (finite float32 numbers, array lengths that are multiples of 3, decoded base64 lengths that are multiples of 12 bytes, a 4x4 transform's last row 0 0 0 1) and rules against the scene (ids that exist, ...) answer 422 and are described in protocol/README.md.",
  "type": "object",
  "properties": {
    "edits": {"type": "array", "items": {"$ref": "#/$defs/edit"}},
    "message": {"$ref": "#/$defs/text", "description": "a note kept with the version in GET /v1/history"}
  },
  "required": ["edits"],
  "additionalProperties": false
})json";

/// The definitions ops share. The limits here are MAX_ID_LENGTH, MAX_SPHERE_SEGMENTS and
/// MAX_PLANE_SUBDIVISIONS (tests/protocol/edit_ops_test.cpp holds them equal).
constexpr std::string_view SHARED_DEFS = R"json({
  "id": {"type": "string", "minLength": 1, "maxLength": 256,
         "pattern": "^[^\\u0000-\\u001F\\u007F-\\u009F\\u2028\\u2029]*$"},
  "text": {"type": "string", "maxLength": 1024,
           "pattern": "^[^\\u0000-\\u001F\\u007F-\\u009F\\u2028\\u2029]*$",
           "description": "free text: UTF-8 without control characters, at most 1024 bytes"},
  "u32": {"type": "integer", "minimum": 0, "maximum": 4294967295},
  "vec3": {"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3},
  "vec4": {"type": "array", "items": {"type": "number"}, "minItems": 4, "maxItems": 4},
  "positions": {
    "type": "array",
    "items": {"type": "number"},
    "description": "x y z per vertex, flat"
  },
  "indices": {
    "type": "array",
    "items": {"$ref": "#/$defs/u32"},
    "description": "three vertex indices per triangle, flat"
  },
  "radii": {
    "type": "array",
    "items": {"type": "number"},
    "description": "one radius per vertex (> 0): a points mesh's spheres, a curve mesh's thickness at each control vertex"
  },
  "strands": {
    "type": "array",
    "items": {"$ref": "#/$defs/u32"},
    "minItems": 1,
    "description": "a curve mesh's topology: the control vertices of each strand, in vertex order (they add up to the vertex count)"
  },
  "normals": {
    "type": "array",
    "items": {"type": "number"},
    "description": "x y z per vertex, flat (non-zero; normalised when shading)"
  },
  "uvs": {
    "type": "array",
    "items": {"type": "number"},
    "description": "u v per vertex, flat"
  },
  "tangents": {
    "type": "array",
    "items": {"type": "number"},
    "description": "x y z w per vertex, flat: the tangent (non-zero) and w, the bitangent's sign (+1 or -1), glTF's convention; without them, normal maps use tangents the server makes (MikkTSpace convention)"
  },
  "base64": {
    "type": "string",
    "pattern": "^(?:[A-Za-z0-9+/]{4})*(?:[A-Za-z0-9+/]{2}==|[A-Za-z0-9+/]{3}=)?$",
    "description": "RFC 4648 base64 of little-endian float32 (positions, normals) or uint32 (indices) triples, float32 pairs (uvs) or quadruples (tangents)"
  },
  "transforms_base64": {
    "type": "string",
    "pattern": "^(?:[A-Za-z0-9+/]{4})*(?:[A-Za-z0-9+/]{2}==|[A-Za-z0-9+/]{3}=)?$",
    "description": "RFC 4648 base64 of little-endian float32 3x4 row-major transforms, 48 bytes per item"
  },
  "bulk_ids": {
    "oneOf": [
      {"type": "array", "items": {"$ref": "#/$defs/id"}},
      {
        "type": "object",
        "properties": {
          "prefix": {"type": "string", "maxLength": 256},
          "first": {"type": "integer", "minimum": 0, "maximum": 9007199254740992},
          "count": {"type": "integer", "minimum": 0, "maximum": 16777216}
        },
        "required": ["count"],
        "additionalProperties": false,
        "description": "prefix followed by the decimal numbers first .. first + count - 1"
      }
    ],
    "description": "the ids of a bulk edit's items, at most 16777216"
  },
  "bulk_transforms": {
    "oneOf": [
      {"type": "array", "items": {"type": "number"},
       "description": "flat: 12 numbers per item, each a 3x4 row-major transform"},
      {"type": "array", "items": {"$ref": "#/$defs/transform"}, "minItems": 1,
       "description": "one transform per item"}
    ]
  },
  "id_or_ids": {
    "oneOf": [{"$ref": "#/$defs/id"}, {"type": "array", "items": {"$ref": "#/$defs/id"}}],
    "description": "one id for every item, or one per item"
  },
  "image_base64": {
    "type": "string",
    "pattern": "^(?:[A-Za-z0-9+/]{4})*(?:[A-Za-z0-9+/]{2}==|[A-Za-z0-9+/]{3}=)?$",
    "description": "RFC 4648 base64 of a PNG or JPEG file"
  },
  "transform": {
    "oneOf": [
      {
        "type": "array",
        "items": {"type": "number"},
        "minItems": 12,
        "maxItems": 12,
        "description": "3x4 row-major"
      },
      {
        "type": "array",
        "items": {"type": "number"},
        "minItems": 16,
        "maxItems": 16,
        "description": "4x4 row-major; the last row must be 0 0 0 1"
      },
      {
        "type": "object",
        "properties": {
          "translate": {"$ref": "#/$defs/vec3"},
          "rotate_deg": {"$ref": "#/$defs/vec3"},
          "quaternion": {"$ref": "#/$defs/vec4"},
          "scale": {"oneOf": [{"type": "number"}, {"$ref": "#/$defs/vec3"}]}
        },
        "additionalProperties": false,
        "not": {"required": ["rotate_deg", "quaternion"]},
        "description": "translate * rotate * scale; rotate_deg applies X, then Y, then Z"
      }
    ]
  },
  "keyframe": {
    "type": "object",
    "properties": {
      "time": {"type": "number",
               "description": "scene time in seconds; increasing along an animation"},
      "transform": {"$ref": "#/$defs/transform"}
    },
    "required": ["time", "transform"],
    "additionalProperties": false,
    "description": "an instance's transform (relative to its parent) at one scene time"
  },
  "sampler": {
    "type": "object",
    "properties": {
      "wrap": {"enum": ["repeat", "clamp", "mirror"]},
      "filter": {"enum": ["bilinear", "nearest"]}
    },
    "additionalProperties": false,
    "description": "how the material's textures are read outside [0, 1) and between texels (default repeat, bilinear)"
  },
  "build": {
    "type": "object",
    "properties": {
      "prefer": {"enum": ["fast_trace", "fast_build"]},
      "allow_refit": {"type": "boolean"},
      "compact": {"type": "boolean", "description": "build the BLAS at full size, measure it, then rebuild it in Embree's compact layout (less memory, slower traces; the report shows both sizes)"}
    },
    "additionalProperties": false
  },
  "shape": {
    "oneOf": [
      {
        "type": "object",
        "properties": {
          "type": {"const": "sphere"},
          "radius": {"type": "number", "exclusiveMinimum": 0},
          "segments": {"type": "integer", "minimum": 3, "maximum": 2048}
        },
        "required": ["type"],
        "additionalProperties": false
      },
      {
        "type": "object",
        "properties": {
          "type": {"const": "box"},
          "size": {
            "oneOf": [
              {"type": "number", "exclusiveMinimum": 0},
              {
                "type": "array",
                "items": {"type": "number", "exclusiveMinimum": 0},
                "minItems": 3,
                "maxItems": 3
              }
            ]
          }
        },
        "required": ["type"],
        "additionalProperties": false
      },
      {
        "type": "object",
        "properties": {
          "type": {"const": "plane"},
          "size": {
            "oneOf": [
              {"type": "number", "exclusiveMinimum": 0},
              {
                "type": "array",
                "items": {"type": "number", "exclusiveMinimum": 0},
                "minItems": 2,
                "maxItems": 2
              }
            ]
          },
          "subdivisions": {
            "type": "array",
            "items": {"type": "integer", "minimum": 1, "maximum": 1024},
            "minItems": 2,
            "maxItems": 2
          }
        },
        "required": ["type"],
        "additionalProperties": false
      }
    ]
  }
})json";

OrderedJson parse_literal(std::string_view text) {
    OrderedJson j = OrderedJson::parse(text, nullptr, /*allow_exceptions=*/false);
    STRATA_CHECK(j.is_object());
    return j;
}

/// `$defs/edit`: an object whose `op` is one of the ops, checked against that op's definition.
OrderedJson dispatch_def() {
    OrderedJson names = OrderedJson::array();
    OrderedJson cases = OrderedJson::array();
    for (const EditOp& op : edit_ops()) {
        names.push_back(op.name);
        cases.push_back(
            {{"if", {{"properties", {{"op", {{"const", op.name}}}}}, {"required", {"op"}}}},
             {"then", {{"$ref", "#/$defs/" + std::string(op.name)}}}});
    }
    return {{"type", "object"},
            {"required", {"op"}},
            {"properties", {{"op", {{"enum", names}}}}},
            {"allOf", cases}};
}

/// An op's definition: its fragment with the table's doc as `description` and `op` as the first
/// property and required member.
OrderedJson op_def(const EditOp& op) {
    const OrderedJson fragment = parse_literal(op.schema);
    OrderedJson properties = {{"op", {{"const", op.name}}}};
    if (const auto p = fragment.find("properties"); p != fragment.end()) {
        for (const auto& [key, value] : p->items()) properties[key] = value;
    }
    if (op.fields) {
        const OrderedJson fields = op.fields();
        for (const auto& [key, value] : fields.items()) {
            STRATA_CHECK(!properties.contains(key));
            properties[key] = value;
        }
    }
    OrderedJson required = OrderedJson::array({"op"});
    if (const auto r = fragment.find("required"); r != fragment.end()) {
        for (const OrderedJson& key : *r) required.push_back(key);
    }
    OrderedJson def = {{"type", fragment.value("type", "object")},
                       {"description", op.doc},
                       {"properties", std::move(properties)},
                       {"required", std::move(required)}};
    for (const auto& [key, value] : fragment.items()) {
        if (key != "type" && key != "properties" && key != "required") def[key] = value;
    }
    return def;
}

OrderedJson build_schema() {
    OrderedJson schema = parse_literal(ENVELOPE);
    OrderedJson defs = parse_literal(SHARED_DEFS);
    defs["edit"] = dispatch_def();
    for (const EditOp& op : edit_ops()) {
        STRATA_CHECK(!defs.contains(op.name));
        defs[std::string(op.name)] = op_def(op);
    }
    schema["$defs"] = std::move(defs);
    return schema;
}

}  // namespace

const OrderedJson& edit_batch_schema() {
    static const OrderedJson schema = build_schema();
    return schema;
}

std::string edit_batch_schema_text() {
    return edit_batch_schema().dump(2) + "\n";
}

MemberRule schema_members(std::string_view pointer) {
    const OrderedJson::json_pointer at{std::string(pointer)};
    const OrderedJson& schema = edit_batch_schema();
    STRATA_CHECK(schema.contains(at));
    const OrderedJson& object = schema.at(at);
    STRATA_CHECK(object.value("type", "") == "object");
    MemberRule rule;
    if (const auto p = object.find("properties"); p != object.end()) {
        for (const auto& [key, value] : p->items()) rule.allowed.push_back(key);
    }
    if (const auto r = object.find("required"); r != object.end()) {
        for (const OrderedJson& key : *r) rule.required.push_back(key.get<std::string>());
    }
    return rule;
}

}  // namespace strata::protocol
