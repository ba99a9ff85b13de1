#pragma once
// The editable scene: flat slot arrays of meshes, instances, materials, groups and lights, string ids mapped to
// generational handles, dirty bits and a version. No Embree here: editing only records changes;
// the acceleration layer reads them at commit time.

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/boxed.h"
#include "engine/core/cow.h"
#include "engine/core/handle.h"
#include "engine/core/id_index.h"
#include "engine/core/result.h"
#include "engine/image/texture.h"
#include "engine/scene/budget.h"
#include "engine/scene/dirty.h"
#include "engine/scene/edits.h"

namespace strata {

struct MeshRecord {
    std::string id;
    // The arrays are copy-on-write (engine/core/cow.h): a snapshot shares them, and an edit
    // either replaces a whole array (no copy) or writes in place through mut().
    CowVector<Vec3> positions;
    CowVector<Triangle> triangles;
    std::vector<Vec3> normals;  ///< per-vertex shading normals (object space); empty: none
    std::vector<Vec2> uvs;      ///< per-vertex texture coordinates; empty: none
    std::vector<Vec2> uvs1;      ///< a second set of texture coordinates; empty: none
    std::vector<Vec4> tangents;  ///< per-vertex tangents (xyz, w: handedness); empty: made
    BuildOptions build;
    MaterialHandle material;          ///< default for its instances; null: built-in default
    CowVector<InstanceHandle> users;  ///< instances that reference this mesh
    MeshDirtyState dirty;             ///< since the last commit
    std::string name = {};            ///< display name (object_fields.h)
    MeshKind kind = MeshKind::Triangles;  ///< mesh_kind.h; fixed when the mesh is added
    CurveBasis basis = CurveBasis::Linear;
    CurveStyle style = CurveStyle::Round;
    std::vector<float> radii;        ///< points and curves: one per vertex; triangles: empty
    /// Vertex keys 1..k over the frame, k per vertex (vertex_attributes.h); empty: still.
    std::vector<Vec3> motion_positions;
    std::vector<uint32_t> strands;   ///< curves: control vertices per strand; others: empty

    /// Its object-space bounds over the frame: the vertices at every key, grown by their radii
    /// for points and curves (a curve's control vertices bound its segments in every basis
    /// Strata has).
    Bounds3 bounds() const;
    /// Its vertex keys over the frame: 1 (still), or 1 + the motion positions per vertex.
    std::size_t motion_keys() const {
        return 1 + values_per_vertex<MotionPositionsAttribute>(motion_positions.size(),
                                                               positions.size());
    }
    /// Position of vertex `v` at key `key` (key < motion_keys()).
    const Vec3& key_position(std::size_t key, std::size_t v) const {
        return key == 0 ? positions[v] : motion_positions[v * (motion_keys() - 1) + key - 1];
    }
    /// Its primitives: triangles, points or curve segments.
    std::size_t primitive_count() const {
        switch (kind) {
            case MeshKind::Points: return positions.size();
            case MeshKind::Curves: return curve_segment_count(basis, strands);
            default: return triangles.size();
        }
    }
};

/// Deepest a group may sit: the groups on the path from the root to any group, itself included.
/// Beyond it add_group and reparenting are refused (TooLarge).
constexpr uint32_t MAX_GROUP_DEPTH = 64;

/// The direct children of a group (or of the root), in the order they joined; removal swaps the
/// last child into the hole, and each child keeps its position (`child_slot`).
struct Children {
    std::vector<GroupHandle> groups;
    std::vector<InstanceHandle> instances;

    bool empty() const { return groups.empty() && instances.empty(); }
};

/// An instance's fields that nearly every instance leaves at their defaults (a million instances
/// hold one pointer each instead): held in InstanceRecord::rare, allocated by the first value
/// set that is not a default.
struct InstanceRare {
    std::string name;            ///< display name (object_fields.h)
    std::vector<Affine> motion;  ///< motion keys in its own space (object_fields.h)
    float lod_near = 0.0f;       ///< under an LOD group: where it is drawn (lod.h)
    float lod_far = LOD_NO_LIMIT;
    MotionInterpolation motion_interpolation = MotionInterpolation::Linear;  ///< of its keys
    bool animation_loop = false;  ///< its animation repeats (animation.h)
    /// Keyframes at scene times (animation.h); non-empty: they, not `transform`, place it.
    std::vector<Keyframe> animation;
    /// Its world keys over the frame (animation.h: its keys and its groups' composed): what the
    /// TLAS interpolates, as `world_interpolation` says (empty: still during the frame).
    std::vector<Affine> world_motion;
    MotionInterpolation world_interpolation = MotionInterpolation::Linear;  ///< of world_motion
    /// The LOD groups above it and their conditions, from the flattening (lod.h).
    LodBands world_lod;
};

struct InstanceRecord {
    std::string id;
    MeshHandle mesh;
    MaterialHandle material;  ///< null: the mesh's default
    Affine transform;         ///< relative to the parent group (world when at the root)
    bool visible = true;      ///< its own flag; hidden too when a group above it is hidden
    bool world_visible = true;
    GroupHandle parent;       ///< null: the root
    uint32_t child_slot = 0;  ///< position in the parent's `Children::instances`
    /// Product of the ancestors' transforms and its own, and whether it and every ancestor are
    /// visible: what the TLAS and shading use. Brought up to date at the end of each applied
    /// batch for the subtrees that batch dirtied.
    Affine world;
    uint32_t mask = 0xFFFFFFFFu;
    uint32_t user_id = 0;
    uint32_t user_slot = 0;  ///< position in the mesh's `users`
    DirtyBits<InstanceDirty> dirty;  ///< since the last commit
    Boxed<InstanceRare> rare;
};

/// A scene-graph node: its transform and visibility apply to everything below it.
struct GroupRecord {
    std::string id;
    GroupHandle parent;       ///< null: the root
    uint32_t child_slot = 0;  ///< position in the parent's `Children::groups`
    Affine transform;         ///< relative to the parent
    bool visible = true;
    Affine world;  ///< as for InstanceRecord::world
    bool world_visible = true;
    Children children;
    DirtyBits<GroupDirty> dirty;  ///< until the batch's flattening
    std::string name = {};        ///< display name (object_fields.h)
    std::string asset = {};       ///< the file it was imported from; empty: not an asset
    bool lod = false;                   ///< its children are levels (lod.h)
    float lod_near = 0.0f;              ///< under an LOD group: where it is drawn (lod.h)
    float lod_far = LOD_NO_LIMIT;
    LodBands world_lod = {};  ///< as for InstanceRecord::world_lod
    std::vector<Affine> motion = {};  ///< as an instance's (object_fields.h)
    MotionInterpolation motion_interpolation = MotionInterpolation::Linear;
    std::vector<Keyframe> animation = {};
    bool animation_loop = false;
    /// Its world keys over the frame, as InstanceRecord::world_motion (empty: still).
    std::vector<Affine> world_keys = {};
    MotionInterpolation world_interpolation = MotionInterpolation::Linear;
};

/// The rarely set fields of an instance (its box) or of a group (the record itself), for code
/// shared by both kinds.
inline const InstanceRare& rare_of(const InstanceRecord& r) {
    return *r.rare;
}
inline const GroupRecord& rare_of(const GroupRecord& g) {
    return g;
}

struct MaterialRecord {
    std::string id;
    Material material;
    DirtyBits<MaterialDirty> dirty;
    PerTextureSlot<TextureHandle> textures;  ///< by TextureSlot; null: none
};

/// A decoded texture. Textures are immutable once added (remove and add again to change one), so
/// launches share the decoded texels with the scene.
struct TextureRecord {
    std::string id;
    std::shared_ptr<const TextureImage> image;
    /// The PNG or JPEG bytes it was decoded from: what a snapshot writes.
    std::shared_ptr<const std::string> encoded;
    std::string name = {};  ///< display name (object_fields.h)
    TextureColorSpace color_space = TextureColorSpace::Srgb;  ///< how it was decoded
};

struct LightRecord {
    std::string id;
    Light light;
};

/// Checks the id of an object about to be added (the id rule of engine/core/utf8.h, then that no
/// object of its kind has it); the error names field `id`.
Status check_new_id(const std::string& id, bool taken, const char* kind);

/// Most lights a scene may hold (TooLarge beyond): launches copy and sample the whole list.
constexpr std::size_t MAX_LIGHTS = 4096;

/// Totals for the scene endpoint and the demo.
struct SceneCounts {
    std::size_t meshes = 0;
    std::size_t instances = 0;
    std::size_t materials = 0;
    std::size_t groups = 0;
    std::size_t lights = 0;
    std::size_t textures = 0;
    uint64_t triangles = 0;            ///< over meshes, each counted once
    uint64_t instanced_triangles = 0;  ///< over visible instances
};

struct UndoLog;

/// A consistent copy of a scene's state (Scene::image()). Its slot arrays and mesh buffers are
/// shared copy-on-write with the scene, so taking one costs an atomic increment per chunk of
/// slots, and it stays readable on another thread while the scene goes on being edited.
struct SceneImage {
    SlotArray<MeshRecord, MeshTag> meshes;
    SlotArray<InstanceRecord, InstanceTag> instances;
    SlotArray<MaterialRecord, MaterialTag> materials;
    SlotArray<GroupRecord, GroupTag> groups;
    SlotArray<LightRecord, LightTag> lights;
    SlotArray<TextureRecord, TextureTag> textures;
    std::vector<GroupHandle> root_groups;  ///< the root's child groups, in order
    Camera camera;
    Lighting lighting;
    uint64_t version = 0;
    Timeline timeline = {};

    /// A batch that builds this state from an empty scene.
    EditBatch to_batch() const;
};

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
    ///
    /// `inverse`, when given, receives the batch that takes this one back (inverse_batch.h).
    Result<uint64_t> apply(EditBatch&& batch,
                           const std::function<Status(uint64_t)>& before_done = nullptr,
                           EditBatch* inverse = nullptr);

    /// Recovery only: the version a restored snapshot had (the scene must be freshly loaded).
    void restore_version(uint64_t version) { m_version = version; }

    /// Snapshot restore: adds one edit of a snapshot's scene straight into the storage, checked
    /// by the same rule as apply() but with no undo log kept and no version bump. A refused edit
    /// leaves the scene part-built: the caller discards it (reset()). End with finish_load().
    Status load(Edit&& edit);
    /// Ends a load: checks the budget over the whole scene and sets the snapshot's version.
    Status finish_load(uint64_t version);
    /// Back to an empty scene at version 0 (the budget is kept).
    void reset();

    /// The budget every later batch must leave the scene within (TooLarge beyond it).
    void set_budget(const SceneBudget& budget) { m_budget = budget; }
    /// What the meshes hold now.
    const MeshTotals& mesh_totals() const { return m_totals; }

    /// Incremented once per applied batch.
    uint64_t version() const { return m_version; }

    MeshHandle find_mesh(std::string_view id) const;
    InstanceHandle find_instance(std::string_view id) const;
    MaterialHandle find_material(std::string_view id) const;
    GroupHandle find_group(std::string_view id) const;
    LightHandle find_light(std::string_view id) const;
    TextureHandle find_texture(std::string_view id) const;

    /// The record, or a StaleHandle error for a removed or never-issued handle.
    Result<const MeshRecord*> mesh(MeshHandle h) const;
    Result<const InstanceRecord*> instance(InstanceHandle h) const;
    Result<const MaterialRecord*> material(MaterialHandle h) const;
    Result<const GroupRecord*> group(GroupHandle h) const;
    Result<const TextureRecord*> texture(TextureHandle h) const;

    const SlotArray<MeshRecord, MeshTag>& meshes() const { return m_meshes; }
    const SlotArray<InstanceRecord, InstanceTag>& instances() const { return m_instances; }
    const SlotArray<MaterialRecord, MaterialTag>& materials() const { return m_materials; }
    const SlotArray<GroupRecord, GroupTag>& groups() const { return m_groups; }
    const SlotArray<LightRecord, LightTag>& lights() const { return m_lights; }
    const SlotArray<TextureRecord, TextureTag>& textures() const { return m_textures; }
    /// The children of group `parent`, or of the root when `parent` is null (a live handle).
    const Children& children(GroupHandle parent) const;
    /// Ids of the groups from the root down to `parent` (empty for the root). O(depth).
    std::vector<std::string> group_path(GroupHandle parent) const;
    const Camera& camera() const { return m_camera; }
    const Lighting& lighting() const { return m_lighting; }
    /// The scene's clock (set_time).
    const Timeline& timeline() const { return m_timeline; }
    /// The clock the animated instances' world transforms show: the scene's after each batch; a
    /// launch may show another time (Engine: a render's `time`) until the next.
    const Timeline& shown_clock() const { return m_shown; }
    /// Brings every animated instance to `clock` (marking those whose world moves), when it is
    /// not the clock they show: the cost follows the animated instances, never the scene.
    void show(const Timeline& clock);

    /// The material an instance shades with: its own, else its mesh's, else the built-in one.
    Material resolved_material(const InstanceRecord& inst) const;

    SceneCounts counts() const;
    /// Bytes the scene holds for its instances, from sizes and capacities: their slots, the heap
    /// parts of their id and name strings, the id map's nodes and buckets, and their entries in
    /// the mesh-user and child lists. O(instances). The TLAS and the commit's per-slot tables are
    /// not counted (Engine::memory_bytes has the TLAS).
    uint64_t instance_bytes() const;
    /// World-space bounds over visible instances (computed on demand, O(vertices)).
    Bounds3 world_bounds() const;

    /// A batch that builds this scene's current state from an empty scene.
    EditBatch to_batch() const { return image().to_batch(); }
    /// The scene's state, shared copy-on-write: cheap enough to take under the scene lock.
    SceneImage image() const;

    /// What changed since the last commit; the commit reads it and then calls clear_changes().
    const ChangeTracker& changes() const { return m_changes; }
    /// Resets every dirty bit and list. Called by the commit once its work is done.
    void clear_changes();

private:
    // One rule per op: check the edit against the scene as it is now, then change the scene,
    // recording in `undo` what the change overwrote (scene_rules.cpp).
    Status apply_edit(AddMesh&& e, UndoLog& undo);
    Status apply_edit(UpdateMeshPositions&& e, UndoLog& undo);
    Status apply_edit(UpdateMeshVertices&& e, UndoLog& undo);
    Status apply_edit(ReplaceMeshTopology&& e, UndoLog& undo);
    Status apply_edit(ReplaceMeshTriangles&& e, UndoLog& undo);
    Status apply_edit(RemoveMesh&& e, UndoLog& undo);
    Status apply_edit(AddMaterial&& e, UndoLog& undo);
    Status apply_edit(UpdateMaterial&& e, UndoLog& undo);
    Status apply_edit(RemoveMaterial&& e, UndoLog& undo);
    Status apply_edit(AddInstance&& e, UndoLog& undo);
    Status apply_edit(UpdateInstance&& e, UndoLog& undo);
    Status apply_edit(SetTransform&& e, UndoLog& undo);
    Status apply_edit(RemoveInstance&& e, UndoLog& undo);
    Status apply_edit(MarkDirty&& e, UndoLog& undo);
    Status apply_edit(SetCamera&& e, UndoLog& undo);
    Status apply_edit(SetLighting&& e, UndoLog& undo);
    Status apply_edit(SetTime&& e, UndoLog& undo);
    Status apply_edit(Clear&& e, UndoLog& undo);
    Status apply_edit(AddGroup&& e, UndoLog& undo);
    Status apply_edit(UpdateGroup&& e, UndoLog& undo);
    Status apply_edit(RemoveGroup&& e, UndoLog& undo);
    Status apply_edit(AddLight&& e, UndoLog& undo);
    Status apply_edit(UpdateLight&& e, UndoLog& undo);
    Status apply_edit(RemoveLight&& e, UndoLog& undo);
    Status apply_edit(AddTexture&& e, UndoLog& undo);
    Status apply_edit(RemoveTexture&& e, UndoLog& undo);
    // Bulk instance ops (bulk_rules.cpp): each item checked as its single edit would be.
    Status apply_edit(AddInstances&& e, UndoLog& undo);
    Status apply_edit(UpdateInstances&& e, UndoLog& undo);
    Status apply_edit(RemoveInstances&& e, UndoLog& undo);

    /// Plays `undo` backwards (scene_undo.cpp).
    void roll_back(UndoLog& undo);

    /// Adds `add` to an object's dirty bits (`add` empty: only lists it, as a removal needs).
    /// Undo is the same for every kind: a rule saves an object's state, dirty state included,
    /// before it changes the object (save_mesh, save_instance, save_group, MaterialState), and
    /// marking records nothing; new objects need no save, removed ones are kept whole.
    void mark(MeshHandle h, DirtyBits<MeshDirty> add);
    void mark(InstanceHandle h, DirtyBits<InstanceDirty> add);
    void mark(MaterialHandle h, DirtyBits<MaterialDirty> add);
    void mark(GroupHandle g, DirtyBits<GroupDirty> add);
    void save_mesh(MeshHandle h, UndoLog& undo) const;
    void save_instance(InstanceHandle h, UndoLog& undo) const;
    /// Adds a checked instance under its id: `r` holds everything but its id and back indices.
    void insert_instance(InstanceRecord&& r, std::string&& id, UndoLog& undo);
    void remove_instance(InstanceHandle h, UndoLog& undo);
    void remove_mesh(MeshHandle h, UndoLog& undo);
    void remove_material(MaterialHandle h, UndoLog& undo);
    void remove_light(LightHandle h, UndoLog& undo);
    void remove_texture(TextureHandle h, UndoLog& undo);
    /// Resolves an optional texture id of a material edit for `slot` (the error names its field).
    Result<TextureHandle> find_material_texture(const std::optional<std::string>& id,
                                                TextureSlot slot) const;

    // Scene graph helpers (scene_graph.cpp).
    Children& children_of(GroupHandle parent);
    /// Resolves an optional parent id (field `field` in errors).
    Result<GroupHandle> find_parent(const std::optional<std::string>& id, const char* field) const;
    /// Checks that group `g` may move under `parent`: no cycle, depth within MAX_GROUP_DEPTH.
    Status check_group_move(GroupHandle g, GroupHandle parent) const;
    /// Moves an instance or a group to another parent's child list, recording the undo step.
    void reparent_instance(InstanceHandle h, GroupHandle parent, UndoLog& undo);
    void reparent_group(GroupHandle g, GroupHandle parent, UndoLog& undo);
    void save_group(GroupHandle g, UndoLog& undo) const;
    void mark_instance_world(InstanceHandle h) { m_world_instances.push_back(h); }
    void remove_group(GroupHandle g, UndoLog& undo);
    /// Removes `g`, the groups and the instances below it (children before parents).
    void remove_subtree(GroupHandle g, UndoLog& undo);
    /// Recomputes the world transform and visibility of every dirty subtree and dirty instance
    /// (Hydra's transform flattening, incremental): runs once per applied batch, costs what the
    /// batch dirtied, and marks the instances whose world changed for the TLAS; then shows the
    /// scene's clock (show()).
    void flatten();
    /// flatten() without the clock: the subtrees and instances marked so far.
    void flatten_marked();
    /// What flatten() is about to compose, checked first and changing nothing: every world
    /// transform the batch's dirty groups and instances will get must be finite (each local
    /// one is, but a chain of groups can multiply past float range). The error names the chain.
    Status check_world_transforms() const;
    /// "'a' > 'b' > 'c'": the groups from the root down to `g`.
    std::string group_chain(GroupHandle g) const;
    /// Recomputes one instance's world from its parent's; marks it when it changed.
    void refresh_instance_world(InstanceHandle h, InstanceRecord& r);
    /// Whether `g` or a group above it is dirty (its world is about to be recomputed).
    bool under_dirty(GroupHandle g) const;
    /// Recomputes one group's world from its parent's and cleans it.
    void refresh_group_world(GroupRecord& group);

    SlotArray<MeshRecord, MeshTag> m_meshes;
    SlotArray<InstanceRecord, InstanceTag> m_instances;
    SlotArray<MaterialRecord, MaterialTag> m_materials;
    SlotArray<GroupRecord, GroupTag> m_groups;
    SlotArray<LightRecord, LightTag> m_lights;
    SlotArray<TextureRecord, TextureTag> m_textures;
    Children m_root;
    /// Instances and groups whose world the next flatten() must recompute (groups: those whose
    /// `dirty` went from 0). Both only grow during a batch, so undo restores their lengths.
    std::vector<InstanceHandle> m_world_instances;
    std::vector<GroupHandle> m_world_groups;
    IdIndex<GroupHandle> m_group_ids;
    IdIndex<MeshHandle> m_mesh_ids;
    IdIndex<InstanceHandle> m_instance_ids;
    IdIndex<MaterialHandle> m_material_ids;
    IdIndex<LightHandle> m_light_ids;
    IdIndex<TextureHandle> m_texture_ids;
    Camera m_camera;
    Lighting m_lighting;
    Timeline m_timeline;
    Timeline m_shown;  ///< shown_clock()
    /// Every instance and group with an animation, and perhaps some that lost theirs or are
    /// gone (show() drops those): the only objects a clock change visits.
    std::vector<InstanceHandle> m_animated;
    std::vector<GroupHandle> m_animated_groups;
    ChangeTracker m_changes;
    uint64_t m_version = 0;
    SceneBudget m_budget;
    MeshTotals m_totals;
};

}  // namespace strata
