#pragma once
// What a launch reads besides the acceleration structures: camera, lighting and per-instance
// shading data. The commit copies only what changed from the scene, so launches never read the
// editable scene and edits can proceed while a frame is being traced.

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/render/frame.h"
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
    /// Client ids by instance slot and by mesh slot ("" for a free slot): launches name the
    /// slots their id AOVs hold without reading the editable scene.
    std::vector<std::string> instance_ids;
    std::vector<std::string> mesh_ids;

    /// The client ids of the slots in `buffers`' instance_id and mesh_id AOVs (this state must
    /// be the one the buffers were traced from).
    FrameIdNames id_names(const FrameBuffers& buffers) const;

private:
    void refresh_instance(const Scene& scene, uint32_t slot);
    void refresh_mesh(const Scene& scene, uint32_t slot);
};

}  // namespace strata
