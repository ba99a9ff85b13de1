#pragma once
// The undo log of one batch. Scene::apply runs each edit's rule (check, then change) directly on
// the scene, recording here what each change overwrote; when an edit is refused, the log is
// played backwards and the scene is exactly as before the batch: records, ids, slots and their
// generations, dirty bits and change lists. A record holds what its change destroyed, moved out
// rather than copied where it can be (a removed mesh's arrays, a replaced topology), so undoing a
// batch costs about what applying it did.

#include <cstdint>
#include <optional>
#include <variant>
#include <vector>

#include "engine/scene/object_fields.h"
#include "engine/scene/scene.h"

namespace strata {

namespace undo {

/// An object the batch created: undoing frees its slot and its id.
template <class H>
struct Inserted {
    H handle;
    bool reused_slot = false;
};

/// An object the batch removed, with everything it held.
template <class H, class Record>
struct Removed {
    H handle;
    Record record;
};

/// A mesh's dirty state before an edit changed it.
struct MeshDirty {
    MeshHandle handle;
    MeshDirtyState dirty;
};

/// Vertex positions an update overwrote: `positions` held vertices [offset, offset + size).
struct MeshPositions {
    MeshHandle handle;
    uint32_t offset = 0;
    std::vector<Vec3> positions;
};

/// Vertex positions an update of listed vertices overwrote, in the order it wrote them (undone
/// in reverse, so a vertex listed twice gets its first old value back).
struct MeshVertexPositions {
    MeshHandle handle;
    std::vector<uint32_t> vertices;
    std::vector<Vec3> positions;
};

/// The whole vertex array an update replaced (shared with the scene's snapshots, never copied).
struct MeshPositionsReplaced {
    MeshHandle handle;
    CowVector<Vec3> positions;
};

/// The arrays a topology change replaced (positions only when they were replaced too).
struct MeshTopology {
    MeshHandle handle;
    std::optional<CowVector<Vec3>> positions;
    CowVector<Triangle> triangles;
    std::optional<std::vector<uint32_t>> strands = std::nullopt;  ///< a curve mesh's, if replaced
};

/// The triangles a local topology edit replaced: `triangles` stood at [first, first + size),
/// where `inserted` triangles stand now.
struct MeshTriangles {
    MeshHandle handle;
    uint32_t first = 0;
    uint32_t inserted = 0;
    std::vector<Triangle> triangles;
};

/// The vertex attributes an edit replaced (each only when that edit touched it).
struct MeshAttributes {
    MeshHandle handle;
    std::optional<std::vector<Vec3>> normals = std::nullopt;
    std::optional<std::vector<Vec2>> uvs = std::nullopt;
    std::optional<std::vector<Vec4>> tangents = std::nullopt;
    std::optional<std::vector<Vec2>> uvs1 = std::nullopt;
    std::optional<std::vector<float>> radii = std::nullopt;
    std::optional<std::vector<Vec3>> motion_positions = std::nullopt;
};

/// An instance's editable state before an edit changed it.
struct InstanceState {
    InstanceHandle handle;
    MaterialHandle material;
    FieldValues<InstanceFields> fields;
    DirtyBits<InstanceDirty> dirty;
};

/// An instance's transform before set_transform replaced it (the hot path of moving instances:
/// it saves only what that op overwrites).
struct InstanceTransform {
    InstanceHandle handle;
    Affine transform;
    DirtyBits<InstanceDirty> dirty;
};

/// A group's editable state before an edit changed it.
struct GroupState {
    GroupHandle handle;
    FieldValues<GroupFields> fields;
    DirtyBits<GroupDirty> dirty;
};

/// An instance or group moved from `old_parent`, where it was child number `old_slot`, to the
/// end of another parent's child list.
template <class H>
struct Reparented {
    H handle;
    GroupHandle old_parent;
    uint32_t old_slot = 0;
};

/// A material's values before an edit changed them.
struct MaterialState {
    MaterialHandle handle;
    Material material;
    DirtyBits<MaterialDirty> dirty;
    PerTextureSlot<TextureHandle> textures;
};

/// A light's values before an edit changed them.
struct LightState {
    LightHandle handle;
    Light light;
};

}  // namespace undo

using UndoRecord = std::variant<
    undo::Inserted<MeshHandle>, undo::Inserted<InstanceHandle>, undo::Inserted<MaterialHandle>,
    undo::Removed<MeshHandle, MeshRecord>, undo::Removed<InstanceHandle, InstanceRecord>,
    undo::Removed<MaterialHandle, MaterialRecord>, undo::MeshDirty, undo::MeshPositions,
    undo::MeshPositionsReplaced, undo::MeshTopology, undo::MeshAttributes, undo::InstanceState,
    undo::InstanceTransform, undo::MaterialState, undo::Inserted<GroupHandle>,
    undo::Removed<GroupHandle, GroupRecord>, undo::GroupState, undo::Reparented<InstanceHandle>,
    undo::Reparented<GroupHandle>, undo::Inserted<TextureHandle>,
    undo::Removed<TextureHandle, TextureRecord>, undo::Inserted<LightHandle>,
    undo::Removed<LightHandle, LightRecord>, undo::LightState, undo::MeshVertexPositions,
    undo::MeshTriangles>;

/// Everything needed to take one batch back.
struct UndoLog {
    std::vector<UndoRecord> records;
    // Scene-wide state at the start of the batch. Change lists only grow during a batch, so
    // their lengths are enough to restore them.
    Camera camera;
    Lighting lighting;
    Timeline timeline;
    MeshTotals totals;
    ChangeTracker::Position changes;
    std::size_t world_instances = 0;
    std::size_t world_groups = 0;
};

}  // namespace strata
