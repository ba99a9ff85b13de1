#pragma once
// A mesh's optional per-vertex attributes, declared once. Each is a member of the same name in
// MeshRecord (a vector, empty: none), AddMesh (the same), UpdateMeshPositions and
// ReplaceMeshTopology (an optional vector, absent: unchanged, empty: removed) and
// undo::MeshAttributes (what an edit replaced). The rules, undo, the inverse batch, the journal
// codec and the wire walk this list, so a new attribute is a new entry here plus its checks.
//
// An attribute holds one value per vertex, or, when `keyed`, the same number k >= 1 of values per
// vertex, vertex after vertex (values_per_vertex): its array is k times the vertex count.

#include <cstdint>
#include <string_view>

#include "engine/core/math.h"
#include "engine/scene/mesh_kind.h"

namespace strata {

/// Shading normals (object space, not zero).
struct NormalsAttribute {
    using Value = Vec3;
    static constexpr std::string_view name = "normals";
    static constexpr unsigned index = 0;  ///< its place in for_each_vertex_attribute's order
    /// Journal tag of the mesh edits' tagged field; 0: in their first extension layout.
    static constexpr uint8_t tag = 0;
    static constexpr bool geometric = false;  ///< true: it shapes the BLAS (a change refits)
    static constexpr bool keyed = false;
    static constexpr bool fits(MeshKind k) { return k == MeshKind::Triangles; }
    template <class S>
    static auto& of(S& s) {
        return s.normals;
    }
};

/// Texture coordinates, set 0 (glTF's TEXCOORD_0).
struct UvsAttribute {
    using Value = Vec2;
    static constexpr std::string_view name = "uvs";
    static constexpr unsigned index = 1;
    static constexpr uint8_t tag = 0;
    static constexpr bool geometric = false;
    static constexpr bool keyed = false;
    static constexpr bool fits(MeshKind k) { return k == MeshKind::Triangles; }
    template <class S>
    static auto& of(S& s) {
        return s.uvs;
    }
};

/// Texture coordinates, set 1 (glTF's TEXCOORD_1): for the material slots whose uv set is 1.
struct Uvs1Attribute {
    using Value = Vec2;
    static constexpr std::string_view name = "uvs1";
    static constexpr unsigned index = 2;
    static constexpr uint8_t tag = 33;
    static constexpr bool geometric = false;
    static constexpr bool keyed = false;
    static constexpr bool fits(MeshKind k) { return k == MeshKind::Triangles; }
    template <class S>
    static auto& of(S& s) {
        return s.uvs1;
    }
};

/// Tangents for normal maps: xyz and the bitangent's sign w (+1 or -1), glTF's TANGENT.
struct TangentsAttribute {
    using Value = Vec4;
    static constexpr std::string_view name = "tangents";
    static constexpr unsigned index = 3;
    static constexpr uint8_t tag = 32;
    static constexpr bool geometric = false;
    static constexpr bool keyed = false;
    static constexpr bool fits(MeshKind k) { return k == MeshKind::Triangles; }
    template <class S>
    static auto& of(S& s) {
        return s.tangents;
    }
};

/// The radius of each point of a points mesh or control vertex of a curve mesh (mesh_kind.h):
/// finite and > 0. Geometry, not shading: a change refits the BLAS like moved positions.
struct RadiiAttribute {
    using Value = float;
    static constexpr std::string_view name = "radii";
    static constexpr unsigned index = 4;
    static constexpr uint8_t tag = 34;
    static constexpr bool geometric = true;
    static constexpr bool keyed = false;
    static constexpr bool fits(MeshKind k) { return k != MeshKind::Triangles; }
    template <class S>
    static auto& of(S& s) {
        return s.radii;
    }
};

/// Vertex keys for deformation blur (OptiX's vertex motion keys): the positions of each vertex at
/// keys 1 to k of the frame, vertex after vertex; `positions` are key 0, and the k + 1 keys are
/// evenly spaced over ray time [0, 1] and interpolated linearly. Geometry: a change of them (or of
/// the positions) rebuilds the BLAS, as Embree 3 has no refit for motion-blur BVHs; keys added or
/// removed change its time steps (MeshDirty::Keys).
struct MotionPositionsAttribute {
    using Value = Vec3;
    static constexpr std::string_view name = "motion_positions";
    static constexpr unsigned index = 5;
    static constexpr uint8_t tag = 36;
    static constexpr bool geometric = true;
    static constexpr bool keyed = true;
    static constexpr bool fits(MeshKind) { return true; }
    template <class S>
    static auto& of(S& s) {
        return s.motion_positions;
    }
};

/// Values of attribute `A` per vertex in an array of `count` values over `vertex_count`
/// vertices: 1, or for a keyed attribute count / vertex_count (0 for none).
template <class A>
constexpr std::size_t values_per_vertex(std::size_t count, std::size_t vertex_count) {
    if constexpr (A::keyed)
        return vertex_count == 0 ? 0 : count / vertex_count;
    else
        return 1;
}

/// Calls `f` with each attribute's descriptor, in declaration order.
template <class F>
void for_each_vertex_attribute(F&& f) {
    f(NormalsAttribute{});
    f(UvsAttribute{});
    f(Uvs1Attribute{});
    f(TangentsAttribute{});
    f(RadiiAttribute{});
    f(MotionPositionsAttribute{});
}

/// Calls `f` with each attribute's descriptor until one returns a failed status; that status, or
/// success.
template <class F>
auto first_failure_over_vertex_attributes(F&& f) {
    decltype(f(NormalsAttribute{})) status{};
    for_each_vertex_attribute([&](auto a) {
        if (status) status = f(a);
    });
    return status;
}

/// Whether an update edit (UpdateMeshPositions, ReplaceMeshTopology) gives any attribute.
template <class E>
bool gives_attributes(const E& e) {
    bool any = false;
    for_each_vertex_attribute([&](auto a) { any = any || decltype(a)::of(e).has_value(); });
    return any;
}

/// Whether an update edit gives any shading attribute (one that is not geometric).
template <class E>
bool gives_shading_attributes(const E& e) {
    bool any = false;
    for_each_vertex_attribute([&](auto a) {
        if constexpr (!decltype(a)::geometric) any = any || decltype(a)::of(e).has_value();
    });
    return any;
}

}  // namespace strata
