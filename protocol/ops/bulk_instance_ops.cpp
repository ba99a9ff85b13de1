// Bulk instance ops: add_instances, update_instances, remove_instances. Many instances in one
// edit, with packed arrays: ids listed or numbered from a prefix; transforms as an array of
// transforms, as flat numbers (12 per item) or as base64 little-endian float32 3x4 rows (48 bytes
// per item); mesh and material once or per item.

#include <algorithm>

#include "engine/core/utf8.h"
#include "protocol/json_document.h"
#include "protocol/ops/families.h"
#include "protocol/transform_parser.h"

namespace strata::protocol::ops {

namespace {

/// `ids`: an array of ids, or {"prefix", "first", "count"}.
BulkIds read_ids(OpFields& f) {
    FieldReader& r = f.reader();
    const Json& v = f.at("ids");
    const std::string ptr = f.pointer("ids");
    BulkIds ids;
    if (v.is_object()) {
        r.expect_object(v, ptr, MemberRule{{"prefix", "first", "count"}, {"count"}});
        f.source().ids_range = true;
        if (const Json* p = FieldReader::member(v, "prefix")) {
            ids.prefix = r.text(*p, child(ptr, "prefix"));
            // No id can be longer; refused before any id is made from it.
            if (utf8_length(ids.prefix) > MAX_ID_LENGTH)
                r.schema_error(child(ptr, "prefix"), "prefix is longer than an id may be (" +
                                                         std::to_string(MAX_ID_LENGTH) +
                                                         " code points)");
        }
        if (const Json* first = FieldReader::member(v, "first"))
            ids.first = r.integer(*first, child(ptr, "first"), 0, uint64_t(1) << 53);
        ids.count = r.integer(v.at("count"), child(ptr, "count"), 0, MAX_BULK_ITEMS);
        return ids;
    }
    if (!v.is_array()) r.schema_error(ptr, "expected an array of ids or a range object");
    if (v.size() > MAX_BULK_ITEMS)
        r.record_value_error(ptr,
                             std::to_string(v.size()) + " ids, over the limit of " +
                                 std::to_string(MAX_BULK_ITEMS) + " per bulk edit",
                             ErrorCode::TooLarge);
    ids.list.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) ids.list.push_back(r.id(v[i], child(ptr, i)));
    return ids;
}

/// An id, or an array of ids (one per item), into `out`; absent leaves `out` empty.
void read_id_or_ids(OpFields& f, std::string_view key, std::vector<std::string>& out) {
    const Json* v = f.get(key);
    if (!v) return;
    const std::string ptr = f.pointer(key);
    if (!v->is_array()) {
        out.push_back(f.reader().id(*v, ptr));
        return;
    }
    out.reserve(v->size());
    for (std::size_t i = 0; i < v->size(); ++i)
        out.push_back(f.reader().id((*v)[i], child(ptr, i)));
}

/// `transforms` (flat numbers, 12 per item, or an array of transforms in any form) or
/// `transforms_b64` (float32 3x4 rows).
std::vector<Affine> read_transforms(OpFields& f) {
    FieldReader& r = f.reader();
    const Json* list = f.get("transforms");
    const Json* b64 = f.get("transforms_b64");
    if (list && b64)
        r.schema_error(f.pointer("transforms_b64"), "give transforms or transforms_b64, not both");
    std::vector<Affine> out;
    if (b64) {
        f.source().transforms_b64 = true;
        return r.transforms_b64(*b64, f.pointer("transforms_b64"));
    }
    if (!list) return out;
    const std::string ptr = f.pointer("transforms");
    // Flat numbers, 12 per item (3x4 row-major): long arrays of numbers are packed as they are
    // parsed and cost no JSON values.
    const bool flat =
        is_packed_numbers(*list) || (list->is_array() && !list->empty() && (*list)[0].is_number());
    if (flat) {
        f.source().transforms_flat = true;
        const std::vector<float> numbers = r.floats(*list, ptr);
        if (numbers.size() % 12 != 0)
            r.record_value_error(ptr, "transforms has " + std::to_string(numbers.size()) +
                                          " numbers, not a multiple of 12 (3x4 row-major each)");
        out.resize(numbers.size() / 12);
        for (std::size_t i = 0; i < out.size(); ++i)
            std::copy_n(numbers.begin() + std::ptrdiff_t(12 * i), 12, out[i].m.begin());
        return out;
    }
    if (!list->is_array()) r.schema_error(ptr, "expected an array of transforms");
    out.reserve(list->size());
    for (std::size_t i = 0; i < list->size(); ++i)
        out.push_back(parse_transform(r, (*list)[i], child(ptr, i)));
    return out;
}

Edit parse_add_instances(OpFields& f) {
    AddInstances e;
    e.ids = read_ids(f);
    read_id_or_ids(f, "mesh", e.meshes);
    read_id_or_ids(f, "material", e.materials);
    e.transforms = read_transforms(f);
    std::optional<std::optional<std::string>> parent;
    read_parent(f, parent);
    if (parent) e.parent = *parent;
    f.read("visible", e.visible);
    return e;
}

Edit parse_update_instances(OpFields& f) {
    UpdateInstances e;
    if (!f.get("transforms") && !f.get("transforms_b64") && !f.get("visible"))
        f.reader().schema_error(f.pointer(), "give transforms, transforms_b64 or visible");
    e.ids = read_ids(f);
    e.transforms = read_transforms(f);
    f.read("visible", e.visible);
    return e;
}

Edit parse_remove_instances(OpFields& f) {
    RemoveInstances e;
    e.ids = read_ids(f);
    return e;
}

constexpr EditOp OPS[] = {
    {"add_instances",
     "Many new instances in one edit: ids listed or numbered, mesh and material once or per item, "
     "transforms as an array or base64 float32 3x4 rows.",
     R"json({
  "type": "object",
  "properties": {
    "ids": {"$ref": "#/$defs/bulk_ids"},
    "mesh": {"$ref": "#/$defs/id_or_ids"},
    "material": {"$ref": "#/$defs/id_or_ids"},
    "transforms": {"$ref": "#/$defs/bulk_transforms"},
    "transforms_b64": {"$ref": "#/$defs/transforms_base64"},
    "parent": {"oneOf": [{"$ref": "#/$defs/id"}, {"type": "null"}]},
    "visible": {"type": "boolean"}
  },
  "required": ["ids", "mesh"],
  "not": {"required": ["transforms", "transforms_b64"]},
  "additionalProperties": false
})json",
     parse_add_instances, edit_kinds<AddInstances>()},
    {"update_instances",
     "Moves, hides or shows many instances in one edit: transforms as an array or base64 float32 "
     "3x4 rows, visible for all.",
     R"json({
  "type": "object",
  "properties": {
    "ids": {"$ref": "#/$defs/bulk_ids"},
    "transforms": {"$ref": "#/$defs/bulk_transforms"},
    "transforms_b64": {"$ref": "#/$defs/transforms_base64"},
    "visible": {"type": "boolean"}
  },
  "required": ["ids"],
  "anyOf": [{"required": ["transforms"]}, {"required": ["transforms_b64"]},
            {"required": ["visible"]}],
  "not": {"required": ["transforms", "transforms_b64"]},
  "additionalProperties": false
})json",
     parse_update_instances, edit_kinds<UpdateInstances>()},
    {"remove_instances", "Removes many instances in one edit.",
     R"json({
  "type": "object",
  "properties": {"ids": {"$ref": "#/$defs/bulk_ids"}},
  "required": ["ids"],
  "additionalProperties": false
})json",
     parse_remove_instances, edit_kinds<RemoveInstances>()},
};

}  // namespace

std::span<const EditOp> bulk_instance_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
