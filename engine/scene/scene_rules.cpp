// The rules of every edit op, each in one place: check the edit against the scene as the earlier
// edits of its batch left it, then change the scene, recording what the change overwrote in the
// batch's undo log (undo_log.h). Scene::apply undoes the whole batch when a rule refuses an edit,
// so a rule never has to think about the edits after it. Editing only records changes (dirty
// bits and change lists); no acceleration structure is touched here.

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/core/utf8.h"
#include "engine/scene/animation.h"
#include "engine/image/texture_decode.h"
#include "engine/scene/child_list.h"
#include "engine/scene/object_fields.h"
#include "engine/scene/scene.h"
#include "engine/scene/undo_log.h"

namespace strata {

namespace {

/// Largest mesh the engine accepts; beyond this Embree's 32-bit primitive ids run out of room.
constexpr std::size_t MAX_MESH_ELEMENTS = std::size_t(1) << 28;

}  // namespace

Status check_new_id(const std::string& id, bool taken, const char* kind) {
    if (const char* why = id_problem(id))
        return failure(ErrorCode::InvalidArgument, std::string(kind) + " id " + why, "id");
    if (taken)
        return failure(ErrorCode::DuplicateId, std::string(kind) + " '" + id + "' already exists",
                       "id");
    return {};
}

namespace {

Status unknown(const char* kind, const std::string& id, const char* field) {
    return failure(ErrorCode::UnknownId, std::string("unknown ") + kind + " '" + id + "'", field);
}

/// `first_vertex` is the mesh vertex the array starts at (for messages); the field path indexes
/// the flat number array of the request. With `keys`, the array holds keys 1..keys of each vertex
/// (motion_positions), and the message names the key.
Status check_positions(const std::vector<Vec3>& positions, const char* field,
                       uint64_t first_vertex = 0, std::size_t keys = 0) {
    for (std::size_t i = 0; i < positions.size(); ++i) {
        if (is_finite(positions[i])) continue;
        const int k = std::isfinite(positions[i].x) ? (std::isfinite(positions[i].y) ? 2 : 1) : 0;
        const std::size_t per = std::max<std::size_t>(keys, 1);
        std::string vertex = "vertex " + std::to_string(first_vertex + i / per);
        if (keys) vertex += " at key " + std::to_string(1 + i % keys);
        return failure(ErrorCode::NotFinite,
                       vertex + " has a NaN or infinite " + "xyz"[k] + " coordinate",
                       std::string(field) + "/" + std::to_string(i * 3 + k));
    }
    return {};
}

/// A whole vertex array: not empty, not too large, every coordinate finite.
Status check_vertex_array(const std::vector<Vec3>& positions) {
    if (positions.size() > MAX_MESH_ELEMENTS)
        return failure(ErrorCode::TooLarge, "too many vertices", "positions");
    return check_positions(positions, "positions");
}

Status check_triangles(const std::vector<Triangle>& tris, std::size_t vertex_count,
                       const char* field) {
    if (tris.size() > MAX_MESH_ELEMENTS)
        return failure(ErrorCode::TooLarge,
                       "too many triangles (" + std::to_string(tris.size()) + ")", field);
    for (std::size_t t = 0; t < tris.size(); ++t) {
        for (int k = 0; k < 3; ++k) {
            if (tris[t][k] >= vertex_count)
                return failure(ErrorCode::OutOfRange,
                               "triangle " + std::to_string(t) + " uses vertex " +
                                   std::to_string(tris[t][k]) + " but the mesh has " +
                                   std::to_string(vertex_count) + " vertices",
                               std::string(field) + "/" + std::to_string(t * 3 + k));
        }
    }
    return {};
}

/// Per-vertex normals: every component finite and the vector not zero. `first_vertex` as above.
Status check_normals(const std::vector<Vec3>& normals, uint64_t first_vertex = 0) {
    for (std::size_t i = 0; i < normals.size(); ++i) {
        const Vec3& n = normals[i];
        if (!is_finite(n))
            return failure(ErrorCode::NotFinite,
                           "normal of vertex " + std::to_string(first_vertex + i) +
                               " has a NaN or infinite component",
                           "normals/" + std::to_string(i * 3));
        // Squared length in double: tiny finite components must still give a direction.
        const glm::dvec3 d(n);
        const double len2 = glm::dot(d, d);
        if (!(len2 > 1e-24))
            return failure(ErrorCode::InvalidArgument,
                           "normal of vertex " + std::to_string(first_vertex + i) + " is zero",
                           "normals/" + std::to_string(i * 3));
    }
    return {};
}

/// Per-vertex texture coordinates (of the set `field` names): every component finite.
Status check_uvs(const std::vector<Vec2>& uvs, uint64_t first_vertex, std::string_view field) {
    for (std::size_t i = 0; i < uvs.size(); ++i) {
        if (is_finite(uvs[i])) continue;
        const int k = std::isfinite(uvs[i].x) ? 1 : 0;
        return failure(ErrorCode::NotFinite,
                       "uv of vertex " + std::to_string(first_vertex + i) +
                           " has a NaN or infinite " + "uv"[k] + " coordinate",
                       std::string(field) + "/" + std::to_string(i * 2 + k));
    }
    return {};
}

/// Per-vertex tangents: xyz finite and not zero, w the bitangent's sign (+1 or -1, as glTF's).
Status check_tangents(const std::vector<Vec4>& tangents, uint64_t first_vertex = 0) {
    for (std::size_t i = 0; i < tangents.size(); ++i) {
        const Vec4& t = tangents[i];
        const std::string vertex = "tangent of vertex " + std::to_string(first_vertex + i);
        if (!is_finite(t))
            return failure(ErrorCode::NotFinite, vertex + " has a NaN or infinite component",
                           "tangents/" + std::to_string(i * 4));
        const glm::dvec3 d(t.x, t.y, t.z);
        if (!(glm::dot(d, d) > 1e-24))
            return failure(ErrorCode::InvalidArgument, vertex + " is zero",
                           "tangents/" + std::to_string(i * 4));
        if (t.w != 1.0f && t.w != -1.0f)
            return failure(ErrorCode::InvalidArgument,
                           vertex + " has w " + std::to_string(t.w) +
                               ": w is the bitangent's sign, +1 or -1",
                           "tangents/" + std::to_string(i * 4 + 3));
    }
    return {};
}

/// Radii of points or curve control vertices: finite, > 0 and at most MAX_COORDINATE.
Status check_radii(const std::vector<float>& radii, uint64_t first_vertex) {
    static_assert(MAX_COORDINATE == 1e15, "the message below says 1e15");
    for (std::size_t i = 0; i < radii.size(); ++i) {
        const float r = radii[i];
        if (!std::isfinite(r))
            return failure(ErrorCode::NotFinite,
                           "radius of vertex " + std::to_string(first_vertex + i) +
                               " is NaN or infinite",
                           "radii/" + std::to_string(i));
        if (!(r > 0.0f) || double(r) > double(MAX_COORDINATE))
            return failure(ErrorCode::InvalidArgument,
                           "radius of vertex " + std::to_string(first_vertex + i) + " is " +
                               std::to_string(r) + ": radii are > 0 and at most 1e15",
                           "radii/" + std::to_string(i));
    }
    return {};
}

/// The checks of attribute `A`'s values, the first of them at vertex `first_vertex`, `per_vertex`
/// values a vertex.
template <class A>
Status check_values(A, const std::vector<typename A::Value>& values, uint64_t first_vertex,
                    std::size_t per_vertex = 1) {
    if constexpr (std::is_same_v<A, MotionPositionsAttribute>)
        return check_positions(values, "motion_positions", first_vertex, per_vertex);
    else if constexpr (std::is_same_v<A, NormalsAttribute>)
        return check_normals(values, first_vertex);
    else if constexpr (std::is_same_v<A, TangentsAttribute>)
        return check_tangents(values, first_vertex);
    else if constexpr (std::is_same_v<A, RadiiAttribute>)
        return check_radii(values, first_vertex);
    else
        return check_uvs(values, first_vertex, A::name);
}

/// Refuses an attribute `e` gives (non-empty for an add, present for an update) that a mesh of
/// `kind` cannot carry, and an add of points or curves without radii.
template <class E>
Status check_attribute_kinds(const E& e, MeshKind kind, const std::string& mesh) {
    return first_failure_over_vertex_attributes([&](auto a) -> Status {
        using A = decltype(a);
        bool given = false;
        bool removed = false;  // an update's empty array
        if constexpr (std::is_same_v<E, AddMesh>) {
            given = !A::of(e).empty();
        } else {
            given = A::of(e).has_value();
            removed = given && A::of(e)->empty();
        }
        if (given && !A::fits(kind))
            return failure(ErrorCode::InvalidArgument,
                           std::string(A::name) + " are for " +
                               (A::fits(MeshKind::Triangles) ? "triangle meshes"
                                                             : "points and curves") +
                               ", and mesh '" + mesh + "' is " + mesh_kind_name(kind),
                           std::string(A::name));
        if constexpr (std::is_same_v<A, RadiiAttribute>) {
            if ((std::is_same_v<E, AddMesh> && !given && kind != MeshKind::Triangles) || removed)
                return failure(ErrorCode::InvalidArgument,
                               std::string(mesh_kind_name(kind)) + " mesh '" + mesh +
                                   "' needs radii, one per vertex",
                               std::string(A::name));
        }
        return {};
    });
}

/// A curve mesh's strands for `vertex_count` vertices.
Status check_strands(CurveBasis basis, const std::vector<uint32_t>& strands,
                     std::size_t vertex_count) {
    std::size_t bad = 0;
    const std::string why = strands_problem(basis, strands, vertex_count, bad);
    if (why.empty()) return {};
    return failure(ErrorCode::InvalidArgument, why,
                   bad < strands.size() ? "strands/" + std::to_string(bad) : "strands");
}

/// The topology arrays of a new mesh of its kind: triangles need indices, points none, curves
/// their strands.
Status check_primitives(const AddMesh& e) {
    const bool curves = e.kind == MeshKind::Curves;
    if (e.kind != MeshKind::Triangles && !e.triangles.empty())
        return failure(ErrorCode::InvalidArgument,
                       std::string(mesh_kind_name(e.kind)) + " mesh '" + e.id +
                           "' takes no indices",
                       "indices");
    if (!curves && !e.strands.empty())
        return failure(ErrorCode::InvalidArgument, "strands are for curve meshes", "strands");
    if (!curves && (e.basis != CurveBasis::Linear || e.style != CurveStyle::Round))
        return failure(ErrorCode::InvalidArgument, "basis and style are for curve meshes",
                       e.basis != CurveBasis::Linear ? "basis" : "style");
    if (e.kind == MeshKind::Triangles) {
        if (e.triangles.empty())
            return failure(ErrorCode::EmptyMesh, "mesh '" + e.id + "' has no triangles",
                           "indices");
        return check_triangles(e.triangles, e.positions.size(), "indices");
    }
    if (curves) return check_strands(e.basis, e.strands, e.positions.size());
    return {};
}

/// A whole array of attribute `A` for a mesh of `vertex_count` vertices (not 0): one value per
/// vertex, or for a keyed attribute k per vertex, k from 1 to MAX_MOTION_KEYS - 1.
template <class A>
Status check_attribute_count(A, std::size_t count, std::size_t vertex_count) {
    const std::string field(A::name);
    if constexpr (A::keyed) {
        if (count > MAX_MESH_ELEMENTS)
            return failure(ErrorCode::TooLarge, "too many " + field, field);
        const std::size_t k = values_per_vertex<A>(count, vertex_count);
        if (count % vertex_count == 0 && k >= 1 && k < MAX_MOTION_KEYS) return {};
        return failure(ErrorCode::InvalidArgument,
                       field + " has " + std::to_string(count) + " entries for " +
                           std::to_string(vertex_count) +
                           " vertices: give k per vertex, vertex after vertex (keys 1 to k, k "
                           "from 1 to " + std::to_string(MAX_MOTION_KEYS - 1) + ")",
                       field);
    }
    if (count == vertex_count) return {};
    return failure(ErrorCode::InvalidArgument,
                   field + " has " + std::to_string(count) + " entries but the mesh has " +
                       std::to_string(vertex_count) + " vertices (one per vertex)",
                   field);
}

/// An update of attribute `A` from vertex `offset`: an empty array removes the attribute; a mesh
/// that has none takes it only whole; otherwise the range must lie inside the mesh, and a keyed
/// attribute keeps its values per vertex (remove it first to change them).
template <class A>
Status check_attribute_range(A a, const std::vector<typename A::Value>& values, uint32_t offset,
                             const MeshRecord& r, const std::string& mesh) {
    const std::string field(A::name);
    const std::size_t vertex_count = r.positions.size();
    const auto& current = A::of(r);
    if (values.empty()) return {};
    if (current.empty()) {
        if (offset == 0 && check_attribute_count(a, values.size(), vertex_count)) return {};
        return failure(ErrorCode::InvalidArgument,
                       "mesh '" + mesh + "' has no " + field + " yet: give " +
                           (A::keyed ? "k" : "one") + " per vertex (" +
                           std::to_string(vertex_count) + " vertices) from offset 0",
                       field);
    }
    const std::size_t per = values_per_vertex<A>(current.size(), vertex_count);
    if (values.size() % per != 0)
        return failure(ErrorCode::InvalidArgument,
                       "mesh '" + mesh + "' has " + std::to_string(per) + " " + field +
                           " per vertex and " + field + " has " + std::to_string(values.size()) +
                           " entries: give whole vertices (remove them with [] to change the "
                           "number of keys)",
                       field);
    const uint64_t end = uint64_t(offset) + values.size() / per;
    if (end > vertex_count)
        return failure(ErrorCode::OutOfRange,
                       field + " for vertices [" + std::to_string(offset) + ", " +
                           std::to_string(end) + ") are outside mesh '" + mesh + "' which has " +
                           std::to_string(vertex_count) + " vertices",
                       field);
    return {};
}

/// A new mesh's attribute `a`: none (empty), or valid values for each vertex.
template <class A>
Status check_whole(A a, const std::vector<typename A::Value>& values, std::size_t vertex_count) {
    if (values.empty()) return {};
    if (Status s = check_attribute_count(a, values.size(), vertex_count); !s) return s;
    return check_values(a, values, 0, values_per_vertex<A>(values.size(), vertex_count));
}

/// An update of attribute `a` (when given) over vertices from `offset`.
template <class A>
Status check_update(A a, const UpdateMeshPositions& e, const MeshRecord& r) {
    const auto& values = A::of(e);
    if (!values) return {};
    if (Status s = check_attribute_range(a, *values, e.offset, r, e.mesh); !s) return s;
    const auto& current = A::of(r);
    const std::size_t n = r.positions.size();
    return check_values(a, *values, e.offset,
                        values_per_vertex<A>(current.empty() ? values->size() : current.size(), n));
}

/// A topology change's attribute `a`: when given, whole for the new vertex count (or [] to
/// remove it); when not, the kept one must still fit that count.
template <class A>
Status check_replaced(A a, const ReplaceMeshTopology& e, const MeshRecord& r,
                      std::size_t vertex_count) {
    const std::size_t old_count = r.positions.size();
    const std::string field(A::name);
    if (const auto& values = A::of(e)) return check_whole(a, *values, vertex_count);
    if (vertex_count == old_count || A::of(r).empty()) return {};
    return failure(ErrorCode::InvalidArgument,
                   "mesh '" + e.mesh + "' has " + field + " for " + std::to_string(old_count) +
                       " vertices: a topology change to " + std::to_string(vertex_count) +
                       " vertices needs new " + field + " (or [] to remove them)",
                   field);
}

/// What the geometric attributes `e` gives (radii, vertex keys) do to the BLAS, before they are
/// written: moved like positions over their vertex range (added to the record's dirty ranges), or
/// for vertex keys added or removed, new time steps (MeshDirty::Keys, counted in `totals`).
DirtyBits<MeshDirty> geometric_changes(MeshRecord& r, const UpdateMeshPositions& e,
                                       MeshTotals& totals) {
    DirtyBits<MeshDirty> bits;
    for_each_vertex_attribute([&](auto a) {
        using A = decltype(a);
        const auto& values = A::of(e);
        const auto& current = A::of(r);
        if (!A::geometric || !values || (values->empty() && current.empty())) return;
        if (A::keyed && (values->empty() || current.empty())) {
            totals.key_positions = totals.key_positions - current.size() + values->size();
            bits |= MeshDirty::Keys;
            return;
        }
        bits |= MeshDirty::Points;
        const std::size_t per = values_per_vertex<A>(current.size(), r.positions.size());
        r.dirty.points.add(e.offset, static_cast<uint32_t>(e.offset + values->size() / per));
    });
    return bits;
}

/// Each attribute `e` gives, written over the record's from `offset` (an empty array clears it;
/// a record without it takes the array whole), what it held kept in `old`.
void patch_attributes(MeshRecord& r, UpdateMeshPositions& e, undo::MeshAttributes& old) {
    for_each_vertex_attribute([&](auto a) {
        using A = decltype(a);
        auto& values = A::of(e);
        auto& dst = A::of(r);
        if (!values) return;
        A::of(old) = dst;
        if (values->empty() || dst.empty()) {
            dst = std::move(*values);
        } else {
            const std::size_t per = values_per_vertex<A>(dst.size(), r.positions.size());
            std::copy(values->begin(), values->end(), dst.begin() + std::ptrdiff_t(e.offset * per));
        }
    });
}

/// Each attribute `e` gives replaces the record's whole; `old` takes what it held.
void replace_attributes(MeshRecord& r, ReplaceMeshTopology& e, undo::MeshAttributes& old) {
    for_each_vertex_attribute([&](auto a) {
        using A = decltype(a);
        if (!A::of(e)) return;
        A::of(old) = std::move(A::of(r));
        A::of(r) = std::move(*A::of(e));
    });
}

/// A topology change's primitives for `vertex_count` vertices: triangles for a triangle mesh,
/// none for points, valid strands (new or kept) for curves.
Status check_new_topology(const ReplaceMeshTopology& e, const MeshRecord& r,
                          std::size_t vertex_count) {
    if (r.kind == MeshKind::Triangles) {
        if (e.strands)
            return failure(ErrorCode::InvalidArgument, "strands are for curve meshes", "strands");
        if (e.triangles.empty())
            return failure(ErrorCode::EmptyMesh, "mesh has no triangles", "indices");
        return check_triangles(e.triangles, vertex_count, "indices");
    }
    if (!e.triangles.empty())
        return failure(ErrorCode::InvalidArgument,
                       std::string(mesh_kind_name(r.kind)) + " mesh '" + e.mesh +
                           "' takes no indices",
                       "indices");
    if (r.kind == MeshKind::Points) {
        if (e.strands)
            return failure(ErrorCode::InvalidArgument, "strands are for curve meshes", "strands");
        return {};
    }
    return check_strands(r.basis, e.strands ? *e.strands : r.strands, vertex_count);
}

}  // namespace

// Step: mesh ops ---------------------------------------------------------------------------------

Status Scene::apply_edit(AddMesh&& e, UndoLog& undo) {
    if (Status s = check_new_id(e.id, !find_mesh(e.id).is_null(), "mesh"); !s) return s;
    if (Status s = check_fields<MeshFields>(e); !s) return s;
    if (e.positions.empty())
        return failure(ErrorCode::EmptyMesh, "mesh '" + e.id + "' has no vertices", "positions");
    if (Status s = check_vertex_array(e.positions); !s) return s;
    if (Status s = check_primitives(e); !s) return s;
    if (Status s = check_attribute_kinds(e, e.kind, e.id); !s) return s;
    if (Status s = first_failure_over_vertex_attributes([&](auto a) {
            return check_whole(a, decltype(a)::of(e), e.positions.size());
        });
        !s)
        return s;
    MaterialHandle material;
    if (e.material) {
        material = find_material(*e.material);
        if (material.is_null()) return unknown("material", *e.material, "material");
    }

    m_totals.vertices += e.positions.size();
    m_totals.key_positions += e.motion_positions.size();
    m_totals.triangles += e.triangles.size();
    ++m_totals.meshes;
    MeshRecord r;
    r.id = e.id;
    r.positions = std::move(e.positions);
    r.triangles = std::move(e.triangles);
    r.strands = std::move(e.strands);
    for_each_vertex_attribute([&](auto a) { decltype(a)::of(r) = std::move(decltype(a)::of(e)); });
    r.build = e.build;
    r.material = material;
    copy_added<MeshFields>(r, e);
    bool reused = false;
    const MeshHandle h = m_meshes.insert(std::move(r), &reused);
    undo.records.emplace_back(undo::Inserted<MeshHandle>{h, reused});
    m_mesh_ids.insert(e.id, h);
    mark(h, MeshDirty::Added);
    return {};
}

Status Scene::apply_edit(UpdateMeshPositions&& e, UndoLog& undo) {
    const MeshHandle h = find_mesh(e.mesh);
    if (h.is_null()) return unknown("mesh", e.mesh, "mesh");
    MeshRecord& r = m_meshes.at(h);
    const bool attributes = gives_attributes(e);
    if (e.positions.empty() && !attributes)
        return failure(ErrorCode::InvalidArgument,
                       "no positions or vertex attributes given", "positions");
    if (Status s = check_attribute_kinds(e, r.kind, e.mesh); !s) return s;
    const uint64_t end = uint64_t(e.offset) + e.positions.size();
    if (!e.positions.empty()) {
        if (end > r.positions.size() && r.kind != MeshKind::Triangles && e.offset == 0)
            return failure(ErrorCode::OutOfRange,
                           std::string(mesh_kind_name(r.kind)) + " mesh '" + e.mesh + "' has " +
                               std::to_string(r.positions.size()) + " vertices: a new number of " +
                               (r.kind == MeshKind::Points ? "points needs resize"
                                                           : "control vertices needs strands"),
                           "positions");
        if (end > r.positions.size())
            return failure(ErrorCode::OutOfRange,
                           "vertices [" + std::to_string(e.offset) + ", " + std::to_string(end) +
                               ") are outside mesh '" + e.mesh + "' which has " +
                               std::to_string(r.positions.size()) + " vertices",
                           e.offset ? "offset" : "positions");
        if (Status s = check_positions(e.positions, "positions", e.offset); !s) return s;
    }
    if (Status s =
            first_failure_over_vertex_attributes([&](auto a) { return check_update(a, e, r); });
        !s)
        return s;

    save_mesh(h, undo);
    // Step: the other attributes (the shading ones are no BLAS work).
    if (attributes) {
        if (gives_shading_attributes(e)) mark(h, MeshDirty::Attributes);
        if (const DirtyBits<MeshDirty> moved = geometric_changes(r, e, m_totals); moved.any())
            mark(h, moved);
        undo::MeshAttributes old{h};
        patch_attributes(r, e, old);
        undo.records.emplace_back(std::move(old));
    }
    if (e.positions.empty()) return {};

    // Step: positions (a BLAS refit at the next commit).
    mark(h, MeshDirty::Points);
    if (e.positions.size() == r.positions.size()) {
        // Every vertex: replace the array, so the undo record holds the old one without a copy
        // (and a snapshot sharing it keeps reading it).
        undo.records.emplace_back(undo::MeshPositionsReplaced{h, r.positions});
        r.positions = std::move(e.positions);
    } else {
        const auto first = r.positions.begin() + e.offset;
        undo.records.emplace_back(undo::MeshPositions{
            h, e.offset, std::vector<Vec3>(first, first + std::ptrdiff_t(e.positions.size()))});
        std::copy(e.positions.begin(), e.positions.end(), r.positions.mut().begin() + e.offset);
    }
    r.dirty.points.add(e.offset, static_cast<uint32_t>(end));
    return {};
}

Status Scene::apply_edit(UpdateMeshVertices&& e, UndoLog& undo) {
    const MeshHandle h = find_mesh(e.mesh);
    if (h.is_null()) return unknown("mesh", e.mesh, "mesh");
    MeshRecord& r = m_meshes.at(h);
    if (e.vertices.empty()) return failure(ErrorCode::InvalidArgument, "no vertices given", "vertices");
    if (e.positions.size() != e.vertices.size())
        return failure(ErrorCode::InvalidArgument,
                       "vertices lists " + std::to_string(e.vertices.size()) +
                           " vertices but positions has " + std::to_string(e.positions.size()),
                       "positions");
    for (std::size_t i = 0; i < e.vertices.size(); ++i) {
        if (e.vertices[i] >= r.positions.size())
            return failure(ErrorCode::OutOfRange,
                           "vertex " + std::to_string(e.vertices[i]) + " is outside mesh '" +
                               e.mesh + "' which has " + std::to_string(r.positions.size()) +
                               " vertices",
                           "vertices/" + std::to_string(i));
    }
    if (Status s = check_positions(e.positions, "positions"); !s) return s;

    save_mesh(h, undo);
    mark(h, MeshDirty::Points);
    std::vector<Vec3>& positions = r.positions.mut();
    undo::MeshVertexPositions old{h, e.vertices, {}};
    old.positions.reserve(e.vertices.size());
    for (std::size_t i = 0; i < e.vertices.size(); ++i) {
        old.positions.push_back(positions[e.vertices[i]]);
        positions[e.vertices[i]] = e.positions[i];
    }
    undo.records.emplace_back(std::move(old));
    // Step: the dirty ranges, one per run of consecutive vertices.
    std::vector<uint32_t> sorted = std::move(e.vertices);
    std::sort(sorted.begin(), sorted.end());
    for (std::size_t i = 0; i < sorted.size();) {
        std::size_t j = i + 1;
        while (j < sorted.size() && sorted[j] <= sorted[j - 1] + 1) ++j;
        r.dirty.points.add(sorted[i], sorted[j - 1] + 1);
        i = j;
    }
    return {};
}

Status Scene::apply_edit(ReplaceMeshTopology&& e, UndoLog& undo) {
    const MeshHandle h = find_mesh(e.mesh);
    if (h.is_null()) return unknown("mesh", e.mesh, "mesh");
    MeshRecord& r = m_meshes.at(h);
    if (Status s = check_attribute_kinds(e, r.kind, e.mesh); !s) return s;
    std::size_t vertex_count = r.positions.size();
    if (e.positions) {
        if (e.positions->empty())
            return failure(ErrorCode::EmptyMesh, "mesh has no vertices", "positions");
        if (Status s = check_vertex_array(*e.positions); !s) return s;
        vertex_count = e.positions->size();
    }
    if (Status s = check_new_topology(e, r, vertex_count); !s) return s;
    // The other attributes: whole arrays for the new vertex count; kept ones must fit it.
    if (Status s = first_failure_over_vertex_attributes(
            [&](auto a) { return check_replaced(a, e, r, vertex_count); });
        !s)
        return s;

    save_mesh(h, undo);
    if (e.motion_positions)
        m_totals.key_positions =
            m_totals.key_positions - r.motion_positions.size() + e.motion_positions->size();
    if (gives_attributes(e)) {
        if (gives_shading_attributes(e)) mark(h, MeshDirty::Attributes);
        undo::MeshAttributes old{h};
        replace_attributes(r, e, old);
        undo.records.emplace_back(std::move(old));
    }
    mark(h, MeshDirty::Topology);
    m_totals.vertices = m_totals.vertices - r.positions.size() + vertex_count;
    m_totals.triangles = m_totals.triangles - r.triangles.size() + e.triangles.size();
    undo::MeshTopology old{h, std::nullopt, r.triangles};
    if (e.positions) {
        old.positions = r.positions;
        r.positions = std::move(*e.positions);
    }
    if (e.strands) {
        old.strands = std::move(r.strands);
        r.strands = std::move(*e.strands);
    }
    r.triangles = std::move(e.triangles);
    undo.records.emplace_back(std::move(old));
    r.dirty.points.clear();
    r.dirty.points.add(0, static_cast<uint32_t>(r.positions.size()));
    return {};
}

Status Scene::apply_edit(ReplaceMeshTriangles&& e, UndoLog& undo) {
    const MeshHandle h = find_mesh(e.mesh);
    if (h.is_null()) return unknown("mesh", e.mesh, "mesh");
    MeshRecord& r = m_meshes.at(h);
    if (r.kind != MeshKind::Triangles)
        return failure(ErrorCode::InvalidArgument,
                       "mesh '" + e.mesh + "' is " + mesh_kind_name(r.kind) +
                           ": replace_triangles is for triangle meshes",
                       "mesh");
    const std::size_t n = r.triangles.size();
    if (e.first > n)
        return failure(ErrorCode::OutOfRange,
                       "first triangle " + std::to_string(e.first) + " is past the end of mesh '" +
                           e.mesh + "', which has " + std::to_string(n) + " triangles",
                       "first");
    if (e.count > n - e.first)
        return failure(ErrorCode::OutOfRange,
                       "triangles " + std::to_string(e.first) + " to " +
                           std::to_string(uint64_t(e.first) + e.count - 1) +
                           " are not all in mesh '" + e.mesh + "', which has " +
                           std::to_string(n) + " triangles",
                       "count");
    const std::size_t after = n - e.count + e.triangles.size();
    if (after == 0) return failure(ErrorCode::EmptyMesh, "mesh would have no triangles", "indices");
    if (after > MAX_MESH_ELEMENTS)
        return failure(ErrorCode::TooLarge,
                       "too many triangles (" + std::to_string(after) + ")", "indices");
    if (Status s = check_triangles(e.triangles, r.positions.size(), "indices"); !s) return s;

    save_mesh(h, undo);
    mark(h, MeshDirty::Triangles);
    const auto inserted = static_cast<uint32_t>(e.triangles.size());
    r.dirty.triangles.add(e.first, e.count, inserted);
    m_totals.triangles = m_totals.triangles - n + after;
    std::vector<Triangle>& tris = r.triangles.mut();
    const auto at = tris.begin() + std::ptrdiff_t(e.first);
    undo::MeshTriangles old{h, e.first, inserted,
                            std::vector<Triangle>(at, at + std::ptrdiff_t(e.count))};
    // Step: splice. Same counts overwrite in place; otherwise the tail moves once.
    if (e.count == inserted) {
        std::copy(e.triangles.begin(), e.triangles.end(), at);
    } else {
        tris.erase(at, at + std::ptrdiff_t(e.count));
        tris.insert(tris.begin() + std::ptrdiff_t(e.first), e.triangles.begin(),
                    e.triangles.end());
    }
    undo.records.emplace_back(std::move(old));
    return {};
}

Status Scene::apply_edit(RemoveMesh&& e, UndoLog& undo) {
    const MeshHandle h = find_mesh(e.mesh);
    if (h.is_null()) return unknown("mesh", e.mesh, "mesh");
    if (const std::size_t users = m_meshes.at(h).users.size(); users > 0)
        return failure(
            ErrorCode::InUse,
            "mesh '" + e.mesh + "' is still used by " + std::to_string(users) + " instance(s)",
            "mesh");
    remove_mesh(h, undo);
    return {};
}

void Scene::remove_mesh(MeshHandle h, UndoLog& undo) {
    MeshRecord& r = m_meshes.at(h);
    STRATA_CHECK(r.users.empty());
    // Listed by its now stale handle, so the commit releases its BLAS.
    mark(h, {});
    m_totals.vertices -= r.positions.size();
    m_totals.key_positions -= r.motion_positions.size();
    m_totals.triangles -= r.triangles.size();
    --m_totals.meshes;
    m_mesh_ids.erase(r.id, h);
    undo.records.emplace_back(undo::Removed<MeshHandle, MeshRecord>{h, m_meshes.take(h)});
}

// Step: material ops -----------------------------------------------------------------------------

Result<TextureHandle> Scene::find_material_texture(const std::optional<std::string>& id,
                                                   TextureSlot slot) const {
    if (!id) return TextureHandle{};
    const TextureHandle h = find_texture(*id);
    if (h.is_null())
        return failure(ErrorCode::UnknownId, "unknown texture '" + *id + "'",
                       std::string(TEXTURE_SLOTS[slot_index(slot)].field));
    return h;
}

Status Scene::apply_edit(AddMaterial&& e, UndoLog& undo) {
    if (Status s = check_new_id(e.id, !find_material(e.id).is_null(), "material"); !s) return s;
    if (Status s = check_material(e.material); !s) return s;
    PerTextureSlot<TextureHandle> textures;
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        const auto texture = find_material_texture(e.textures[slot_index(slot.slot)], slot.slot);
        if (!texture) return Unexpected(texture.error());
        textures[slot_index(slot.slot)] = texture.value();
    }

    bool reused = false;
    const MaterialHandle h =
        m_materials.insert(MaterialRecord{e.id, e.material, {}, textures}, &reused);
    undo.records.emplace_back(undo::Inserted<MaterialHandle>{h, reused});
    m_material_ids.insert(e.id, h);
    mark(h, MaterialDirty::Added);
    return {};
}

Status Scene::apply_edit(UpdateMaterial&& e, UndoLog& undo) {
    const MaterialHandle h = find_material(e.material);
    if (h.is_null()) return unknown("material", e.material, "material");
    MaterialRecord& r = m_materials.at(h);
    Material updated = r.material;
    apply_to(updated, e);
    if (Status s = check_material(updated); !s) return s;
    PerTextureSlot<TextureHandle> textures = r.textures;
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        const auto& set = e.textures[slot_index(slot.slot)];
        if (!set) continue;
        const auto found = find_material_texture(*set, slot.slot);
        if (!found) return Unexpected(found.error());
        textures[slot_index(slot.slot)] = found.value();
    }

    undo.records.emplace_back(undo::MaterialState{h, std::move(r.material), r.dirty, r.textures});
    r.material = std::move(updated);
    r.textures = textures;
    mark(h, MaterialDirty::Params);
    return {};
}

Status Scene::apply_edit(RemoveMaterial&& e, UndoLog& undo) {
    const MaterialHandle h = find_material(e.material);
    if (h.is_null()) return unknown("material", e.material, "material");
    // A scan keeps no user lists to maintain and undo; removing a material is rare.
    std::size_t users = 0;
    std::string first;
    const auto count = [&](const char* kind, const std::string& id) {
        if (users++ == 0) first = std::string(kind) + " '" + id + "'";
    };
    m_meshes.for_each([&](MeshHandle, const MeshRecord& m) {
        if (m.material == h) count("mesh", m.id);
    });
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        if (i.material == h) count("instance", i.id);
    });
    if (users > 0)
        return failure(ErrorCode::InUse,
                       "material '" + e.material + "' is still used by " + std::to_string(users) +
                           " mesh(es) or instance(s), e.g. " + first,
                       "material");
    remove_material(h, undo);
    return {};
}

void Scene::remove_material(MaterialHandle h, UndoLog& undo) {
    mark(h, {});
    MaterialRecord& r = m_materials.at(h);
    m_material_ids.erase(r.id, h);
    undo.records.emplace_back(
        undo::Removed<MaterialHandle, MaterialRecord>{h, m_materials.take(h)});
}

// Step: texture ops ------------------------------------------------------------------------------

Status Scene::apply_edit(AddTexture&& e, UndoLog& undo) {
    if (Status s = check_new_id(e.id, !find_texture(e.id).is_null(), "texture"); !s) return s;
    if (Status s = check_fields<TextureFields>(e); !s) return s;
    // A texture costs its texels and its file (only the image's own bytes: whatever follows its
    // end is dropped). What is left of the budget after the file bounds the decode: a huge image
    // is refused from its header, before its texels are allocated.
    const std::size_t own = image_length(e.data);
    const uint64_t encoded = own > 0 ? own : e.data.size();
    const uint64_t used = m_totals.texture_bytes + encoded;
    TextureLimits limits;
    limits.max_bytes = m_budget.max_texture_bytes > used ? m_budget.max_texture_bytes - used : 0;
    Result<TextureImage> image =
        e.decoded ? std::move(e.decoded->image) : decode_texture(e.data, limits, e.color_space);
    if (image && e.decoded) {
        const char* format = std::string_view(texture_format(e.data)) == "png" ? "PNG" : "JPEG";
        if (Status s = check_texture_size(image->width, image->height, limits, format,
                                          !image->alpha.empty());
            !s)
            image = Unexpected(std::move(s).error());
    }
    if (!image) {
        Error err = std::move(image).error();
        err.message = "texture '" + e.id + "': " + err.message;
        return Unexpected(std::move(err));
    }
    if (own > 0 && own < e.data.size()) e.data = e.data.substr(0, own);

    m_totals.texture_bytes += image.value().bytes() + e.data.size();
    TextureRecord r;
    r.id = e.id;
    r.image = std::make_shared<const TextureImage>(std::move(image).value());
    r.encoded = std::make_shared<const std::string>(std::move(e.data));
    copy_added<TextureFields>(r, e);
    bool reused = false;
    const TextureHandle h = m_textures.insert(std::move(r), &reused);
    undo.records.emplace_back(undo::Inserted<TextureHandle>{h, reused});
    m_texture_ids.insert(e.id, h);
    m_changes.mark(SceneDirty::Textures);
    return {};
}

Status Scene::apply_edit(RemoveTexture&& e, UndoLog& undo) {
    const TextureHandle h = find_texture(e.texture);
    if (h.is_null()) return unknown("texture", e.texture, "texture");
    // Materials are few next to texels; a scan keeps no user list to undo.
    std::size_t users = 0;
    std::string first;
    m_materials.for_each([&](MaterialHandle, const MaterialRecord& m) {
        if (std::find(m.textures.begin(), m.textures.end(), h) == m.textures.end()) return;
        if (users++ == 0) first = m.id;
    });
    if (users > 0)
        return failure(ErrorCode::InUse,
                       "texture '" + e.texture + "' is still used by " + std::to_string(users) +
                           " material(s), e.g. '" + first + "'",
                       "texture");
    remove_texture(h, undo);
    return {};
}

void Scene::remove_texture(TextureHandle h, UndoLog& undo) {
    TextureRecord& r = m_textures.at(h);
    m_totals.texture_bytes -= r.image->bytes() + r.encoded->size();
    m_texture_ids.erase(r.id, h);
    m_changes.mark(SceneDirty::Textures);
    undo.records.emplace_back(undo::Removed<TextureHandle, TextureRecord>{h, m_textures.take(h)});
}

// Step: instance ops -----------------------------------------------------------------------------

Status Scene::apply_edit(AddInstance&& e, UndoLog& undo) {
    if (Status s = check_new_id(e.id, !find_instance(e.id).is_null(), "instance"); !s) return s;
    const MeshHandle mesh_handle = find_mesh(e.mesh);
    if (mesh_handle.is_null()) return unknown("mesh", e.mesh, "mesh");
    MaterialHandle material;
    if (e.material) {
        material = find_material(*e.material);
        if (material.is_null()) return unknown("material", *e.material, "material");
    }
    if (Status s = check_fields<InstanceFields>(e); !s) return s;
    if (Status s = check_lod_range(e.lod_near, e.lod_far); !s) return s;
    if (Status s = check_keys(e.motion, e.animation); !s) return s;
    auto parent = find_parent(e.parent, "parent");
    if (!parent) return Unexpected(parent.error());

    InstanceRecord r;
    r.mesh = mesh_handle;
    r.material = material;
    copy_added<InstanceFields>(r, e);
    r.parent = parent.value();
    insert_instance(std::move(r), std::move(e.id), undo);
    return {};
}

void Scene::insert_instance(InstanceRecord&& r, std::string&& id, UndoLog& undo) {
    MeshRecord& mesh = m_meshes.at(r.mesh);
    r.id = id;
    r.user_slot = static_cast<uint32_t>(mesh.users.size());
    std::vector<InstanceHandle>& siblings = children_of(r.parent).instances;
    r.child_slot = static_cast<uint32_t>(siblings.size());
    bool reused = false;
    const bool animated = !r.rare->animation.empty();
    const InstanceHandle h = m_instances.insert(std::move(r), &reused);
    undo.records.emplace_back(undo::Inserted<InstanceHandle>{h, reused});
    if (animated) m_animated.push_back(h);
    mesh.users.mut().push_back(h);
    siblings.push_back(h);
    mark_instance_world(h);
    m_instance_ids.insert(id, h);
    ++m_totals.instances;
    mark(h, InstanceDirty::Added);
}

Status Scene::apply_edit(UpdateInstance&& e, UndoLog& undo) {
    const InstanceHandle h = find_instance(e.instance);
    if (h.is_null()) return unknown("instance", e.instance, "instance");
    MaterialHandle material;
    if (e.material && *e.material) {
        material = find_material(**e.material);
        if (material.is_null()) return unknown("material", **e.material, "material");
    }
    if (Status s = check_update<InstanceFields>(e); !s) return s;
    const InstanceRare& current = *m_instances.at(h).rare;
    if (Status s = check_lod_range(e.lod_near.value_or(current.lod_near),
                                   e.lod_far.value_or(current.lod_far));
        !s)
        return s;
    if (Status s = check_keys(e.motion ? *e.motion : current.motion,
                              e.animation ? *e.animation : current.animation);
        !s)
        return s;
    GroupHandle parent;
    if (e.parent) {
        auto found = find_parent(*e.parent, "parent");
        if (!found) return Unexpected(found.error());
        parent = found.value();
    }

    save_instance(h, undo);
    if (e.parent && !(parent == m_instances.at(h).parent)) reparent_instance(h, parent, undo);
    InstanceRecord& r = m_instances.at(h);
    DirtyBits<InstanceDirty> bits = apply_update<InstanceFields>(r, e);
    if (e.material) {
        r.material = material;
        bits |= InstanceDirty::Material;
    }
    if (bits.any()) mark(h, bits);
    if ((bits & (InstanceDirty::Transform | InstanceDirty::Visibility | InstanceDirty::Lod)).any())
        mark_instance_world(h);
    if (e.animation && !e.animation->empty()) m_animated.push_back(h);
    return {};
}

Status Scene::apply_edit(SetTransform&& e, UndoLog& undo) {
    const InstanceHandle h = find_instance(e.instance);
    if (h.is_null()) return unknown("instance", e.instance, "instance");
    static const FieldInfo& TRANSFORM = field_info<InstanceFields>("transform");
    if (Status s = check_value(TRANSFORM, e.transform); !s) return s;

    InstanceRecord& r = m_instances.at(h);
    undo.records.emplace_back(undo::InstanceTransform{h, r.transform, r.dirty});
    r.transform = e.transform;
    mark(h, InstanceDirty::Transform);
    mark_instance_world(h);
    return {};
}

Status Scene::apply_edit(RemoveInstance&& e, UndoLog& undo) {
    const InstanceHandle h = find_instance(e.instance);
    if (h.is_null()) return unknown("instance", e.instance, "instance");
    remove_instance(h, undo);
    return {};
}

void Scene::remove_instance(InstanceHandle h, UndoLog& undo) {
    InstanceRecord& r = m_instances.at(h);
    MeshRecord& mesh = m_meshes.at(r.mesh);
    // Swap-remove from the mesh's user list, fixing the moved instance's back index.
    std::vector<InstanceHandle>& users = mesh.users.mut();
    const InstanceHandle last = users.back();
    users[r.user_slot] = last;
    m_instances.at(last).user_slot = r.user_slot;
    users.pop_back();
    detach_child(children_of(r.parent).instances, m_instances, r.child_slot);
    // Listed by its now stale handle, so the commit takes it out of the TLAS.
    mark(h, {});
    m_instance_ids.erase(r.id, h);
    --m_totals.instances;
    undo.records.emplace_back(
        undo::Removed<InstanceHandle, InstanceRecord>{h, m_instances.take(h)});
}

// Step: scene-wide ops ---------------------------------------------------------------------------

Status Scene::apply_edit(MarkDirty&& e, UndoLog& undo) {
    if (!e.mesh) {
        m_changes.mark(e.action == DirtyAction::Refit ? SceneDirty::TlasUpdateRequested
                                                      : SceneDirty::TlasRebuildRequested);
        return {};
    }
    const MeshHandle h = find_mesh(*e.mesh);
    if (h.is_null()) return unknown("mesh", *e.mesh, "target/mesh");
    save_mesh(h, undo);
    mark(h, e.action == DirtyAction::Refit ? MeshDirty::RefitRequested
                                           : MeshDirty::RebuildRequested);
    return {};
}

// Step: light ops -------------------------------------------------------------------------------

Status Scene::apply_edit(AddLight&& e, UndoLog& undo) {
    if (Status s = check_new_id(e.id, !find_light(e.id).is_null(), "light"); !s) return s;
    if (Status s = check_light(e.light); !s) return s;
    if (m_lights.size() >= MAX_LIGHTS)
        return failure(ErrorCode::TooLarge,
                       "the scene already holds " + std::to_string(MAX_LIGHTS) +
                           " lights, the most it may",
                       "id");

    bool reused = false;
    const LightHandle h = m_lights.insert(LightRecord{e.id, e.light}, &reused);
    undo.records.emplace_back(undo::Inserted<LightHandle>{h, reused});
    m_light_ids.insert(e.id, h);
    m_changes.mark(SceneDirty::Lights);
    return {};
}

Status Scene::apply_edit(UpdateLight&& e, UndoLog& undo) {
    const LightHandle h = find_light(e.light);
    if (h.is_null()) return unknown("light", e.light, "light");
    LightRecord& r = m_lights.at(h);
    Light updated = r.light;
    apply_to(updated, e);
    if (Status s = check_light(updated); !s) return s;

    undo.records.emplace_back(undo::LightState{h, std::move(r.light)});
    r.light = std::move(updated);
    m_changes.mark(SceneDirty::Lights);
    return {};
}

Status Scene::apply_edit(RemoveLight&& e, UndoLog& undo) {
    const LightHandle h = find_light(e.light);
    if (h.is_null()) return unknown("light", e.light, "light");
    remove_light(h, undo);
    return {};
}

void Scene::remove_light(LightHandle h, UndoLog& undo) {
    m_light_ids.erase(m_lights.at(h).id, h);
    undo.records.emplace_back(undo::Removed<LightHandle, LightRecord>{h, m_lights.take(h)});
    m_changes.mark(SceneDirty::Lights);
}

// Camera, lighting and timeline are saved whole at the start of each batch (UndoLog).
Status Scene::apply_edit(SetCamera&& e, UndoLog&) {
    Camera updated = m_camera;
    apply_to(updated, e);
    if (Status s = check_camera(updated); !s) return s;
    m_camera = updated;
    m_changes.mark(SceneDirty::Camera);
    return {};
}

Status Scene::apply_edit(SetLighting&& e, UndoLog&) {
    Lighting updated = m_lighting;
    apply_to(updated, e);
    if (Status s = check_lighting(updated); !s) return s;
    m_lighting = updated;
    m_changes.mark(SceneDirty::Lighting);
    return {};
}

Status Scene::apply_edit(SetTime&& e, UndoLog&) {
    if (Status s = check_update<TimelineFields>(e); !s) return s;
    apply_to(m_timeline, e);  // the batch's flattening shows it (Scene::show)
    return {};
}

Status Scene::apply_edit(Clear&&, UndoLog& undo) {
    // Instances first: a mesh can only go once nothing uses it.
    std::vector<InstanceHandle> instances;
    instances.reserve(m_instances.size());
    m_instances.for_each([&](InstanceHandle h, const InstanceRecord&) { instances.push_back(h); });
    for (InstanceHandle h : instances) remove_instance(h, undo);
    while (!m_root.groups.empty()) remove_subtree(m_root.groups.back(), undo);
    std::vector<MeshHandle> meshes;
    m_meshes.for_each([&](MeshHandle h, const MeshRecord&) { meshes.push_back(h); });
    for (MeshHandle h : meshes) remove_mesh(h, undo);
    std::vector<MaterialHandle> materials;
    m_materials.for_each([&](MaterialHandle h, const MaterialRecord&) { materials.push_back(h); });
    for (MaterialHandle h : materials) remove_material(h, undo);
    std::vector<LightHandle> lights;
    m_lights.for_each([&](LightHandle h, const LightRecord&) { lights.push_back(h); });
    for (LightHandle h : lights) remove_light(h, undo);
    std::vector<TextureHandle> textures;
    m_textures.for_each([&](TextureHandle h, const TextureRecord&) { textures.push_back(h); });
    for (TextureHandle h : textures) remove_texture(h, undo);
    m_camera = Camera{};
    m_lighting = Lighting{};
    m_timeline = Timeline{};
    m_changes.mark(SceneDirty::Camera | SceneDirty::Lighting | SceneDirty::Materials);
    return {};
}

}  // namespace strata
