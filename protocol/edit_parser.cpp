#include "protocol/edit_parser.h"

#include "protocol/op_parsers.h"
#include "protocol/transform_parser.h"

namespace strata::protocol {

namespace {

using detail::parse_add_mesh;
using detail::parse_update_mesh;

Material read_material_fields(FieldReader& r, const Json& v, const std::string& ptr,
                              UpdateMaterial* update) {
    Material m;
    auto vec = [&](const char* key, Vec3& out, std::optional<Vec3>* changed) {
        if (const Json* f = FieldReader::member(v, key)) {
            out = r.vec3(*f, child(ptr, key));
            if (changed) *changed = out;
        }
    };
    auto scalar = [&](const char* key, float& out, std::optional<float>* changed) {
        if (const Json* f = FieldReader::member(v, key)) {
            out = r.number(*f, child(ptr, key));
            if (changed) *changed = out;
        }
    };
    vec("base_color", m.base_color, update ? &update->base_color : nullptr);
    scalar("roughness", m.roughness, update ? &update->roughness : nullptr);
    scalar("metallic", m.metallic, update ? &update->metallic : nullptr);
    vec("emission", m.emission, update ? &update->emission : nullptr);
    return m;
}

Edit parse_add_material(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", "id", "base_color", "roughness", "metallic", "emission"});
    AddMaterial e;
    e.id = r.id(r.required(v, ptr, "id"), child(ptr, "id"));
    e.material = read_material_fields(r, v, ptr, nullptr);
    return e;
}

Edit parse_update_material(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", "material", "base_color", "roughness", "metallic", "emission"});
    UpdateMaterial e;
    e.material = r.id(r.required(v, ptr, "material"), child(ptr, "material"));
    read_material_fields(r, v, ptr, &e);
    return e;
}

uint32_t read_u32(FieldReader& r, const Json& v, const std::string& ptr) {
    return static_cast<uint32_t>(r.integer(v, ptr, 0, UINT32_MAX));
}

/// The members add_instance and update_instance share (plain values in one, optionals in the
/// other).
template <class E>
void read_instance_fields(FieldReader& r, const Json& v, const std::string& ptr, E& e) {
    if (const Json* f = FieldReader::member(v, "transform"))
        e.transform = parse_transform(r, *f, child(ptr, "transform"));
    if (const Json* f = FieldReader::member(v, "visible"))
        e.visible = r.boolean(*f, child(ptr, "visible"));
    if (const Json* f = FieldReader::member(v, "mask"))
        e.mask = read_u32(r, *f, child(ptr, "mask"));
    if (const Json* f = FieldReader::member(v, "user_id"))
        e.user_id = read_u32(r, *f, child(ptr, "user_id"));
}

Edit parse_add_instance(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr,
                    {"op", "id", "mesh", "material", "transform", "visible", "mask", "user_id"});
    AddInstance e;
    e.id = r.id(r.required(v, ptr, "id"), child(ptr, "id"));
    e.mesh = r.id(r.required(v, ptr, "mesh"), child(ptr, "mesh"));
    if (const Json* f = FieldReader::member(v, "material"))
        e.material = r.id(*f, child(ptr, "material"));
    read_instance_fields(r, v, ptr, e);
    return e;
}

Edit parse_update_instance(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr,
                    {"op", "instance", "material", "transform", "visible", "mask", "user_id"});
    UpdateInstance e;
    e.instance = r.id(r.required(v, ptr, "instance"), child(ptr, "instance"));
    if (const Json* f = FieldReader::member(v, "material")) {
        // null: back to the mesh's default material.
        e.material = f->is_null() ? std::optional<std::string>() : r.id(*f, child(ptr, "material"));
    }
    read_instance_fields(r, v, ptr, e);
    return e;
}

Edit parse_set_transform(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", "instance", "transform"});
    SetTransform e;
    e.instance = r.id(r.required(v, ptr, "instance"), child(ptr, "instance"));
    e.transform = parse_transform(r, r.required(v, ptr, "transform"), child(ptr, "transform"));
    return e;
}

Edit parse_mark_dirty(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", "target", "action"});
    MarkDirty e;
    const Json& target = r.required(v, ptr, "target");
    const std::string tp = child(ptr, "target");
    if (target.is_object()) {
        r.expect_object(target, tp, {"mesh"});
        e.mesh = r.id(r.required(target, tp, "mesh"), child(tp, "mesh"));
    } else if (!(target.is_string() && target.get_ref<const std::string&>() == "tlas")) {
        r.schema_error(tp, "expected \"tlas\" or {\"mesh\": id}");
    }
    e.action =
        r.choice(r.required(v, ptr, "action"), child(ptr, "action"), {"refit", "rebuild"}) == 0
            ? DirtyAction::Refit
            : DirtyAction::Rebuild;
    return e;
}

Edit parse_set_camera(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", "eye", "target", "up", "fov_y_deg"});
    SetCamera e;
    if (const Json* f = FieldReader::member(v, "eye")) e.eye = r.vec3(*f, child(ptr, "eye"));
    if (const Json* f = FieldReader::member(v, "target"))
        e.target = r.vec3(*f, child(ptr, "target"));
    if (const Json* f = FieldReader::member(v, "up")) e.up = r.vec3(*f, child(ptr, "up"));
    if (const Json* f = FieldReader::member(v, "fov_y_deg"))
        e.fov_y_deg = r.number(*f, child(ptr, "fov_y_deg"));
    return e;
}

Edit parse_set_lighting(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", "sun_direction", "sun_color", "sky_color", "sky_intensity"});
    SetLighting e;
    if (const Json* f = FieldReader::member(v, "sun_direction"))
        e.sun_direction = r.vec3(*f, child(ptr, "sun_direction"));
    if (const Json* f = FieldReader::member(v, "sun_color"))
        e.sun_color = r.vec3(*f, child(ptr, "sun_color"));
    if (const Json* f = FieldReader::member(v, "sky_color"))
        e.sky_color = r.vec3(*f, child(ptr, "sky_color"));
    if (const Json* f = FieldReader::member(v, "sky_intensity"))
        e.sky_intensity = r.number(*f, child(ptr, "sky_intensity"));
    return e;
}

template <class E, const char* KEY>
Edit parse_remove(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op", KEY});
    return E{r.id(r.required(v, ptr, KEY), child(ptr, KEY))};
}

Edit parse_clear(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"op"});
    return Clear{};
}

constexpr char MESH_KEY[] = "mesh";
constexpr char INSTANCE_KEY[] = "instance";

using OpParser = Edit (*)(FieldReader&, const Json&, const std::string&, EditSource&);

template <Edit (*F)(FieldReader&, const Json&, const std::string&)>
Edit no_source(FieldReader& r, const Json& v, const std::string& ptr, EditSource&) {
    return F(r, v, ptr);
}

struct OpEntry {
    std::string_view name;
    OpParser parse;
};

constexpr OpEntry OPS[] = {
    {"add_mesh", parse_add_mesh},
    {"update_mesh", parse_update_mesh},
    {"remove_mesh", no_source<parse_remove<RemoveMesh, MESH_KEY>>},
    {"add_material", no_source<parse_add_material>},
    {"update_material", no_source<parse_update_material>},
    {"add_instance", no_source<parse_add_instance>},
    {"update_instance", no_source<parse_update_instance>},
    {"set_transform", no_source<parse_set_transform>},
    {"remove_instance", no_source<parse_remove<RemoveInstance, INSTANCE_KEY>>},
    {"mark_dirty", no_source<parse_mark_dirty>},
    {"set_camera", no_source<parse_set_camera>},
    {"set_lighting", no_source<parse_set_lighting>},
    {"clear", no_source<parse_clear>},
};

Edit parse_edit(FieldReader& r, const Json& v, const std::string& ptr, EditSource& src) {
    if (!v.is_object()) r.schema_error(ptr, "an edit is an object with an \"op\" member");
    const Json& op = r.required(v, ptr, "op");
    if (op.is_string()) {
        for (const OpEntry& e : OPS) {
            if (op.get_ref<const std::string&>() == e.name) return e.parse(r, v, ptr, src);
        }
    }
    std::string list;
    for (const OpEntry& e : OPS) list += (list.empty() ? "" : ", ") + std::string(e.name);
    r.schema_error(child(ptr, "op"),
                   "unknown op" +
                       (op.is_string() ? " '" + op.get<std::string>() + "'" : std::string()) +
                       " (ops: " + list + ")");
}

/// Parses the whole batch; throws the first schema error, returns the first value error.
std::optional<RequestError> parse_into(const Json& body, ParsedBatch& out) {
    FieldReader r;
    r.expect_object(body, "", {"edits"});
    const Json& edits = r.required(body, "", "edits");
    if (!edits.is_array()) r.schema_error("/edits", "expected an array of edits");
    out.batch.edits.reserve(edits.size());
    out.sources.resize(edits.size());
    for (std::size_t i = 0; i < edits.size(); ++i) {
        r.set_edit_index(i);
        out.batch.edits.push_back(
            parse_edit(r, edits[i], "/edits/" + std::to_string(i), out.sources[i]));
    }
    return r.value_error();
}

}  // namespace

const std::vector<std::string_view>& edit_op_names() {
    static const std::vector<std::string_view> names = [] {
        std::vector<std::string_view> n;
        for (const OpEntry& e : OPS) n.push_back(e.name);
        return n;
    }();
    return names;
}

Parsed<ParsedBatch> parse_edit_batch(const Json& body) {
    ParsedBatch out;
    try {
        if (auto value_error = parse_into(body, out)) return Unexpected(std::move(*value_error));
    } catch (const RequestFailure& f) {
        return Unexpected(f.error());
    }
    return out;
}

Parsed<ParsedBatch> parse_edit_batch(std::string_view text, const JsonLimits& limits) {
    auto doc = parse_json(text, limits);
    if (!doc) return Unexpected(doc.error());
    return parse_edit_batch(doc.value());
}

std::optional<RequestError> check_edit_batch_structure(const Json& body) {
    ParsedBatch scratch;
    try {
        parse_into(body, scratch);
    } catch (const RequestFailure& f) {
        return f.error();
    }
    return std::nullopt;
}

}  // namespace strata::protocol
