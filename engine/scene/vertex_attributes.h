#pragma once
// A mesh's optional per-vertex attributes, declared once. Each is a member of the same name in
// MeshRecord (a vector, empty: none), AddMesh (the same), UpdateMeshPositions and
// ReplaceMeshTopology (an optional vector, absent: unchanged, empty: removed) and
// undo::MeshAttributes (what an edit replaced). The rules, undo, the inverse batch, the journal
// codec and the wire walk this list, so a new attribute is a new entry here plus its checks.

#include <cstdint>
#include <string_view>

#include "engine/core/math.h"

namespace strata {

/// Shading normals (object space, not zero).
struct NormalsAttribute {
    using Value = Vec3;
    static constexpr std::string_view name = "normals";
    static constexpr unsigned index = 0;  ///< its place in for_each_vertex_attribute's order
    /// Journal tag of the mesh edits' tagged field; 0: in their first extension layout.
    static constexpr uint8_t tag = 0;
    static constexpr bool geometric = false;  ///< true: it shapes the BLAS (a change refits)
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
    template <class S>
    static auto& of(S& s) {
        return s.radii;
    }
};

/// Calls `f` with each attribute's descriptor, in declaration order.
template <class F>
void for_each_vertex_attribute(F&& f) {
    f(NormalsAttribute{});
    f(UvsAttribute{});
    f(Uvs1Attribute{});
    f(TangentsAttribute{});
    f(RadiiAttribute{});
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
