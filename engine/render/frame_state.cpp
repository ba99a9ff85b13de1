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

void FrameState::sync(const Scene& scene) {
    const ChangeTracker& changes = scene.changes();
    version = scene.version();
    if (changes.scene_bits & dirty::Camera) camera = scene.camera();
    if (changes.scene_bits & dirty::Lighting) lighting = scene.lighting();
    for (MaterialHandle h : changes.materials) {
        if (h.index + 1 >= materials.size()) materials.resize(h.index + 2);
        if (const MaterialRecord* m = scene.materials().get(h)) materials[h.index + 1] = m->material;
    }
    for (InstanceHandle h : changes.instances) refresh_instance(scene, h.index);
}

}  // namespace strata
