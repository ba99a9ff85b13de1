// Scene-wide ops: mark_dirty, set_camera, set_lighting, set_time, clear.

#include "protocol/edit_schema.h"
#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

Edit parse_mark_dirty(OpFields& f) {
    static const MemberRule MESH_TARGET =
        schema_members("/$defs/mark_dirty/properties/target/oneOf/1");
    FieldReader& r = f.reader();
    MarkDirty e;
    const Json& target = f.at("target");
    const std::string tp = f.pointer("target");
    if (target.is_object()) {
        r.expect_object(target, tp, MESH_TARGET);
        e.mesh = r.id(r.required(target, tp, "mesh"), child(tp, "mesh"));
    } else if (!(target.is_string() && target.get_ref<const std::string&>() == "tlas")) {
        r.schema_error(tp, "expected \"tlas\" or {\"mesh\": id}");
    }
    e.action = r.choice(f.at("action"), f.pointer("action"), {"refit", "rebuild"}) == 0
                   ? DirtyAction::Refit
                   : DirtyAction::Rebuild;
    return e;
}

Edit parse_set_camera(OpFields& f) {
    SetCamera e;
    read_updates<CameraFields>(f, e);
    return e;
}

Edit parse_set_lighting(OpFields& f) {
    SetLighting e;
    read_updates<LightingFields>(f, e);
    return e;
}

Edit parse_set_time(OpFields& f) {
    SetTime e;
    read_updates<TimelineFields>(f, e);
    return e;
}

Edit parse_clear(OpFields&) {
    return Clear{};
}

constexpr EditOp OPS[] = {
    {"mark_dirty",
     "Asks the next commit to refit or rebuild one mesh's BLAS, or to update or rebuild the TLAS.",
     R"json({
  "type": "object",
  "properties": {
    "target": {
      "oneOf": [
        {"const": "tlas"},
        {
          "type": "object",
          "properties": {"mesh": {"$ref": "#/$defs/id"}},
          "required": ["mesh"],
          "additionalProperties": false
        }
      ]
    },
    "action": {"enum": ["refit", "rebuild"]}
  },
  "required": ["target", "action"],
  "additionalProperties": false
})json",
     parse_mark_dirty, edit_kinds<MarkDirty>()},
    {"set_camera", "Changes some of the camera's eye, target, up and vertical field of view.",
     R"json({
  "type": "object",
  "additionalProperties": false
})json",
     parse_set_camera, edit_kinds<SetCamera>(), field_properties<CameraFields, false>},
    {"set_lighting",
     "Changes some of the sun's direction and colour and the sky's colour and intensity.",
     R"json({
  "type": "object",
  "additionalProperties": false
})json",
     parse_set_lighting, edit_kinds<SetLighting>(), field_properties<LightingFields, false>},
    {"set_time",
     "Sets the scene's time (and the frame's duration): the animated instances move to it, at "
     "the cost of a TLAS update of those alone.",
     R"json({
  "type": "object",
  "additionalProperties": false
})json",
     parse_set_time, edit_kinds<SetTime>(), field_properties<TimelineFields, false>},
    {"clear",
     "Removes every mesh, instance, material, texture, group and light and resets camera, "
     "lighting and timeline.",
     R"json({"type": "object", "additionalProperties": false})json", parse_clear,
     edit_kinds<Clear>()},
};

}  // namespace

std::span<const EditOp> scene_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
