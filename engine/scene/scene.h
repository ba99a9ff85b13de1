#pragma once
// The editable scene: flat slot arrays of meshes, instances and materials, string ids mapped to
// generational handles, dirty bits and a version. No Embree here: editing only records changes;
// the acceleration layer reads them at commit time.

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "engine/core/handle.h"
#include "engine/core/result.h"
#include "engine/scene/budget.h"
#include "engine/scene/dirty.h"
#include "engine/scene/edits.h"

namespace strata {

struct MeshRecord {
    std::string id;
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
    BuildOptions build;
    MaterialHandle material;            ///< default for its instances; null: built-in default
    std::vector<InstanceHandle> users;  ///< instances that reference this mesh
    uint32_t dirty = 0;                 ///< dirty::MeshBits since the last commit
    uint32_t dirty_begin = UINT32_MAX;  ///< vertices [dirty_begin, dirty_end) have new positions
    uint32_t dirty_end = 0;
};

struct InstanceRecord {
    std::string id;
    MeshHandle mesh;
    MaterialHandle material;  ///< null: the mesh's default
    Affine transform;
    bool visible = true;
    uint32_t mask = 0xFFFFFFFFu;
    uint32_t user_id = 0;
    uint32_t user_slot = 0;  ///< position in the mesh's `users`
    uint32_t dirty = 0;      ///< dirty::InstanceBits since the last commit
};

struct MaterialRecord {
    std::string id;
    Material material;
    uint32_t dirty = 0;
};

/// Totals for the scene endpoint and the demo.
struct SceneCounts {
    std::size_t meshes = 0;
    std::size_t instances = 0;
    std::size_t materials = 0;
    uint64_t triangles = 0;            ///< over meshes, each counted once
    uint64_t instanced_triangles = 0;  ///< over visible instances
};

struct UndoLog;

class Scene {
public:
    /// Applies every edit of `batch` in order, each checked against the scene as the earlier
    /// edits of the batch left it (one rule per op, in scene_rules.cpp), and increments the
    /// version by one. The first refused edit comes back as an Error with its index, and the
    /// edits before it are undone: the scene is then exactly as before the call, slots and
    /// handles included. Large arrays are moved out of the batch.
    ///
    /// `before_done`, when given, runs once every edit passed, with the version the batch is
    /// about to produce (the journal writes its record there); its error undoes the batch too.
    Result<uint64_t> apply(EditBatch&& batch,
                           const std::function<Status(uint64_t)>& before_done = nullptr);

    /// Recovery only: the version a restored snapshot had (the scene must be freshly loaded).
    void restore_version(uint64_t version) { m_version = version; }

    /// The budget every later batch must leave the scene within (TooLarge beyond it).
    void set_budget(const SceneBudget& budget) { m_budget = budget; }
    /// What the meshes hold now.
    const MeshTotals& mesh_totals() const { return m_totals; }

    /// Incremented once per applied batch.
    uint64_t version() const { return m_version; }

    MeshHandle find_mesh(std::string_view id) const;
    InstanceHandle find_instance(std::string_view id) const;
    MaterialHandle find_material(std::string_view id) const;

    /// The record, or a StaleHandle error for a removed or never-issued handle.
    Result<const MeshRecord*> mesh(MeshHandle h) const;
    Result<const InstanceRecord*> instance(InstanceHandle h) const;
    Result<const MaterialRecord*> material(MaterialHandle h) const;

    const SlotArray<MeshRecord, MeshTag>& meshes() const { return m_meshes; }
    const SlotArray<InstanceRecord, InstanceTag>& instances() const { return m_instances; }
    const SlotArray<MaterialRecord, MaterialTag>& materials() const { return m_materials; }
    const Camera& camera() const { return m_camera; }
    const Lighting& lighting() const { return m_lighting; }

    /// The material an instance shades with: its own, else its mesh's, else the built-in one.
    Material resolved_material(const InstanceRecord& inst) const;

    SceneCounts counts() const;
    /// World-space bounds over visible instances (computed on demand, O(vertices)).
    Bounds3 world_bounds() const;

    /// A batch that builds this scene's current state from an empty scene.
    EditBatch to_batch() const;

    /// What changed since the last commit; the commit reads it and then calls clear_changes().
    const ChangeTracker& changes() const { return m_changes; }
    /// Resets every dirty bit and list. Called by the commit once its work is done.
    void clear_changes();

private:
    // One rule per op: check the edit against the scene as it is now, then change the scene,
    // recording in `undo` what the change overwrote (scene_rules.cpp).
    Status apply_edit(AddMesh&& e, UndoLog& undo);
    Status apply_edit(UpdateMeshPositions&& e, UndoLog& undo);
    Status apply_edit(ReplaceMeshTopology&& e, UndoLog& undo);
    Status apply_edit(RemoveMesh&& e, UndoLog& undo);
    Status apply_edit(AddMaterial&& e, UndoLog& undo);
    Status apply_edit(UpdateMaterial&& e, UndoLog& undo);
    Status apply_edit(AddInstance&& e, UndoLog& undo);
    Status apply_edit(UpdateInstance&& e, UndoLog& undo);
    Status apply_edit(SetTransform&& e, UndoLog& undo);
    Status apply_edit(RemoveInstance&& e, UndoLog& undo);
    Status apply_edit(MarkDirty&& e, UndoLog& undo);
    Status apply_edit(SetCamera&& e, UndoLog& undo);
    Status apply_edit(SetLighting&& e, UndoLog& undo);
    Status apply_edit(Clear&& e, UndoLog& undo);

    /// Plays `undo` backwards (scene_undo.cpp).
    void roll_back(UndoLog& undo);

    /// Dirty-bit helpers. The `undo` forms first record the object's dirty state.
    void mark_mesh(MeshHandle h, uint32_t bits, UndoLog& undo);
    void mark_instance(InstanceHandle h, uint32_t bits);
    void mark_material(MaterialHandle h, uint32_t bits);
    void save_instance(InstanceHandle h, UndoLog& undo) const;
    void remove_instance(InstanceHandle h, UndoLog& undo);
    void remove_mesh(MeshHandle h, UndoLog& undo);
    void remove_material(MaterialHandle h, UndoLog& undo);

    SlotArray<MeshRecord, MeshTag> m_meshes;
    SlotArray<InstanceRecord, InstanceTag> m_instances;
    SlotArray<MaterialRecord, MaterialTag> m_materials;
    std::unordered_map<std::string, MeshHandle> m_mesh_ids;
    std::unordered_map<std::string, InstanceHandle> m_instance_ids;
    std::unordered_map<std::string, MaterialHandle> m_material_ids;
    Camera m_camera;
    Lighting m_lighting;
    ChangeTracker m_changes;
    uint64_t m_version = 0;
    SceneBudget m_budget;
    MeshTotals m_totals;
};

}  // namespace strata
