#pragma once
// Edits are plain structs (pbrt-v4's SceneEntity idea): the protocol layer fills them from JSON,
// the scene validates a whole batch and only then applies it. Objects are named by their
// client-facing string ids; the scene maps ids to handles.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "engine/scene/types.h"
#include "engine/scene/vertex_attributes.h"

namespace strata {

struct DecodedTexture;  // engine/image/texture_decode.h

struct AddMesh {
    std::string id;
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
    BuildOptions build;
    std::optional<std::string> material;  ///< default material of the mesh's instances
    std::vector<Vec3> normals = {};       ///< per-vertex shading normals; empty: none
    std::vector<Vec2> uvs = {};           ///< per-vertex texture coordinates; empty: none
    std::vector<Vec2> uvs1 = {};          ///< a second set (TEXCOORD_1); empty: none
    /// Per-vertex tangents for normal maps (xyz, w = +1 or -1 the bitangent's sign); empty:
    /// made at commit in the MikkTSpace convention (engine/render/tangents.h).
    std::vector<Vec4> tangents = {};
    std::string name = {};                ///< display name (object_fields.h)
    MeshKind kind = MeshKind::Triangles;  ///< mesh_kind.h; triangles need `triangles` only
    CurveBasis basis = CurveBasis::Linear;
    CurveStyle style = CurveStyle::Round;
    std::vector<float> radii = {};        ///< points and curves: one per vertex
    /// Vertex keys 1..k for deformation blur, vertex after vertex (vertex_attributes.h).
    std::vector<Vec3> motion_positions = {};
    std::vector<uint32_t> strands = {};   ///< curves: control vertices per strand
};

/// New vertex data for vertices [offset, offset + n): positions (empty: unchanged) and, when set,
/// its other attributes (vertex_attributes.h) over their own length from the same offset. The
/// vertex count is unchanged. A mesh without an attribute takes it only whole (offset 0, one per
/// vertex); an empty array removes it. Only positions touch the BLAS.
struct UpdateMeshPositions {
    std::string mesh;
    uint32_t offset = 0;
    std::vector<Vec3> positions;
    std::optional<std::vector<Vec3>> normals = std::nullopt;
    std::optional<std::vector<Vec2>> uvs = std::nullopt;
    std::optional<std::vector<Vec4>> tangents = std::nullopt;
    std::optional<std::vector<Vec2>> uvs1 = std::nullopt;
    std::optional<std::vector<float>> radii = std::nullopt;
    std::optional<std::vector<Vec3>> motion_positions = std::nullopt;
};

/// New positions for listed vertices: vertex `vertices[i]` takes `positions[i]` (a vertex listed
/// twice takes its last position). Scattered edits, a brush stroke, in one edit: the commit
/// refits what the listed vertices touch (one cluster each, on a clustered BLAS).
struct UpdateMeshVertices {
    std::string mesh;
    std::vector<uint32_t> vertices;
    std::vector<Vec3> positions;
};

/// New triangles, and optionally a whole new vertex array (which may change the vertex count),
/// with whole new attributes (vertex_attributes.h) when set (empty: removed). A vertex count
/// change must bring a new array of each attribute the mesh has. For points `triangles` stays
/// empty; for curves too, with `strands` when they change (a count change must bring them).
struct ReplaceMeshTopology {
    std::string mesh;
    std::optional<std::vector<Vec3>> positions;
    std::vector<Triangle> triangles;
    std::optional<std::vector<Vec3>> normals = std::nullopt;
    std::optional<std::vector<Vec2>> uvs = std::nullopt;
    std::optional<std::vector<Vec4>> tangents = std::nullopt;
    std::optional<std::vector<Vec2>> uvs1 = std::nullopt;
    std::optional<std::vector<float>> radii = std::nullopt;
    std::optional<std::vector<Vec3>> motion_positions = std::nullopt;
    /// A curve mesh's new strands (mesh_kind.h); absent: unchanged.
    std::optional<std::vector<uint32_t>> strands = std::nullopt;
};

/// A local topology edit: triangles [first, first + count) are replaced by `triangles` (any
/// number, none to cut a hole); the triangles after them move by triangles.size() - count. The
/// vertices stay as they are. On a clustered BLAS the commit rebuilds only the clusters that held
/// the replaced triangles (clustered_blas.h).
struct ReplaceMeshTriangles {
    std::string mesh;
    uint32_t first = 0;
    uint32_t count = 0;
    std::vector<Triangle> triangles;
};

struct RemoveMesh {
    std::string mesh;
};

struct AddMaterial {
    std::string id;
    Material material;
    /// A texture id per slot (TEXTURE_SLOTS); nullopt: none.
    PerTextureSlot<std::optional<std::string>> textures = {};
};

/// Removes a material; refused while a mesh (as its default) or an instance uses it.
struct RemoveMaterial {
    std::string material;
};

struct UpdateMaterial {
    std::string material;
    std::optional<Vec3> base_color;
    std::optional<float> roughness;
    std::optional<float> metallic;
    std::optional<Vec3> emission;
    /// Per slot (TEXTURE_SLOTS): set to a texture id; set to nullopt: no texture any more.
    PerTextureSlot<std::optional<std::optional<std::string>>> textures = {};
    std::optional<TextureWrap> wrap = std::nullopt;
    std::optional<TextureFilter> filter = std::nullopt;
    std::optional<std::string> name = std::nullopt;
    std::optional<float> alpha = std::nullopt;
    std::optional<AlphaMode> alpha_mode = std::nullopt;
    std::optional<float> alpha_cutoff = std::nullopt;
    std::optional<float> normal_scale = std::nullopt;
    std::optional<float> occlusion_strength = std::nullopt;
    std::optional<bool> unlit = std::nullopt;
    std::optional<uint32_t> base_color_uv_set = std::nullopt;
    std::optional<uint32_t> metallic_roughness_uv_set = std::nullopt;
    std::optional<uint32_t> normal_uv_set = std::nullopt;
    std::optional<uint32_t> occlusion_uv_set = std::nullopt;
    std::optional<uint32_t> emissive_uv_set = std::nullopt;
};

/// A texture from PNG or JPEG bytes (the format is read from the bytes). Decoded when the edit is
/// applied, as `color_space` says; the encoded bytes are kept for snapshots.
struct AddTexture {
    std::string id;
    std::string data;
    std::string name = {};  ///< display name (object_fields.h)
    TextureColorSpace color_space = TextureColorSpace::Srgb;
    /// `data` decoded ahead, outside the scene lock (Engine::apply); never on the wire. The rule
    /// decodes `data` itself when this is empty.
    std::shared_ptr<DecodedTexture> decoded = {};
};

/// Removes a texture; refused while a material refers to it.
struct RemoveTexture {
    std::string texture;
};

struct AddInstance {
    std::string id;
    std::string mesh;
    std::optional<std::string> material;  ///< overrides the mesh's default material
    Affine transform;
    bool visible = true;
    uint32_t mask = 0xFFFFFFFFu;
    uint32_t user_id = 0;
    std::optional<std::string> parent;  ///< a group id; nullopt: the root
    std::string name = {};              ///< display name (object_fields.h)
    std::vector<Affine> motion = {};    ///< motion keys (object_fields.h); empty: none
    float lod_near = 0.0f;              ///< under an LOD group (lod.h; object_fields.h)
    float lod_far = LOD_NO_LIMIT;
    MotionInterpolation motion_interpolation = MotionInterpolation::Linear;
    std::vector<Keyframe> animation = {};  ///< keyframes (animation.h); empty: none
    bool animation_loop = false;
};

struct UpdateInstance {
    std::string instance;
    /// Set: a material id overrides; set to nullopt: back to the mesh's default material.
    std::optional<std::optional<std::string>> material;
    std::optional<Affine> transform;
    std::optional<bool> visible;
    std::optional<uint32_t> mask;
    std::optional<uint32_t> user_id;
    /// Set: a group id moves the instance under that group; set to nullopt: to the root.
    std::optional<std::optional<std::string>> parent;
    std::optional<std::string> name = std::nullopt;
    std::optional<std::vector<Affine>> motion = std::nullopt;  ///< [] removes the keys
    std::optional<float> lod_near = std::nullopt;
    std::optional<float> lod_far = std::nullopt;
    std::optional<MotionInterpolation> motion_interpolation = std::nullopt;
    std::optional<std::vector<Keyframe>> animation = std::nullopt;  ///< [] removes it
    std::optional<bool> animation_loop = std::nullopt;
};

struct SetTransform {
    std::string instance;
    Affine transform;
};

struct RemoveInstance {
    std::string instance;
};

/// Most items one bulk edit may carry (TooLarge beyond).
constexpr uint64_t MAX_BULK_ITEMS = uint64_t(1) << 24;

/// The ids of a bulk edit's items: a list, or a numbered range, `prefix` followed by the decimal
/// numbers `first` .. `first + count - 1` ("tree-", 0, 3: tree-0, tree-1, tree-2). One form only:
/// a list with a non-zero count is refused. No items (an empty list, count 0) is allowed and does
/// nothing.
struct BulkIds {
    std::vector<std::string> list;
    std::string prefix;
    uint64_t first = 0;
    uint64_t count = 0;

    std::size_t size() const {
        return list.empty() ? static_cast<std::size_t>(count) : list.size();
    }
    /// The id of item `i` (< size()).
    std::string at(std::size_t i) const {
        return list.empty() ? prefix + std::to_string(first + i) : list[i];
    }
};

/// Many new instances in one edit (bulk instancing: forests, crowds, particles). Item i takes
/// `ids.at(i)`, mesh `meshes[i]` (or `meshes[0]` when it holds one), material `materials[i]`
/// (one: all; none: the mesh's default) and `transforms[i]` (none: identity). Checked and applied
/// as the same number of add_instance edits would be; an error names its item.
struct AddInstances {
    BulkIds ids;
    std::vector<std::string> meshes;
    std::vector<std::string> materials = {};
    std::vector<Affine> transforms = {};
    std::optional<std::string> parent = std::nullopt;  ///< a group id; nullopt: the root
    bool visible = true;
};

/// New transforms and/or visibility for many instances: item i takes `transforms[i]` (empty:
/// unchanged) and `visible` (nullopt: unchanged).
struct UpdateInstances {
    BulkIds ids;
    std::vector<Affine> transforms = {};
    std::optional<bool> visible = std::nullopt;
};

/// Removes many instances.
struct RemoveInstances {
    BulkIds ids;
};

enum class DirtyAction : uint8_t { Refit, Rebuild };

/// Asks the next commit to refit or rebuild one mesh's BLAS, or to update or rebuild the TLAS.
struct MarkDirty {
    std::optional<std::string> mesh;  ///< nullopt: the TLAS
    DirtyAction action = DirtyAction::Rebuild;
};

/// Camera fields to change; unset fields keep their value.
struct SetCamera {
    std::optional<Vec3> eye;
    std::optional<Vec3> target;
    std::optional<Vec3> up;
    std::optional<float> fov_y_deg;
    std::optional<float> shutter_open = std::nullopt;
    std::optional<float> shutter_close = std::nullopt;
};

/// Timeline fields to change (set_time): the scene's time and the frame duration.
struct SetTime {
    std::optional<float> time = std::nullopt;
    std::optional<float> frame_duration = std::nullopt;
};

/// Lighting fields to change; unset fields keep their value.
struct SetLighting {
    std::optional<Vec3> sun_direction;
    std::optional<Vec3> sun_color;
    std::optional<Vec3> sky_color;
    std::optional<float> sky_intensity;
};

/// Removes every mesh, instance, material, texture, group and light and resets camera and
/// lighting.
struct Clear {};

/// A new group: a node of the scene graph whose transform and visibility apply to everything
/// below it.
struct AddGroup {
    std::string id;
    std::optional<std::string> parent;  ///< a group id; nullopt: the root
    Affine transform;
    bool visible = true;
    std::string name = {};   ///< display name (object_fields.h)
    std::string asset = {};  ///< the file it was imported from (object_fields.h)
    bool lod = false;                   ///< a level-of-detail group (lod.h)
    float lod_near = 0.0f;              ///< under an LOD group (lod.h; object_fields.h)
    float lod_far = LOD_NO_LIMIT;
    std::vector<Affine> motion = {};    ///< motion keys (object_fields.h); empty: none
    MotionInterpolation motion_interpolation = MotionInterpolation::Linear;
    std::vector<Keyframe> animation = {};  ///< keyframes (animation.h); empty: none
    bool animation_loop = false;
};

/// Changes some of a group's fields.
struct UpdateGroup {
    std::string group;
    /// Set: a group id moves this group (with its subtree) under it; set to nullopt: to the root.
    std::optional<std::optional<std::string>> parent;
    std::optional<Affine> transform;
    std::optional<bool> visible;
    std::optional<std::string> name = std::nullopt;
    std::optional<std::string> asset = std::nullopt;
    std::optional<bool> lod = std::nullopt;
    std::optional<float> lod_near = std::nullopt;
    std::optional<float> lod_far = std::nullopt;
    std::optional<std::vector<Affine>> motion = std::nullopt;  ///< [] removes the keys
    std::optional<MotionInterpolation> motion_interpolation = std::nullopt;
    std::optional<std::vector<Keyframe>> animation = std::nullopt;  ///< [] removes it
    std::optional<bool> animation_loop = std::nullopt;
};

/// Removes a group; refused while it has children unless `recursive`, which removes the whole
/// subtree, instances included.
struct RemoveGroup {
    std::string group;
    bool recursive = false;
};

/// A new light (types.h: Light).
struct AddLight {
    std::string id;
    Light light;
};

/// Light fields to change; unset fields keep their value.
struct UpdateLight {
    std::string light;
    std::optional<LightKind> kind;
    std::optional<Vec3> position;
    std::optional<Vec3> direction;
    std::optional<Vec3> color;
    std::optional<float> intensity;
    std::optional<float> angle_deg;
    std::optional<float> inner_angle_deg;
    std::optional<float> width;
    std::optional<float> height;
    std::optional<std::string> name = std::nullopt;
};

struct RemoveLight {
    std::string light;
};

using Edit = std::variant<AddMesh, UpdateMeshPositions, ReplaceMeshTopology, RemoveMesh,
                          AddMaterial, UpdateMaterial, AddInstance, UpdateInstance, SetTransform,
                          RemoveInstance, MarkDirty, SetCamera, SetLighting, Clear, AddGroup,
                          UpdateGroup, RemoveGroup, AddLight, UpdateLight, RemoveLight,
                          AddTexture, RemoveTexture, UpdateMeshVertices, RemoveMaterial,
                          AddInstances, UpdateInstances, RemoveInstances, ReplaceMeshTriangles,
                          SetTime>;

/// Copies the fields an edit sets onto a full value; unset fields keep theirs.
void apply_to(Camera& c, const SetCamera& e);
void apply_to(Lighting& l, const SetLighting& e);
void apply_to(Timeline& t, const SetTime& e);
void apply_to(Material& m, const UpdateMaterial& e);
void apply_to(Light& l, const UpdateLight& e);

/// What a batch is in the scene's history (engine/scene/edit_history.h): a client's edits, or the
/// undo or redo of an earlier batch.
enum class BatchKind : uint8_t { Edits, Undo, Redo };

/// Longest message a batch may carry, in bytes.
constexpr std::size_t MAX_BATCH_MESSAGE_BYTES = 1024;

/// A batch's place in the history: journaled with it, never applied to the scene.
struct BatchInfo {
    BatchKind kind = BatchKind::Edits;
    uint64_t target = 0;  ///< Undo and Redo: the version whose batch this takes back or redoes
    int64_t time_ms = 0;  ///< when it was applied (Unix ms); 0: stamped by Engine::apply
    std::string message;  ///< the client's note (text, at most MAX_BATCH_MESSAGE_BYTES)

    bool empty() const {
        return kind == BatchKind::Edits && target == 0 && time_ms == 0 && message.empty();
    }
};

/// Edits applied atomically: all or none.
struct EditBatch {
    std::vector<Edit> edits;
    BatchInfo info = {};
};

}  // namespace strata
