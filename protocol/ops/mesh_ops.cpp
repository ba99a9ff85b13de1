// Mesh ops: add_mesh, update_mesh, remove_mesh. Arrays come flat or base64; a mesh may also be a
// procedural shape, with build options.

#include "engine/scene/shapes.h"
#include "protocol/edit_schema.h"
#include "protocol/field_json.h"
#include "protocol/ops/families.h"

namespace strata::protocol::ops {

namespace {

/// A flat array member or its base64 twin (at most one of them); nullopt when neither is given.
template <class T>
std::optional<std::vector<T>> read_array(
    OpFields& f, std::string_view flat_key, std::string_view b64_key,
    std::vector<T> (FieldReader::*read_flat)(const Json&, const std::string&),
    std::vector<T> (FieldReader::*read_b64)(const Json&, const std::string&),
    bool EditSource::*from_b64) {
    FieldReader& r = f.reader();
    const Json* flat = f.get(flat_key);
    const Json* b64 = f.get(b64_key);
    if (flat && b64)
        r.schema_error(f.pointer(b64_key), "give " + std::string(flat_key) + " or " +
                                               std::string(b64_key) + ", not both");
    if (flat) return (r.*read_flat)(*flat, f.pointer(flat_key));
    if (!b64) return std::nullopt;
    f.source().*from_b64 = true;
    return (r.*read_b64)(*b64, f.pointer(b64_key));
}

std::optional<std::vector<Vec3>> read_positions(OpFields& f) {
    return read_array(f, "positions", "positions_b64", &FieldReader::positions,
                      &FieldReader::positions_b64, &EditSource::positions_b64);
}

std::optional<std::vector<Triangle>> read_indices(OpFields& f) {
    return read_array(f, "indices", "indices_b64", &FieldReader::indices, &FieldReader::indices_b64,
                      &EditSource::indices_b64);
}

/// Vertex attribute `A`, flat (`normals`) or base64 (`normals_b64`); nullopt when neither.
template <class A>
std::optional<std::vector<typename A::Value>> read_attribute(OpFields& f, A) {
    using V = typename A::Value;
    FieldReader& r = f.reader();
    const std::string b64_key = std::string(A::name) + "_b64";
    const Json* flat = f.get(A::name);
    const Json* b64 = f.get(b64_key);
    if (flat && b64)
        r.schema_error(f.pointer(b64_key),
                       "give " + std::string(A::name) + " or " + b64_key + ", not both");
    if (flat) return r.per_vertex<V>(*flat, f.pointer(A::name), A::name);
    if (!b64) return std::nullopt;
    f.source().attributes_b64 |= uint8_t(1u << A::index);
    return r.per_vertex_b64<V>(*b64, f.pointer(b64_key), A::name);
}

/// Every vertex attribute the op gives, into `e`'s members of the same names.
template <class E>
void read_attributes(OpFields& f, E& e) {
    for_each_vertex_attribute([&](auto a) {
        auto values = read_attribute(f, a);
        if constexpr (std::is_same_v<E, AddMesh>) {
            if (values) decltype(a)::of(e) = std::move(*values);
        } else {
            decltype(a)::of(e) = std::move(values);
        }
    });
}

/// A curve mesh's strands: control vertices per strand, flat or base64 uint32s.
std::optional<std::vector<uint32_t>> read_strands(OpFields& f) {
    return read_array(f, "strands", "strands_b64", &FieldReader::vertex_ids,
                      &FieldReader::vertex_ids_b64, &EditSource::strands_b64);
}

std::optional<std::vector<uint32_t>> read_vertices(OpFields& f) {
    return read_array(f, "vertices", "vertices_b64", &FieldReader::vertex_ids,
                      &FieldReader::vertex_ids_b64, &EditSource::vertices_b64);
}

/// `[n, n]` of integers in [1, hi].
std::pair<uint32_t, uint32_t> read_pair(FieldReader& r, const Json& v, const std::string& ptr,
                                        uint32_t hi) {
    if (!v.is_array() || v.size() != 2) r.schema_error(ptr, "expected an array of 2 integers");
    return {static_cast<uint32_t>(r.integer(v[0], child(ptr, std::size_t(0)), 1, hi)),
            static_cast<uint32_t>(r.integer(v[1], child(ptr, std::size_t(1)), 1, hi))};
}

/// `size`: a number or an array of `n` numbers, each > 0.
Vec3 read_size(FieldReader& r, const Json& v, const std::string& ptr, int n) {
    if (v.is_number()) return Vec3(r.positive_number(v, ptr));
    if (!v.is_array() || v.size() != std::size_t(n))
        r.schema_error(ptr,
                       "expected a number or an array of " + std::to_string(n) + " numbers > 0");
    Vec3 out(1.0f);
    for (int k = 0; k < n; ++k) out[k] = r.positive_number(v[k], child(ptr, std::size_t(k)));
    return out;
}

MeshData read_shape(FieldReader& r, const Json& v, const std::string& ptr) {
    // In the order of the `oneOf` of $defs/shape.
    static const MemberRule SHAPES[] = {schema_members("/$defs/shape/oneOf/0"),
                                        schema_members("/$defs/shape/oneOf/1"),
                                        schema_members("/$defs/shape/oneOf/2")};
    if (!v.is_object()) r.schema_error(ptr, "expected a shape object with a \"type\"");
    const std::size_t type =
        r.choice(r.required(v, ptr, "type"), child(ptr, "type"), {"sphere", "box", "plane"});
    r.expect_object(v, ptr, SHAPES[type]);
    const Json* size = FieldReader::member(v, "size");
    switch (type) {
        case 0: {
            const Json* radius = FieldReader::member(v, "radius");
            const Json* segments = FieldReader::member(v, "segments");
            const float rad = radius ? r.positive_number(*radius, child(ptr, "radius")) : 1.0f;
            const auto seg =
                segments ? r.integer(*segments, child(ptr, "segments"), 3, MAX_SPHERE_SEGMENTS)
                         : 32;
            if (!r.reserve_shape_triangles(sphere_triangle_count(uint32_t(seg)), ptr)) return {};
            return make_sphere(rad, static_cast<uint32_t>(seg));
        }
        case 1:
            return make_box(size ? read_size(r, *size, child(ptr, "size"), 3) : Vec3(1.0f));
        default: {
            const Json* subdivisions = FieldReader::member(v, "subdivisions");
            const Vec3 s = size ? read_size(r, *size, child(ptr, "size"), 2) : Vec3(1.0f);
            const auto [nx, nz] = subdivisions
                                      ? read_pair(r, *subdivisions, child(ptr, "subdivisions"),
                                                  MAX_PLANE_SUBDIVISIONS)
                                      : std::pair<uint32_t, uint32_t>{1, 1};
            if (!r.reserve_shape_triangles(2ull * nx * nz, ptr)) return {};
            // A plane's size is [x, z]; make_plane takes a Vec3 and ignores y.
            return make_plane(Vec3(s.x, 0.0f, s.y), nx, nz);
        }
    }
}

BuildOptions read_build(FieldReader& r, const Json& v, const std::string& ptr) {
    static const MemberRule BUILD = schema_members("/$defs/build");
    r.expect_object(v, ptr, BUILD);
    BuildOptions b;
    if (const Json* p = FieldReader::member(v, "prefer"))
        b.prefer = r.choice(*p, child(ptr, "prefer"), {"fast_trace", "fast_build"}) == 0
                       ? BuildPreference::FastTrace
                       : BuildPreference::FastBuild;
    if (const Json* a = FieldReader::member(v, "allow_refit"))
        b.allow_refit = r.boolean(*a, child(ptr, "allow_refit"));
    if (const Json* c = FieldReader::member(v, "compact"))
        b.compact = r.boolean(*c, child(ptr, "compact"));
    return b;
}

Edit parse_add_mesh(OpFields& f) {
    FieldReader& r = f.reader();
    AddMesh e;
    e.id = f.id("id");
    if (const Json* shape = f.get("shape")) {
        for (const char* other : {"positions", "positions_b64", "indices", "indices_b64"}) {
            if (f.get(other))
                r.schema_error(f.pointer(other),
                               std::string("give shape or ") + other + ", not both");
        }
        f.source().shape = true;
        MeshData data = read_shape(r, *shape, f.pointer("shape"));
        // A sphere is smooth: its normals point away from its centre (the origin). Boxes and
        // planes keep their faces' own normals (sharp edges). Normals given in the op win.
        if (shape->at("type") == "sphere") {
            e.normals.reserve(data.positions.size());
            for (const Vec3& p : data.positions) e.normals.push_back(glm::normalize(p));
        }
        e.positions = std::move(data.positions);
        e.triangles = std::move(data.triangles);
    } else {
        auto positions = read_positions(f);
        if (!positions)
            r.schema_error(f.pointer("positions"),
                           "add_mesh needs positions, positions_b64 or shape");
        // Triangles need indices; points and curves have none (the scene's rules say so).
        auto indices = read_indices(f);
        const Json* kind = f.get("kind");
        if (!indices && (!kind || *kind == "triangles"))
            r.schema_error(f.pointer("indices"),
                           "add_mesh needs indices or indices_b64 with positions");
        e.positions = std::move(*positions);
        if (indices) e.triangles = std::move(*indices);
        if (auto strands = read_strands(f)) e.strands = std::move(*strands);
    }
    read_attributes(f, e);
    if (const Json* b = f.get("build")) e.build = read_build(r, *b, f.pointer("build"));
    f.read("material", e.material);
    read_added<MeshFields>(f, e);
    return e;
}

/// update_mesh with `vertices`: positions for listed vertices (a brush stroke), positions only.
Edit listed_vertices(OpFields& f, std::string mesh, std::optional<std::vector<Vec3>> positions,
                     std::vector<uint32_t> vertices) {
    FieldReader& r = f.reader();
    for (const char* other : {"offset", "indices", "indices_b64", "strands", "strands_b64",
                              "resize"}) {
        if (f.get(other))
            r.schema_error(f.pointer(other),
                           std::string(other) + " does not go with vertices (positions only)");
    }
    for_each_vertex_attribute([&](auto a) {
        for (const std::string& key : {std::string(a.name), std::string(a.name) + "_b64"})
            if (f.get(key))
                r.schema_error(f.pointer(key), key + " does not go with vertices (positions only)");
    });
    if (!positions)
        r.schema_error(f.pointer("positions"),
                       "update_mesh with vertices needs positions or positions_b64");
    UpdateMeshVertices listed;
    listed.mesh = std::move(mesh);
    listed.vertices = std::move(vertices);
    listed.positions = std::move(*positions);
    return listed;
}

Edit parse_update_mesh(OpFields& f) {
    FieldReader& r = f.reader();
    std::string mesh = f.id("mesh");
    auto positions = read_positions(f);
    auto indices = read_indices(f);
    UpdateMeshPositions e;  // the attributes, whichever edit they go to
    read_attributes(f, e);
    const bool attributes = gives_attributes(e);
    auto vertices = read_vertices(f);
    auto strands = read_strands(f);
    if (vertices)
        return listed_vertices(f, std::move(mesh), std::move(positions), std::move(*vertices));
    bool resize = false;
    f.read("resize", resize);
    if (resize && !positions)
        r.schema_error(f.pointer("positions"), "resize needs positions or positions_b64");
    if (indices || strands || resize) {
        // A topology change: new triangles, a curve mesh's strands or a points mesh's new
        // count, and optionally a whole new vertex array.
        if (f.get("offset"))
            r.schema_error(f.pointer("offset"),
                           "offset applies to a positions update, not to a topology change");
        if (int(bool(indices)) + int(bool(strands)) + int(resize) > 1)
            r.schema_error(f.pointer(resize ? "resize" : "strands"),
                           "give one of indices (triangles), strands (curves) or resize (points)");
        ReplaceMeshTopology topology;
        topology.mesh = std::move(mesh);
        topology.positions = std::move(positions);
        if (indices) topology.triangles = std::move(*indices);
        topology.strands = std::move(strands);
        for_each_vertex_attribute(
            [&](auto a) { decltype(a)::of(topology) = std::move(decltype(a)::of(e)); });
        return topology;
    }
    if (!positions && !attributes) {
        std::string names;  // the vertex attributes, as their list declares them
        for_each_vertex_attribute([&](auto a) { names += ", " + std::string(a.name); });
        r.schema_error(f.pointer("positions"),
                       "update_mesh needs positions" + names + " (or indices or strands)");
    }
    e.mesh = std::move(mesh);
    if (positions) e.positions = std::move(*positions);
    f.read("offset", e.offset);
    return e;
}

Edit parse_replace_triangles(OpFields& f) {
    ReplaceMeshTriangles e;
    e.mesh = f.id("mesh");
    f.read("first", e.first);
    f.read("count", e.count);
    auto indices = read_indices(f);
    if (!indices)
        f.reader().schema_error(f.pointer("indices"),
                                "replace_triangles needs indices or indices_b64 ([] removes)");
    e.triangles = std::move(*indices);
    return e;
}

Edit parse_remove_mesh(OpFields& f) {
    return RemoveMesh{f.id("mesh")};
}

constexpr EditOp OPS[] = {
    {"add_mesh",
     "A new mesh from flat arrays, base64 arrays or a procedural shape; optionally with "
     "per-vertex normals, uvs (two sets) and tangents, and vertex keys for deformation blur "
     "(motion_positions). With kind points or curves: spheres or strands of curve segments "
     "with a radius per vertex.",
     R"json({
  "type": "object",
  "properties": {
    "id": {"$ref": "#/$defs/id"},
    "positions": {"$ref": "#/$defs/positions"},
    "positions_b64": {"$ref": "#/$defs/base64"},
    "indices": {"$ref": "#/$defs/indices"},
    "indices_b64": {"$ref": "#/$defs/base64"},
    "normals": {"$ref": "#/$defs/normals"},
    "normals_b64": {"$ref": "#/$defs/base64"},
    "uvs": {"$ref": "#/$defs/uvs"},
    "uvs_b64": {"$ref": "#/$defs/base64"},
    "uvs1": {"$ref": "#/$defs/uvs"},
    "uvs1_b64": {"$ref": "#/$defs/base64"},
    "tangents": {"$ref": "#/$defs/tangents"},
    "tangents_b64": {"$ref": "#/$defs/base64"},
    "radii": {"$ref": "#/$defs/radii"},
    "radii_b64": {"$ref": "#/$defs/base64"},
    "motion_positions": {"$ref": "#/$defs/positions", "description": "vertex keys for deformation blur: k positions per vertex (keys 1 to k; positions are key 0), vertex after vertex; the k + 1 keys span the frame evenly"},
    "motion_positions_b64": {"$ref": "#/$defs/base64"},
    "strands": {"$ref": "#/$defs/strands"},
    "strands_b64": {"$ref": "#/$defs/base64"},
    "shape": {"$ref": "#/$defs/shape"},
    "build": {"$ref": "#/$defs/build"},
    "material": {"$ref": "#/$defs/id"}
  },
  "required": ["id"],
  "additionalProperties": false,
  "not": {"anyOf": [{"required": ["normals", "normals_b64"]}, {"required": ["uvs", "uvs_b64"]},
                    {"required": ["uvs1", "uvs1_b64"]},
                    {"required": ["tangents", "tangents_b64"]},
                    {"required": ["radii", "radii_b64"]},
                    {"required": ["motion_positions", "motion_positions_b64"]},
                    {"required": ["strands", "strands_b64"]}]},
  "oneOf": [
    {
      "required": ["shape"],
      "not": {"anyOf": [{"required": ["positions"]}, {"required": ["positions_b64"]},
                        {"required": ["indices"]}, {"required": ["indices_b64"]},
                        {"required": ["kind"]}]}
    },
    {
      "not": {"required": ["shape"]},
      "allOf": [
        {"oneOf": [{"required": ["positions"]}, {"required": ["positions_b64"]}]},
        {
          "if": {"required": ["kind"], "properties": {"kind": {"enum": ["points", "curves"]}}},
          "then": {"oneOf": [{"required": ["radii"]}, {"required": ["radii_b64"]}]},
          "else": {"oneOf": [{"required": ["indices"]}, {"required": ["indices_b64"]}]}
        },
        {
          "if": {"required": ["kind"], "properties": {"kind": {"const": "curves"}}},
          "then": {"oneOf": [{"required": ["strands"]}, {"required": ["strands_b64"]}]}
        }
      ]
    }
  ]
})json",
     parse_add_mesh, edit_kinds<AddMesh>(), field_properties<MeshFields, true>},
    {"update_mesh",
     "New positions, normals, uvs (either set), tangents, radii or vertex keys for a vertex "
     "range (offset "
     "in vertices), new positions for listed vertices (vertices), or with indices (or a curve "
     "mesh's strands, or a points mesh's positions of a new length) a topology change.",
     R"json({
  "type": "object",
  "properties": {
    "mesh": {"$ref": "#/$defs/id"},
    "positions": {"$ref": "#/$defs/positions"},
    "positions_b64": {"$ref": "#/$defs/base64"},
    "indices": {"$ref": "#/$defs/indices"},
    "indices_b64": {"$ref": "#/$defs/base64"},
    "normals": {"$ref": "#/$defs/normals"},
    "normals_b64": {"$ref": "#/$defs/base64"},
    "uvs": {"$ref": "#/$defs/uvs"},
    "uvs_b64": {"$ref": "#/$defs/base64"},
    "uvs1": {"$ref": "#/$defs/uvs"},
    "uvs1_b64": {"$ref": "#/$defs/base64"},
    "tangents": {"$ref": "#/$defs/tangents"},
    "tangents_b64": {"$ref": "#/$defs/base64"},
    "radii": {"$ref": "#/$defs/radii"},
    "radii_b64": {"$ref": "#/$defs/base64"},
    "motion_positions": {"$ref": "#/$defs/positions", "description": "vertex keys for deformation blur: k positions per vertex (keys 1 to k; positions are key 0), vertex after vertex; the k + 1 keys span the frame evenly"},
    "motion_positions_b64": {"$ref": "#/$defs/base64"},
    "strands": {"$ref": "#/$defs/strands"},
    "strands_b64": {"$ref": "#/$defs/base64"},
    "resize": {"type": "boolean", "description": "points: positions (and radii) are the mesh's whole new vertex array, of any length"},
    "offset": {"$ref": "#/$defs/u32"},
    "vertices": {"type": "array", "items": {"$ref": "#/$defs/u32"},
                 "description": "vertex indices: positions[i] goes to vertex vertices[i]"},
    "vertices_b64": {"$ref": "#/$defs/base64"}
  },
  "required": ["mesh"],
  "additionalProperties": false,
  "not": {
    "anyOf": [
      {"required": ["positions", "positions_b64"]},
      {"required": ["indices", "indices_b64"]},
      {"required": ["normals", "normals_b64"]},
      {"required": ["uvs", "uvs_b64"]},
      {"required": ["uvs1", "uvs1_b64"]},
      {"required": ["tangents", "tangents_b64"]},
      {"required": ["radii", "radii_b64"]},
      {"required": ["motion_positions", "motion_positions_b64"]},
      {"required": ["strands", "strands_b64"]},
      {"required": ["vertices", "vertices_b64"]},
      {"required": ["indices", "offset"]},
      {"required": ["indices_b64", "offset"]},
      {"required": ["strands", "offset"]},
      {"required": ["strands_b64", "offset"]},
      {"required": ["indices", "strands"]},
      {"required": ["indices", "strands_b64"]},
      {"required": ["indices_b64", "strands"]},
      {"required": ["indices_b64", "strands_b64"]},
      {"required": ["resize", "offset"]},
      {"required": ["resize", "indices"]},
      {"required": ["resize", "indices_b64"]},
      {"required": ["resize", "strands"]},
      {"required": ["resize", "strands_b64"]}
    ]
  },
  "if": {"anyOf": [{"required": ["vertices"]}, {"required": ["vertices_b64"]}]},
  "then": {
    "anyOf": [{"required": ["positions"]}, {"required": ["positions_b64"]}],
    "not": {"anyOf": [{"required": ["offset"]}, {"required": ["indices"]},
                      {"required": ["indices_b64"]}, {"required": ["normals"]},
                      {"required": ["normals_b64"]}, {"required": ["uvs"]},
                      {"required": ["uvs_b64"]}, {"required": ["uvs1"]},
                      {"required": ["uvs1_b64"]}, {"required": ["tangents"]},
                      {"required": ["tangents_b64"]}, {"required": ["radii"]},
                      {"required": ["radii_b64"]}, {"required": ["motion_positions"]},
                      {"required": ["motion_positions_b64"]}, {"required": ["strands"]},
                      {"required": ["strands_b64"]}, {"required": ["resize"]}]}
  },
  "anyOf": [{"required": ["positions"]}, {"required": ["positions_b64"]},
            {"required": ["indices"]}, {"required": ["indices_b64"]},
            {"required": ["normals"]}, {"required": ["normals_b64"]},
            {"required": ["uvs"]}, {"required": ["uvs_b64"]},
            {"required": ["uvs1"]}, {"required": ["uvs1_b64"]},
            {"required": ["tangents"]}, {"required": ["tangents_b64"]},
            {"required": ["radii"]}, {"required": ["radii_b64"]},
            {"required": ["motion_positions"]}, {"required": ["motion_positions_b64"]},
            {"required": ["strands"]}, {"required": ["strands_b64"]}]
})json",
     parse_update_mesh,
     edit_kinds<UpdateMeshPositions, UpdateMeshVertices, ReplaceMeshTopology>()},
    {"replace_triangles",
     "A local topology edit: triangles first .. first + count - 1 are replaced by the triangles "
     "of indices (any number; [] cuts them out) over the mesh's existing vertices, and the "
     "triangles after them are renumbered. A clustered mesh rebuilds only the clusters that held "
     "them.",
     R"json({
  "type": "object",
  "properties": {
    "mesh": {"$ref": "#/$defs/id"},
    "first": {"$ref": "#/$defs/u32", "description": "the first triangle replaced"},
    "count": {"$ref": "#/$defs/u32", "description": "how many triangles are replaced"},
    "indices": {"$ref": "#/$defs/indices"},
    "indices_b64": {"$ref": "#/$defs/base64"}
  },
  "required": ["mesh", "first", "count"],
  "additionalProperties": false,
  "oneOf": [{"required": ["indices"]}, {"required": ["indices_b64"]}]
})json",
     parse_replace_triangles, edit_kinds<ReplaceMeshTriangles>()},
    {"remove_mesh", "Removes a mesh that no instance uses.",
     R"json({
  "type": "object",
  "properties": {"mesh": {"$ref": "#/$defs/id"}},
  "required": ["mesh"],
  "additionalProperties": false
})json",
     parse_remove_mesh, edit_kinds<RemoveMesh>()},
};

}  // namespace

std::span<const EditOp> mesh_ops() {
    return OPS;
}

}  // namespace strata::protocol::ops
