// add_mesh and update_mesh: flat or base64 arrays, procedural shapes and build options.

#include "protocol/op_parsers.h"

#include "engine/scene/shapes.h"

namespace strata::protocol::detail {

namespace {

/// Reads `positions` or `positions_b64` (at most one may be present); nullopt when neither is.
std::optional<std::vector<Vec3>> read_positions(FieldReader& r, const Json& v,
                                                const std::string& ptr, EditSource& src) {
    const Json* flat = FieldReader::member(v, "positions");
    const Json* b64 = FieldReader::member(v, "positions_b64");
    if (flat && b64)
        r.schema_error(child(ptr, "positions_b64"), "give positions or positions_b64, not both");
    if (flat) return r.positions(*flat, child(ptr, "positions"));
    if (b64) {
        src.positions_b64 = true;
        return r.positions_b64(*b64, child(ptr, "positions_b64"));
    }
    return std::nullopt;
}

std::optional<std::vector<Triangle>> read_indices(FieldReader& r, const Json& v,
                                                  const std::string& ptr, EditSource& src) {
    const Json* flat = FieldReader::member(v, "indices");
    const Json* b64 = FieldReader::member(v, "indices_b64");
    if (flat && b64)
        r.schema_error(child(ptr, "indices_b64"), "give indices or indices_b64, not both");
    if (flat) return r.indices(*flat, child(ptr, "indices"));
    if (b64) {
        src.indices_b64 = true;
        return r.indices_b64(*b64, child(ptr, "indices_b64"));
    }
    return std::nullopt;
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
    if (!v.is_object()) r.schema_error(ptr, "expected a shape object with a \"type\"");
    const std::size_t type =
        r.choice(r.required(v, ptr, "type"), child(ptr, "type"), {"sphere", "box", "plane"});
    switch (type) {
        case 0: {
            r.expect_object(v, ptr, {"type", "radius", "segments"});
            const Json* radius = FieldReader::member(v, "radius");
            const Json* segments = FieldReader::member(v, "segments");
            const float rad = radius ? r.positive_number(*radius, child(ptr, "radius")) : 1.0f;
            const auto seg =
                segments ? r.integer(*segments, child(ptr, "segments"), 3, MAX_SPHERE_SEGMENTS)
                         : 32;
            return make_sphere(rad, static_cast<uint32_t>(seg));
        }
        case 1: {
            r.expect_object(v, ptr, {"type", "size"});
            const Json* size = FieldReader::member(v, "size");
            return make_box(size ? read_size(r, *size, child(ptr, "size"), 3) : Vec3(1.0f));
        }
        default: {
            r.expect_object(v, ptr, {"type", "size", "subdivisions"});
            const Json* size = FieldReader::member(v, "size");
            const Json* subdivisions = FieldReader::member(v, "subdivisions");
            const Vec3 s = size ? read_size(r, *size, child(ptr, "size"), 2) : Vec3(1.0f);
            const auto [nx, nz] = subdivisions
                                      ? read_pair(r, *subdivisions, child(ptr, "subdivisions"),
                                                  MAX_PLANE_SUBDIVISIONS)
                                      : std::pair<uint32_t, uint32_t>{1, 1};
            // A plane's size is [x, z]; make_plane takes a Vec3 and ignores y.
            return make_plane(Vec3(s.x, 0.0f, s.y), nx, nz);
        }
    }
}

BuildOptions read_build(FieldReader& r, const Json& v, const std::string& ptr) {
    r.expect_object(v, ptr, {"prefer", "allow_refit"});
    BuildOptions b;
    if (const Json* p = FieldReader::member(v, "prefer"))
        b.prefer = r.choice(*p, child(ptr, "prefer"), {"fast_trace", "fast_build"}) == 0
                       ? BuildPreference::FastTrace
                       : BuildPreference::FastBuild;
    if (const Json* a = FieldReader::member(v, "allow_refit"))
        b.allow_refit = r.boolean(*a, child(ptr, "allow_refit"));
    return b;
}

}  // namespace

Edit parse_add_mesh(FieldReader& r, const Json& v, const std::string& ptr, EditSource& src) {
    r.expect_object(v, ptr,
                    {"op", "id", "positions", "positions_b64", "indices", "indices_b64", "shape",
                     "build", "material"});
    AddMesh e;
    e.id = r.id(r.required(v, ptr, "id"), child(ptr, "id"));
    if (const Json* shape = FieldReader::member(v, "shape")) {
        for (const char* other : {"positions", "positions_b64", "indices", "indices_b64"}) {
            if (FieldReader::member(v, other))
                r.schema_error(child(ptr, other),
                               std::string("give shape or ") + other + ", not both");
        }
        src.shape = true;
        MeshData data = read_shape(r, *shape, child(ptr, "shape"));
        e.positions = std::move(data.positions);
        e.triangles = std::move(data.triangles);
    } else {
        auto positions = read_positions(r, v, ptr, src);
        if (!positions)
            r.schema_error(child(ptr, "positions"),
                           "add_mesh needs positions, positions_b64 or shape");
        auto indices = read_indices(r, v, ptr, src);
        if (!indices)
            r.schema_error(child(ptr, "indices"),
                           "add_mesh needs indices or indices_b64 with positions");
        e.positions = std::move(*positions);
        e.triangles = std::move(*indices);
    }
    if (const Json* b = FieldReader::member(v, "build"))
        e.build = read_build(r, *b, child(ptr, "build"));
    if (const Json* m = FieldReader::member(v, "material"))
        e.material = r.id(*m, child(ptr, "material"));
    return e;
}

Edit parse_update_mesh(FieldReader& r, const Json& v, const std::string& ptr, EditSource& src) {
    r.expect_object(
        v, ptr, {"op", "mesh", "positions", "positions_b64", "offset", "indices", "indices_b64"});
    std::string mesh = r.id(r.required(v, ptr, "mesh"), child(ptr, "mesh"));
    auto positions = read_positions(r, v, ptr, src);
    auto indices = read_indices(r, v, ptr, src);
    const Json* offset = FieldReader::member(v, "offset");
    if (indices) {
        // A topology change: new triangles and optionally a whole new vertex array.
        if (offset)
            r.schema_error(child(ptr, "offset"),
                           "offset applies to a positions update, not to a topology change");
        ReplaceMeshTopology e;
        e.mesh = std::move(mesh);
        e.positions = std::move(positions);
        e.triangles = std::move(*indices);
        return e;
    }
    if (!positions)
        r.schema_error(child(ptr, "positions"),
                       "update_mesh needs positions or positions_b64 (or indices)");
    UpdateMeshPositions e;
    e.mesh = std::move(mesh);
    e.positions = std::move(*positions);
    if (offset)
        e.offset = static_cast<uint32_t>(r.integer(*offset, child(ptr, "offset"), 0, UINT32_MAX));
    return e;
}

}  // namespace strata::protocol::detail
