#pragma once
// Hydra-style dirty bits (OpenUSD pxr/imaging/hd/changeTracker.h). An edit adds bits to the
// object it touches; the ChangeTracker lists the object the first time it goes dirty, so the
// commit visits only what changed, and holds the scene-wide bits.

#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "engine/core/handle.h"
#include "engine/scene/triangle_splices.h"
#include "engine/scene/vertex_ranges.h"

namespace strata {

/// What changed in a mesh.
enum class MeshDirty : uint32_t {
    Added = 1u << 0,             ///< new mesh: needs its first build
    Points = 1u << 1,            ///< vertex positions moved, same topology
    Topology = 1u << 2,          ///< triangles (and maybe vertex count) replaced
    RefitRequested = 1u << 3,    ///< mark_dirty {mesh, refit}
    RebuildRequested = 1u << 4,  ///< mark_dirty {mesh, rebuild}
    Attributes = 1u << 5,        ///< normals or uvs changed: shading only, no BLAS work
    Triangles = 1u << 6,         ///< runs of triangles replaced (TriangleSplices), same vertices
    Keys = 1u << 7,              ///< vertex keys (motion_positions) added, removed or recounted
};

/// What changed in an instance.
enum class InstanceDirty : uint32_t {
    Added = 1u << 0,
    Transform = 1u << 1,
    Visibility = 1u << 2,
    Mask = 1u << 3,
    Material = 1u << 4,  ///< shading only
    UserId = 1u << 5,    ///< shading only
    Lod = 1u << 6,       ///< its level-of-detail range or the LOD groups above it (lod.h)
};

/// What changed in a group. All mean the same to the flattening at the end of a batch (the
/// world transforms and visibility of its subtree must be recomputed); they are kept apart for
/// reports.
enum class GroupDirty : uint32_t {
    Added = 1u << 0,
    Transform = 1u << 1,
    Parent = 1u << 2,
    Visibility = 1u << 3,
    Lod = 1u << 4,  ///< its `lod` flag or its level-of-detail range (lod.h)
};

/// What changed in a material.
enum class MaterialDirty : uint32_t {
    Added = 1u << 0,
    Params = 1u << 1,
};

/// What changed in the scene as a whole.
enum class SceneDirty : uint32_t {
    Camera = 1u << 0,
    Lighting = 1u << 1,
    TlasUpdateRequested = 1u << 2,   ///< mark_dirty {tlas, refit}
    TlasRebuildRequested = 1u << 3,  ///< mark_dirty {tlas, rebuild}
    Materials = 1u << 4,
    Groups = 1u << 5,    ///< a group was added, changed or removed (no acceleration work by itself)
    Lights = 1u << 6,    ///< a light was added, changed or removed (shading only)
    Textures = 1u << 7,  ///< a texture was added or removed (shading only, through materials)
};

/// A set of the bits of one enum above.
template <class Bit>
class DirtyBits {
public:
    constexpr DirtyBits() = default;
    constexpr DirtyBits(Bit b) : m_bits(static_cast<uint32_t>(b)) {}  // NOLINT: a bit is a set

    constexpr bool none() const { return m_bits == 0; }
    constexpr bool any() const { return m_bits != 0; }
    /// True when any bit of `other` is set here.
    constexpr bool has(DirtyBits other) const { return (m_bits & other.m_bits) != 0; }

    constexpr DirtyBits operator|(DirtyBits o) const { return raw_set(m_bits | o.m_bits); }
    constexpr DirtyBits operator&(DirtyBits o) const { return raw_set(m_bits & o.m_bits); }
    constexpr DirtyBits& operator|=(DirtyBits o) {
        m_bits |= o.m_bits;
        return *this;
    }
    friend constexpr bool operator==(DirtyBits, DirtyBits) = default;
    /// The bits as a number (for logs and test dumps).
    constexpr uint32_t value() const { return m_bits; }

private:
    static constexpr DirtyBits raw_set(uint32_t bits) {
        DirtyBits d;
        d.m_bits = bits;
        return d;
    }
    uint32_t m_bits = 0;
};

/// The scene clock's (set_time): it marks nothing itself; the batch's flattening marks the
/// animated instances that move (Scene::show).
enum class ClockDirty : uint32_t {
    Time = 1u << 0,
};

template <class T>
inline constexpr bool IS_DIRTY_BIT =
    std::is_same_v<T, MeshDirty> || std::is_same_v<T, InstanceDirty> ||
    std::is_same_v<T, GroupDirty> || std::is_same_v<T, MaterialDirty> ||
    std::is_same_v<T, SceneDirty> || std::is_same_v<T, ClockDirty>;

template <class Bit>
requires IS_DIRTY_BIT<Bit>
constexpr DirtyBits<Bit> operator|(Bit a, Bit b) {
    return DirtyBits<Bit>(a) | b;
}

/// Instance bits that change what the TLAS holds; the others only change shading.
inline constexpr DirtyBits<InstanceDirty> INSTANCE_TLAS_BITS =
    InstanceDirty::Added | InstanceDirty::Transform | InstanceDirty::Visibility |
    InstanceDirty::Mask | InstanceDirty::Lod;

/// A mesh's dirty state: its bits, the vertices whose positions changed and the triangles
/// replaced.
struct MeshDirtyState {
    DirtyBits<MeshDirty> bits;
    VertexRanges points;
    TriangleSplices triangles;

    friend bool operator==(const MeshDirtyState&, const MeshDirtyState&) = default;
};

/// The meshes, instances and materials touched since the last commit, and the scene-wide bits.
/// Removed objects stay listed by their (now stale) handle so the acceleration layer can release
/// what it built for them.
class ChangeTracker {
public:
    /// Adds `add` to an object's `bits`, listing `h` when they were clean. `add` may be empty:
    /// then the object is only listed (a removal, whose stale handle the commit must see).
    template <class H, class Bit>
    void mark(H h, DirtyBits<Bit>& bits, DirtyBits<Bit> add) {
        if (bits.none()) list_of(h).push_back(h);
        bits |= add;
    }
    /// Adds scene-wide bits.
    void mark(DirtyBits<SceneDirty> bits) { m_scene |= bits; }
    /// Counts world transforms the flattening recomputed.
    void count_world_transforms(uint64_t n = 1) { m_world_transforms += n; }

    std::span<const MeshHandle> meshes() const { return m_meshes; }
    std::span<const InstanceHandle> instances() const { return m_instances; }
    std::span<const MaterialHandle> materials() const { return m_materials; }
    DirtyBits<SceneDirty> scene() const { return m_scene; }
    /// True when any of `bits` is set scene-wide.
    bool has(DirtyBits<SceneDirty> bits) const { return m_scene.has(bits); }
    /// World transforms (groups and instances) recomputed since the last commit.
    uint64_t world_transforms() const { return m_world_transforms; }
    bool empty() const {
        return m_meshes.empty() && m_instances.empty() && m_materials.empty() && m_scene.none();
    }

    /// Where the tracker stands: lists only grow during a batch, so this is enough to go back.
    struct Position {
        std::size_t meshes = 0;
        std::size_t instances = 0;
        std::size_t materials = 0;
        DirtyBits<SceneDirty> scene;
    };
    Position position() const {
        return {m_meshes.size(), m_instances.size(), m_materials.size(), m_scene};
    }
    /// Back to `p` (a batch rolled back; the objects' own states are restored by the undo log).
    void rewind(const Position& p);
    /// Forgets every change (a commit did the work); the objects' bits are the caller's to clean.
    void clean();

private:
    std::vector<MeshHandle>& list_of(MeshHandle) { return m_meshes; }
    std::vector<InstanceHandle>& list_of(InstanceHandle) { return m_instances; }
    std::vector<MaterialHandle>& list_of(MaterialHandle) { return m_materials; }

    std::vector<MeshHandle> m_meshes;
    std::vector<InstanceHandle> m_instances;
    std::vector<MaterialHandle> m_materials;
    DirtyBits<SceneDirty> m_scene;
    uint64_t m_world_transforms = 0;
};

inline void ChangeTracker::rewind(const Position& p) {
    m_meshes.resize(p.meshes);
    m_instances.resize(p.instances);
    m_materials.resize(p.materials);
    m_scene = p.scene;
}

inline void ChangeTracker::clean() {
    m_meshes.clear();
    m_instances.clear();
    m_materials.clear();
    m_scene = {};
    m_world_transforms = 0;
}

}  // namespace strata
