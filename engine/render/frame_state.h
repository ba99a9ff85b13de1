#pragma once
// What a launch reads besides the acceleration structures: camera, lighting and per-instance
// shading data. The commit copies only what changed from the scene, so launches never read the
// editable scene and edits can proceed while a frame is being traced.

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "engine/scene/scene.h"

namespace strata {

/// Index of the built-in default material in FrameState::materials.
constexpr uint32_t DEFAULT_MATERIAL = 0;

struct InstanceShade {
    uint32_t material = DEFAULT_MATERIAL;  ///< index into FrameState::materials
    uint32_t mesh_slot = 0;
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
    FrameState() { materials.push_back(Material{}); }

    /// Copies the entries the scene's change lists name.
    void sync(const Scene& scene);

    uint64_t version = 0;
    Camera camera;
    Lighting lighting;
    /// [0] is the built-in default; material slot s lives at s + 1.
    std::vector<Material> materials;
    /// Indexed by instance slot (the inst_id of a hit).
    std::vector<InstanceShade> instances;
    /// Indexed by mesh slot; null for meshes without normals and uvs.
    std::vector<std::shared_ptr<const MeshShade>> meshes;

    /// The shading attributes of the mesh in `slot`, or nullptr.
    const MeshShade* mesh_shade(uint32_t slot) const {
        return slot < meshes.size() ? meshes[slot].get() : nullptr;
    }

private:
    void refresh_instance(const Scene& scene, uint32_t slot);
    void refresh_mesh(const Scene& scene, MeshHandle h);
};

}  // namespace strata
