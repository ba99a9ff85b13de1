#pragma once
// What a launch reads besides the acceleration structures: camera, lighting and per-instance
// shading data. The commit copies only what changed from the scene, so launches never read the
// editable scene and edits can proceed while a frame is being traced.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/render/frame.h"
#include "engine/render/light_table.h"
#include "engine/scene/scene.h"

namespace strata {

/// Index of the built-in default material in FrameState::materials.
constexpr uint32_t DEFAULT_MATERIAL = 0;

struct InstanceShade {
    uint32_t material = DEFAULT_MATERIAL;  ///< index into FrameState::materials
    uint32_t mesh_slot = 0;
    uint32_t user_id = 0;           ///< the client's number, for the user_id AOV
    glm::mat3 normal_matrix{1.0f};  ///< object-to-world for normals
};

/// A mesh's per-vertex shading attributes with the triangles that index them: copied at commit,
/// and only for meshes that have normals or uvs (the others shade with geometric normals).
struct MeshShade {
    std::vector<Triangle> triangles;
    std::vector<Vec3> normals;  ///< empty: geometric normals
    std::vector<Vec2> uvs;      ///< empty: none

    /// The interpolated normal of triangle `prim` at barycentrics (u, v) (Embree's: weight u on
    /// the second vertex, v on the third), in object space, not normalised.
    Vec3 normal(uint32_t prim, float u, float v) const {
        const Triangle& t = triangles[prim];
        return (1.0f - u - v) * normals[t[0]] + u * normals[t[1]] + v * normals[t[2]];
    }
    /// The interpolated texture coordinate of triangle `prim` at (u, v).
    Vec2 uv(uint32_t prim, float u, float v) const {
        const Triangle& t = triangles[prim];
        return (1.0f - u - v) * uvs[t[0]] + u * uvs[t[1]] + v * uvs[t[2]];
    }
};

class FrameState {
public:
    FrameState() {
        materials.push_back(Material{});
        material_textures.emplace_back();
    }

    /// Copies the entries the scene's change lists name.
    void sync(const Scene& scene);

    uint64_t version = 0;
    Camera camera;
    Lighting lighting;
    /// [0] is the built-in default; material slot s lives at s + 1.
    std::vector<Material> materials;
    /// The base-colour texture of each entry of `materials` (null: none). Textures are immutable
    /// and cannot be removed while a material names them, so sharing the texels is safe.
    std::vector<std::shared_ptr<const TextureImage>> material_textures;
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

    /// The base colour of material `material` (an index into `materials`) at a hit on the mesh
    /// `mesh` (nullptr: no uvs) at barycentrics (u, v) of triangle `prim`: the material's colour,
    /// times its texture where it has one and the mesh has uvs.
    Vec3 base_color(uint32_t material, const MeshShade* mesh, uint32_t prim, float u,
                    float v) const {
        const Material& m = materials[material];
        const TextureImage* tex = material_textures[material].get();
        if (!tex || !mesh || mesh->uvs.empty() || prim >= mesh->triangles.size())
            return m.base_color;
        return m.base_color * tex->sample(mesh->uv(prim, u, v), m.base_color_sampler);
    }

    /// The shading attributes of the mesh in `slot`, or nullptr.
    const MeshShade* mesh_shade(uint32_t slot) const {
        return slot < meshes.size() ? meshes[slot].get() : nullptr;
    }

    /// The client ids of the slots in `buffers`' instance_id and mesh_id AOVs (this state must
    /// be the one the buffers were traced from).
    FrameIdNames id_names(const FrameBuffers& buffers) const;

private:
    /// Refreshes an instance's shading data; returns true when it is or was an emitter.
    bool refresh_instance(const Scene& scene, uint32_t slot);
    /// Whether the instance in `slot` should be an emitter now (the slot's shade is current).
    bool emits(const Scene& scene, uint32_t slot) const;
    void rebuild_lights(const Scene& scene);
    void refresh_mesh(const Scene& scene, MeshHandle h);

    std::vector<uint8_t> m_emitter;  ///< by instance slot
    std::size_t m_emitters = 0;      ///< slots set in m_emitter
};

}  // namespace strata
