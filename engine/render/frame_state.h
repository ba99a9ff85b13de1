#pragma once
// What a launch reads besides the acceleration structures: camera, lighting and per-instance
// shading data. The commit copies only what changed from the scene, so launches never read the
// editable scene and edits can proceed while a frame is being traced.

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/accel/ray.h"
#include "engine/core/boxed.h"
#include "engine/image/texture.h"
#include "engine/render/frame.h"
#include "engine/render/light_table.h"
#include "engine/scene/scene.h"

namespace strata {

/// Index of the built-in default material in FrameState::materials.
constexpr uint32_t DEFAULT_MATERIAL = 0;

/// An instance's world-space motion keys over the frame (at least two).
struct ShadeMotion {
    std::vector<Affine> keys;
    MotionInterpolation interpolation = MotionInterpolation::Linear;
};

struct InstanceShade {
    uint32_t material = DEFAULT_MATERIAL;  ///< index into FrameState::materials
    uint32_t mesh_slot = 0;
    uint32_t user_id = 0;           ///< the client's number, for the user_id AOV
    glm::mat3 normal_matrix{1.0f};  ///< object-to-world for normals (without motion)
    Boxed<ShadeMotion> motion;      ///< empty: still over the frame (nearly every instance)

    /// Object-to-world for normals at ray time `time`.
    glm::mat3 normals_at(float time) const {
        return motion ? motion_at(motion->keys, time, motion->interpolation).normal_matrix()
                      : normal_matrix;
    }
};

/// A mesh's per-vertex shading attributes with the triangles that index them: copied at commit,
/// and only for meshes that have normals or uvs (the others shade with geometric normals).
struct MeshShade {
    std::vector<Triangle> triangles;
    std::vector<Vec3> normals;  ///< empty: geometric normals
    std::vector<Vec2> uvs;      ///< empty: none
    std::vector<Vec2> uvs1;     ///< the second texture coordinate set; empty: none
    /// Tangent frames for normal maps when the mesh has normals and uvs: its own tangents, or
    /// else made (tangents.h) from the positions of the commit that changed its topology or
    /// attributes: a commit that only moves vertices keeps them, as it keeps the normals.
    std::vector<glm::vec4> tangents;

    /// The interpolated normal of triangle `prim` at barycentrics (u, v) (Embree's: weight u on
    /// the second vertex, v on the third), in object space, not normalised.
    Vec3 normal(uint32_t prim, float u, float v) const {
        const Triangle& t = triangles[prim];
        return (1.0f - u - v) * normals[t[0]] + u * normals[t[1]] + v * normals[t[2]];
    }
    /// The texture coordinate set `set` reads (0: uvs, 1: uvs1), or the other one when the
    /// mesh lacks it; null when it has neither.
    const std::vector<Vec2>* uv_set(uint32_t set) const {
        const std::vector<Vec2>* first = set == 1 ? &uvs1 : &uvs;
        const std::vector<Vec2>* other = set == 1 ? &uvs : &uvs1;
        return !first->empty() ? first : !other->empty() ? other : nullptr;
    }
    /// The interpolated texture coordinate of triangle `prim` at (u, v) in `set`'s coordinates
    /// (one of uv_set()'s answers).
    Vec2 uv(const std::vector<Vec2>& set, uint32_t prim, float u, float v) const {
        const Triangle& t = triangles[prim];
        return (1.0f - u - v) * set[t[0]] + u * set[t[1]] + v * set[t[2]];
    }
    /// The interpolated tangent (xyz, not normalised) and handedness (w) of triangle `prim`.
    glm::vec4 tangent(uint32_t prim, float u, float v) const {
        const Triangle& t = triangles[prim];
        return (1.0f - u - v) * tangents[t[0]] + u * tangents[t[1]] + v * tangents[t[2]];
    }
};

/// A material's textures as launches read them, by TextureSlot (null: none). Textures are
/// immutable and cannot be removed while a material names them, so sharing the texels is safe.
using MaterialTextures = PerTextureSlot<std::shared_ptr<const TextureImage>>;

/// A material at one surface point: its factors times its textures there.
struct SurfaceMaterial {
    /// base_color, roughness, metallic and emission with their textures applied.
    Material material;
    float occlusion = 1.0f;  ///< multiplies light that arrives by bounces
    /// The normal map's tangent-space normal, scaled by normal_scale (not normalised); valid
    /// when `normal_mapped`.
    Vec3 tangent_normal{0.0f, 0.0f, 1.0f};
    bool normal_mapped = false;
};

class FrameState {
public:
    FrameState() {
        materials.push_back(Material{});
        material_textures.emplace_back();
        emitter_emission.emplace_back(0.0f);
    }

    /// Copies the entries the scene's change lists name.
    void sync(const Scene& scene);

    uint64_t version = 0;
    Camera camera;
    Lighting lighting;
    /// The clock the animated instances show (Scene::shown_clock), set by every commit.
    Timeline clock;
    /// [0] is the built-in default; material slot s lives at s + 1. Without their names
    /// (launches copy a hit's material; picks name things from the scene).
    std::vector<Material> materials;
    /// The textures of each entry of `materials`.
    std::vector<MaterialTextures> material_textures;
    /// The emission the light table gives each entry of `materials`: its emission times the
    /// mean of its emissive texture (next-event estimation sees a textured emitter as uniform).
    std::vector<Vec3> emitter_emission;
    /// Indexed by instance slot (the inst_id of a hit).
    std::vector<InstanceShade> instances;
    /// Indexed by mesh slot; null for meshes without normals and uvs.
    std::vector<std::shared_ptr<const MeshShade>> meshes;
    /// Client ids by instance slot and by mesh slot ("" for a free slot): launches name the
    /// slots their id AOVs hold without reading the editable scene.
    std::vector<std::string> instance_ids;
    std::vector<std::string> mesh_ids;
    /// The scene's lights and emitting triangles, rebuilt only by commits that change a light or
    /// something an emitter depends on (its instance, mesh or material).
    LightTable lights;

    /// True when instance slot `slot` is visible and its material emits: its triangles are in
    /// `lights`, so bounce rays that reach it weigh its emission by MIS.
    bool is_emitter(uint32_t slot) const {
        return slot < m_emitter.size() && m_emitter[slot] != 0;
    }
    /// How many instance slots is_emitter().
    std::size_t emitter_instances() const { return m_emitters; }

    /// Material `material` (an index into `materials`) at a hit on the mesh `mesh` (nullptr:
    /// no attributes) at barycentrics (u, v) of triangle `prim`: its factors, times its textures
    /// where it has them and the mesh has uvs (glTF's channels: metallic-roughness G and B,
    /// occlusion R).
    SurfaceMaterial surface(uint32_t material, const MeshShade* mesh, uint32_t prim, float u,
                            float v) const;

    /// The coverage of material `material` at a hit as surface() would see it: alpha times the
    /// base-colour texture's alpha.
    float coverage(uint32_t material, const MeshShade* mesh, uint32_t prim, float u,
                   float v) const;

    /// The hit test that applies the materials' alpha modes (mask and blend), or nullopt when
    /// every material is opaque. It refers to this state: launches take it with the state.
    std::optional<HitTest> hit_test() const;

    /// The shading attributes of the mesh in `slot`, or nullptr.
    const MeshShade* mesh_shade(uint32_t slot) const {
        return slot < meshes.size() ? meshes[slot].get() : nullptr;
    }

    /// The client ids of the slots in `buffers`' instance_id and mesh_id AOVs (this state must
    /// be the one the buffers were traced from).
    FrameIdNames id_names(const FrameBuffers& buffers) const;

private:
    /// What refreshing instances did to the emitter table.
    struct EmitterChange {
        int64_t count = 0;     ///< emitters gained minus emitters lost
        bool touched = false;  ///< one of them is or was an emitter

        EmitterChange operator+(const EmitterChange& o) const {
            return {count + o.count, touched || o.touched};
        }
    };
    /// Refreshes the shading data of the instance in `slot` (the tables already reach it).
    EmitterChange refresh_instance(const Scene& scene, uint32_t slot);
    /// Refreshes every listed instance; returns whether one of them is or was an emitter.
    bool refresh_instances(const Scene& scene, std::span<const InstanceHandle> handles);
    /// Whether the instance in `slot` should be an emitter now (the slot's shade is current).
    bool emits(const Scene& scene, uint32_t slot) const;
    void rebuild_lights(const Scene& scene);
    void refresh_mesh(const Scene& scene, MeshHandle h);

    /// Refreshes the material entry `index` (a slot + 1) from the scene.
    void refresh_material(const Scene& scene, MaterialHandle h);

    std::vector<uint8_t> m_emitter;  ///< by instance slot
    std::size_t m_emitters = 0;      ///< slots set in m_emitter
    std::size_t m_see_through = 0;   ///< entries of `materials` whose alpha mode is not opaque
};

}  // namespace strata
