#include "engine/render/frame_state.h"

namespace strata {

void FrameState::refresh_instance(const Scene& scene, uint32_t slot) {
    if (slot >= instances.size()) instances.resize(slot + 1);
    InstanceShade& shade = instances[slot];
    if (!scene.instances().alive_at(slot)) {
        shade = InstanceShade{};
        return;
    }
    const InstanceRecord& r = scene.instances().at_slot(slot);
    MaterialHandle material = r.material;
    if (!scene.materials().contains(material)) material = scene.meshes().get(r.mesh)->material;
    shade.material = scene.materials().contains(material) ? material.index + 1 : DEFAULT_MATERIAL;
    shade.mesh_slot = r.mesh.index;
    shade.normal_matrix = r.world.normal_matrix();
}

void FrameState::refresh_mesh(const Scene& scene, MeshHandle h) {
    const MeshRecord* r = scene.meshes().get(h);
    if (!r) {
        // Removed: clear the slot unless a newer mesh already lives there.
        if (h.index < meshes.size() && !scene.meshes().alive_at(h.index)) meshes[h.index].reset();
        return;
    }
    constexpr uint32_t SHADE_BITS = dirty::MeshAdded | dirty::MeshTopology | dirty::MeshAttributes;
    if ((r->dirty & SHADE_BITS) == 0) return;
    if (h.index >= meshes.size()) meshes.resize(h.index + 1);
    if (r->normals.empty() && r->uvs.empty()) {
        meshes[h.index].reset();
        return;
    }
    meshes[h.index] =
        std::make_shared<const MeshShade>(MeshShade{r->triangles, r->normals, r->uvs});
}

void FrameState::sync(const Scene& scene) {
    const ChangeTracker& changes = scene.changes();
    version = scene.version();
    if (changes.scene_bits & dirty::Camera) camera = scene.camera();
    if (changes.scene_bits & dirty::Lighting) lighting = scene.lighting();
    for (MaterialHandle h : changes.materials) {
        if (h.index + 1 >= materials.size()) materials.resize(h.index + 2);
        if (const MaterialRecord* m = scene.materials().get(h)) materials[h.index + 1] = m->material;
    }
    for (MeshHandle h : changes.meshes) refresh_mesh(scene, h);
    for (InstanceHandle h : changes.instances) refresh_instance(scene, h.index);
}

}  // namespace strata
