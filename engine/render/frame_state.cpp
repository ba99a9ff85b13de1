#include "engine/render/frame_state.h"

namespace strata {

namespace {

/// (slot, names[slot]) for every distinct slot in `ids` but MISS_ID, sorted by slot.
std::vector<std::pair<uint32_t, std::string>> named_slots(const std::vector<uint32_t>& ids,
                                                          const std::vector<std::string>& names) {
    std::vector<bool> seen(names.size(), false);
    std::vector<std::pair<uint32_t, std::string>> out;
    for (uint32_t id : ids) {
        if (id == MISS_ID || id >= seen.size() || seen[id]) continue;
        seen[id] = true;
    }
    for (uint32_t slot = 0; slot < seen.size(); ++slot) {
        if (seen[slot]) out.emplace_back(slot, names[slot]);
    }
    return out;
}

}  // namespace

FrameIdNames FrameState::id_names(const FrameBuffers& buffers) const {
    FrameIdNames out;
    if (buffers.aovs.has(Aov::InstanceId))
        out.instances = named_slots(buffers.instance_id, instance_ids);
    if (buffers.aovs.has(Aov::MeshId)) out.meshes = named_slots(buffers.mesh_id, mesh_ids);
    return out;
}

void FrameState::refresh_instance(const Scene& scene, uint32_t slot) {
    if (slot >= instances.size()) {
        instances.resize(slot + 1);
        instance_ids.resize(slot + 1);
    }
    InstanceShade& shade = instances[slot];
    if (!scene.instances().alive_at(slot)) {
        shade = InstanceShade{};
        instance_ids[slot].clear();
        return;
    }
    const InstanceRecord& r = scene.instances().at_slot(slot);
    instance_ids[slot] = r.id;
    MaterialHandle material = r.material;
    if (!scene.materials().contains(material)) material = scene.meshes().get(r.mesh)->material;
    shade.material = scene.materials().contains(material) ? material.index + 1 : DEFAULT_MATERIAL;
    shade.mesh_slot = r.mesh.index;
    shade.user_id = r.user_id;
    shade.normal_matrix = r.world.normal_matrix();
}

void FrameState::refresh_mesh(const Scene& scene, MeshHandle h) {
    if (h.index >= mesh_ids.size()) mesh_ids.resize(h.index + 1);
    mesh_ids[h.index] = scene.meshes().alive_at(h.index) ? scene.meshes().at_slot(h.index).id : "";
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
        if (h.index + 1 >= materials.size()) {
            materials.resize(h.index + 2);
            material_textures.resize(h.index + 2);
        }
        if (const MaterialRecord* m = scene.materials().get(h)) {
            materials[h.index + 1] = m->material;
            const TextureRecord* t = scene.textures().get(m->base_color_texture);
            material_textures[h.index + 1] = t ? t->image : nullptr;
        } else if (!scene.materials().alive_at(h.index)) {
            material_textures[h.index + 1].reset();  // removed: let its texels go
        }
    }
    for (MeshHandle h : changes.meshes) refresh_mesh(scene, h);
    for (InstanceHandle h : changes.instances) refresh_instance(scene, h.index);
}

}  // namespace strata
