#pragma once
// Hydra-style dirty bits (OpenUSD pxr/imaging/hd/changeTracker.h). An edit ORs bits into the
// object it touches and, the first time the object goes dirty, records its handle in the
// ChangeTracker, so the commit visits only what changed.

#include <cstdint>
#include <vector>

#include "engine/core/handle.h"

namespace strata::dirty {

enum MeshBits : uint32_t {
    MeshAdded = 1u << 0,             ///< new mesh: needs its first build
    MeshPoints = 1u << 1,            ///< vertex positions moved, same topology
    MeshTopology = 1u << 2,          ///< triangles (and maybe vertex count) replaced
    MeshRefitRequested = 1u << 3,    ///< mark_dirty {mesh, refit}
    MeshRebuildRequested = 1u << 4,  ///< mark_dirty {mesh, rebuild}
    MeshAttributes = 1u << 5,        ///< normals or uvs changed: shading only, no BLAS work
};

enum InstanceBits : uint32_t {
    InstanceAdded = 1u << 0,
    InstanceTransform = 1u << 1,
    InstanceVisibility = 1u << 2,
    InstanceMask = 1u << 3,
    InstanceMaterial = 1u << 4,  ///< shading only
    InstanceUserId = 1u << 5,    ///< shading only
};

/// A group's bits all mean the same to the flattening at the end of a batch: the world
/// transforms and visibility of its subtree must be recomputed. They are kept apart for reports.
enum GroupBits : uint32_t {
    GroupAdded = 1u << 0,
    GroupTransform = 1u << 1,
    GroupParent = 1u << 2,
    GroupVisibility = 1u << 3,
};

enum MaterialBits : uint32_t {
    MaterialAdded = 1u << 0,
    MaterialParams = 1u << 1,
};

/// Instance bits that change what the TLAS holds; the others only change shading.
constexpr uint32_t INSTANCE_TLAS_BITS =
    InstanceAdded | InstanceTransform | InstanceVisibility | InstanceMask;

enum SceneBits : uint32_t {
    Camera = 1u << 0,
    Lighting = 1u << 1,
    TlasUpdateRequested = 1u << 2,   ///< mark_dirty {tlas, refit}
    TlasRebuildRequested = 1u << 3,  ///< mark_dirty {tlas, rebuild}
    Materials = 1u << 4,
    Groups = 1u << 5,  ///< a group was added, changed or removed (no acceleration work by itself)
    Textures = 1u << 7,  ///< a texture was added or removed (shading only, through materials)
    Lights = 1u << 6,  ///< a light was added, changed or removed (shading only)
};

}  // namespace strata::dirty

namespace strata {

/// Lists of objects touched since the last commit. Removed objects stay listed by their (now
/// stale) handle so the acceleration layer can release what it built for them.
struct ChangeTracker {
    std::vector<MeshHandle> meshes;
    std::vector<InstanceHandle> instances;
    std::vector<MaterialHandle> materials;
    uint32_t scene_bits = 0;
    /// World transforms (groups and instances) recomputed by the flattening of the batches since
    /// the last commit.
    uint64_t world_transforms = 0;

    bool empty() const {
        return meshes.empty() && instances.empty() && materials.empty() && scene_bits == 0;
    }
    void reset() {
        meshes.clear();
        instances.clear();
        materials.clear();
        scene_bits = 0;
        world_transforms = 0;
    }
};

}  // namespace strata
