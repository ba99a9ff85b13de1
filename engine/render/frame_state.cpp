#include "engine/render/frame_state.h"

#include <cmath>

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

bool FrameState::emits(const Scene& scene, uint32_t slot) const {
    if (!scene.instances().alive_at(slot) || !scene.instances().at_slot(slot).world_visible)
        return false;
    const Vec3& e = materials[instances[slot].material].emission;
    return e.x > 0.0f || e.y > 0.0f || e.z > 0.0f;
}

bool FrameState::refresh_instance(const Scene& scene, uint32_t slot) {
    if (slot >= instances.size()) {
        instances.resize(slot + 1);
        instance_ids.resize(slot + 1);
        m_emitter.resize(slot + 1, 0);
    }
    InstanceShade& shade = instances[slot];
    const bool was = m_emitter[slot] != 0;
    if (!scene.instances().alive_at(slot)) {
        shade = InstanceShade{};
        instance_ids[slot].clear();
        m_emitter[slot] = 0;
        m_emitters -= was;
        return was;
    }
    const InstanceRecord& r = scene.instances().at_slot(slot);
    instance_ids[slot] = r.id;
    MaterialHandle material = r.material;
    if (!scene.materials().contains(material)) material = scene.meshes().get(r.mesh)->material;
    shade.material = scene.materials().contains(material) ? material.index + 1 : DEFAULT_MATERIAL;
    shade.mesh_slot = r.mesh.index;
    shade.user_id = r.user_id;
    shade.normal_matrix = r.world.normal_matrix();
    const bool now = emits(scene, slot);
    m_emitter[slot] = now;
    m_emitters = m_emitters - was + now;
    return was || now;
}

void FrameState::rebuild_lights(const Scene& scene) {
    std::vector<Light> list;
    list.reserve(scene.lights().size());
    scene.lights().for_each([&](LightHandle, const LightRecord& r) { list.push_back(r.light); });
    std::vector<EmitterTriangle> emitters;
    for (uint32_t slot = 0; m_emitters > 0 && slot < m_emitter.size(); ++slot) {
        if (!m_emitter[slot]) continue;
        const InstanceRecord& inst = scene.instances().at_slot(slot);
        const MeshRecord& mesh = scene.meshes().at(inst.mesh);
        const Vec3 emission = materials[instances[slot].material].emission;
        for (const Triangle& t : mesh.triangles) {
            const Vec3 a = inst.world.transform_point(mesh.positions[t[0]]);
            const Vec3 e1 = inst.world.transform_point(mesh.positions[t[1]]) - a;
            const Vec3 e2 = inst.world.transform_point(mesh.positions[t[2]]) - a;
            const float area = 0.5f * glm::length(glm::cross(e1, e2));
            if (area > 0.0f && std::isfinite(area)) emitters.push_back({a, e1, e2, emission, area});
        }
    }
    lights.build(std::move(list), std::move(emitters));
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
    if (!r->dirty.bits.has(MeshDirty::Added | MeshDirty::Topology | MeshDirty::Attributes)) return;
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
    if (changes.has(SceneDirty::Camera)) camera = scene.camera();
    if (changes.has(SceneDirty::Lighting)) lighting = scene.lighting();
    // Emitters: an emissive material changed (every instance may have gained or lost one), an
    // instance that is or was an emitter changed, or the mesh of one did.
    bool rescan = false;
    for (MaterialHandle h : changes.materials()) {
        if (h.index + 1 >= materials.size()) {
            materials.resize(h.index + 2);
            material_textures.resize(h.index + 2);
        }
        const Material before = materials[h.index + 1];
        if (const MaterialRecord* m = scene.materials().get(h)) {
            materials[h.index + 1] = m->material;
            const TextureRecord* t = scene.textures().get(m->base_color_texture);
            material_textures[h.index + 1] = t ? t->image : nullptr;
        } else if (!scene.materials().alive_at(h.index)) {
            material_textures[h.index + 1].reset();  // removed: let its texels go
        }
        const Material& after = materials[h.index + 1];
        rescan = rescan || glm::any(glm::greaterThan(before.emission, Vec3(0.0f))) ||
                 glm::any(glm::greaterThan(after.emission, Vec3(0.0f)));
    }
    for (MeshHandle h : changes.meshes()) refresh_mesh(scene, h);
    bool emitters_changed = false;
    for (InstanceHandle h : changes.instances())
        emitters_changed = refresh_instance(scene, h.index) || emitters_changed;
    if (rescan) {
        // A material's emission changed: which instances emit is read again (O(instances), and
        // only for such edits).
        m_emitters = 0;
        for (uint32_t slot = 0; slot < m_emitter.size(); ++slot) {
            m_emitter[slot] = emits(scene, slot);
            m_emitters += m_emitter[slot];
        }
        emitters_changed = true;
    }
    for (MeshHandle h : changes.meshes()) {
        const MeshRecord* r = scene.meshes().get(h);
        if (!r || m_emitters == 0 || !r->dirty.bits.has(MeshDirty::Points | MeshDirty::Topology))
            continue;
        for (InstanceHandle user : r->users) emitters_changed = emitters_changed || is_emitter(user.index);
    }
    if (emitters_changed || changes.has(SceneDirty::Lights)) rebuild_lights(scene);
}

}  // namespace strata
