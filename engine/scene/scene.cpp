#include "engine/scene/scene.h"

#include <algorithm>
#include <type_traits>

namespace strata {

namespace {

template <class Map, class H>
H lookup(const Map& map, std::string_view id) {
    auto it = map.find(std::string(id));
    return it == map.end() ? H{} : it->second;
}

Error stale(const char* kind) {
    return make_error(ErrorCode::StaleHandle, std::string(kind) + " handle is stale or invalid");
}

}  // namespace

const char* edit_name(const Edit& e) {
    static constexpr const char* NAMES[] = {
        "add_mesh",        "update_mesh",  "update_mesh",     "remove_mesh",   "add_material",
        "update_material", "add_instance", "update_instance", "set_transform", "remove_instance",
        "mark_dirty",      "set_camera",   "set_lighting",    "clear"};
    static_assert(std::size(NAMES) == std::variant_size_v<Edit>);
    return NAMES[e.index()];
}

void apply_to(Camera& c, const SetCamera& e) {
    if (e.eye) c.eye = *e.eye;
    if (e.target) c.target = *e.target;
    if (e.up) c.up = *e.up;
    if (e.fov_y_deg) c.fov_y_deg = *e.fov_y_deg;
}

void apply_to(Lighting& l, const SetLighting& e) {
    if (e.sun_direction) l.sun_direction = *e.sun_direction;
    if (e.sun_color) l.sun_color = *e.sun_color;
    if (e.sky_color) l.sky_color = *e.sky_color;
    if (e.sky_intensity) l.sky_intensity = *e.sky_intensity;
}

void apply_to(Material& m, const UpdateMaterial& e) {
    if (e.base_color) m.base_color = *e.base_color;
    if (e.roughness) m.roughness = *e.roughness;
    if (e.metallic) m.metallic = *e.metallic;
    if (e.emission) m.emission = *e.emission;
}

MeshHandle Scene::find_mesh(std::string_view id) const {
    return lookup<decltype(m_mesh_ids), MeshHandle>(m_mesh_ids, id);
}
InstanceHandle Scene::find_instance(std::string_view id) const {
    return lookup<decltype(m_instance_ids), InstanceHandle>(m_instance_ids, id);
}
MaterialHandle Scene::find_material(std::string_view id) const {
    return lookup<decltype(m_material_ids), MaterialHandle>(m_material_ids, id);
}

Result<const MeshRecord*> Scene::mesh(MeshHandle h) const {
    if (const MeshRecord* r = m_meshes.get(h)) return r;
    return Unexpected(stale("mesh"));
}
Result<const InstanceRecord*> Scene::instance(InstanceHandle h) const {
    if (const InstanceRecord* r = m_instances.get(h)) return r;
    return Unexpected(stale("instance"));
}
Result<const MaterialRecord*> Scene::material(MaterialHandle h) const {
    if (const MaterialRecord* r = m_materials.get(h)) return r;
    return Unexpected(stale("material"));
}

Material Scene::resolved_material(const InstanceRecord& inst) const {
    if (const MaterialRecord* m = m_materials.get(inst.material)) return m->material;
    if (const MeshRecord* mesh = m_meshes.get(inst.mesh)) {
        if (const MaterialRecord* m = m_materials.get(mesh->material)) return m->material;
    }
    return Material{};
}

Result<uint64_t> Scene::apply(EditBatch&& batch) {
    if (Status s = validate(batch); !s) return Unexpected(s.error());
    for (Edit& e : batch.edits) apply_one(std::move(e));
    return ++m_version;
}

void Scene::apply_one(Edit&& edit) {
    std::visit([this](auto&& e) { apply_edit(std::move(e)); }, std::move(edit));
}

// Step: change tracking helpers ---------------------------------------------------------------

void Scene::mark_mesh(MeshHandle h, uint32_t bits) {
    MeshRecord& r = m_meshes.at(h);
    if (r.dirty == 0) m_changes.meshes.push_back(h);
    r.dirty |= bits;
}

void Scene::mark_instance(InstanceHandle h, uint32_t bits) {
    InstanceRecord& r = m_instances.at(h);
    if (r.dirty == 0) m_changes.instances.push_back(h);
    r.dirty |= bits;
}

void Scene::mark_material(MaterialHandle h, uint32_t bits) {
    MaterialRecord& r = m_materials.at(h);
    if (r.dirty == 0) m_changes.materials.push_back(h);
    r.dirty |= bits;
    m_changes.scene_bits |= dirty::Materials;
}

void Scene::clear_changes() {
    for (MeshHandle h : m_changes.meshes) {
        if (MeshRecord* r = m_meshes.get(h)) {
            r->dirty = 0;
            r->dirty_begin = UINT32_MAX;
            r->dirty_end = 0;
        }
    }
    for (InstanceHandle h : m_changes.instances) {
        if (InstanceRecord* r = m_instances.get(h)) r->dirty = 0;
    }
    for (MaterialHandle h : m_changes.materials) {
        if (MaterialRecord* r = m_materials.get(h)) r->dirty = 0;
    }
    m_changes.reset();
}

// Step: mesh edits -----------------------------------------------------------------------------

void Scene::apply_edit(AddMesh&& e) {
    MeshRecord r;
    r.id = e.id;
    r.positions = std::move(e.positions);
    r.triangles = std::move(e.triangles);
    r.build = e.build;
    if (e.material) r.material = find_material(*e.material);
    const MeshHandle h = m_meshes.insert(std::move(r));
    m_mesh_ids[e.id] = h;
    mark_mesh(h, dirty::MeshAdded);
}

void Scene::apply_edit(UpdateMeshPositions&& e) {
    const MeshHandle h = find_mesh(e.mesh);
    MeshRecord& r = m_meshes.at(h);
    std::copy(e.positions.begin(), e.positions.end(), r.positions.begin() + e.offset);
    const uint32_t end = e.offset + static_cast<uint32_t>(e.positions.size());
    mark_mesh(h, dirty::MeshPoints);
    r.dirty_begin = std::min(r.dirty_begin, e.offset);
    r.dirty_end = std::max(r.dirty_end, end);
}

void Scene::apply_edit(ReplaceMeshTopology&& e) {
    const MeshHandle h = find_mesh(e.mesh);
    MeshRecord& r = m_meshes.at(h);
    if (e.positions) r.positions = std::move(*e.positions);
    r.triangles = std::move(e.triangles);
    mark_mesh(h, dirty::MeshTopology);
    r.dirty_begin = 0;
    r.dirty_end = static_cast<uint32_t>(r.positions.size());
}

void Scene::remove_mesh(MeshHandle h) {
    MeshRecord& r = m_meshes.at(h);
    STRATA_CHECK(r.users.empty());
    if (r.dirty == 0) m_changes.meshes.push_back(h);
    m_mesh_ids.erase(r.id);
    m_meshes.erase(h);
}

void Scene::apply_edit(RemoveMesh&& e) {
    remove_mesh(find_mesh(e.mesh));
}

// Step: material edits -------------------------------------------------------------------------

void Scene::apply_edit(AddMaterial&& e) {
    const MaterialHandle h = m_materials.insert(MaterialRecord{e.id, e.material, 0});
    m_material_ids[e.id] = h;
    mark_material(h, dirty::MaterialAdded);
}

void Scene::apply_edit(UpdateMaterial&& e) {
    const MaterialHandle h = find_material(e.material);
    apply_to(m_materials.at(h).material, e);
    mark_material(h, dirty::MaterialParams);
}

// Step: instance edits -------------------------------------------------------------------------

void Scene::apply_edit(AddInstance&& e) {
    InstanceRecord r;
    r.id = e.id;
    r.mesh = find_mesh(e.mesh);
    if (e.material) r.material = find_material(*e.material);
    r.transform = e.transform;
    r.visible = e.visible;
    r.mask = e.mask;
    r.user_id = e.user_id;
    MeshRecord& mesh = m_meshes.at(r.mesh);
    r.user_slot = static_cast<uint32_t>(mesh.users.size());
    const InstanceHandle h = m_instances.insert(std::move(r));
    mesh.users.push_back(h);
    m_instance_ids[e.id] = h;
    mark_instance(h, dirty::InstanceAdded);
}

void Scene::apply_edit(UpdateInstance&& e) {
    const InstanceHandle h = find_instance(e.instance);
    InstanceRecord& r = m_instances.at(h);
    uint32_t bits = 0;
    if (e.material) {
        r.material = *e.material ? find_material(**e.material) : MaterialHandle{};
        bits |= dirty::InstanceMaterial;
    }
    if (e.transform) {
        r.transform = *e.transform;
        bits |= dirty::InstanceTransform;
    }
    if (e.visible) {
        r.visible = *e.visible;
        bits |= dirty::InstanceVisibility;
    }
    if (e.mask) {
        r.mask = *e.mask;
        bits |= dirty::InstanceMask;
    }
    if (e.user_id) {
        r.user_id = *e.user_id;
        bits |= dirty::InstanceUserId;
    }
    if (bits) mark_instance(h, bits);
}

void Scene::apply_edit(SetTransform&& e) {
    const InstanceHandle h = find_instance(e.instance);
    m_instances.at(h).transform = e.transform;
    mark_instance(h, dirty::InstanceTransform);
}

void Scene::remove_instance(InstanceHandle h) {
    InstanceRecord& r = m_instances.at(h);
    MeshRecord& mesh = m_meshes.at(r.mesh);
    // Swap-remove from the mesh's user list, fixing the moved instance's back index.
    const InstanceHandle last = mesh.users.back();
    mesh.users[r.user_slot] = last;
    m_instances.at(last).user_slot = r.user_slot;
    mesh.users.pop_back();
    if (r.dirty == 0) m_changes.instances.push_back(h);
    m_instance_ids.erase(r.id);
    m_instances.erase(h);
}

void Scene::apply_edit(RemoveInstance&& e) {
    remove_instance(find_instance(e.instance));
}

// Step: scene-wide edits -----------------------------------------------------------------------

void Scene::apply_edit(MarkDirty&& e) {
    if (e.mesh) {
        mark_mesh(find_mesh(*e.mesh), e.action == DirtyAction::Refit ? dirty::MeshRefitRequested
                                                                     : dirty::MeshRebuildRequested);
    } else {
        m_changes.scene_bits |= e.action == DirtyAction::Refit ? dirty::TlasUpdateRequested
                                                               : dirty::TlasRebuildRequested;
    }
}

void Scene::apply_edit(SetCamera&& e) {
    apply_to(m_camera, e);
    m_changes.scene_bits |= dirty::Camera;
}

void Scene::apply_edit(SetLighting&& e) {
    apply_to(m_lighting, e);
    m_changes.scene_bits |= dirty::Lighting;
}

void Scene::apply_edit(Clear&&) {
    std::vector<InstanceHandle> instances;
    m_instances.for_each([&](InstanceHandle h, const InstanceRecord&) { instances.push_back(h); });
    for (InstanceHandle h : instances) remove_instance(h);
    std::vector<MeshHandle> meshes;
    m_meshes.for_each([&](MeshHandle h, const MeshRecord&) { meshes.push_back(h); });
    for (MeshHandle h : meshes) remove_mesh(h);
    m_materials.for_each([&](MaterialHandle h, MaterialRecord& r) {
        if (r.dirty == 0) m_changes.materials.push_back(h);
    });
    m_materials.clear();
    m_material_ids.clear();
    m_camera = Camera{};
    m_lighting = Lighting{};
    m_changes.scene_bits |= dirty::Camera | dirty::Lighting | dirty::Materials;
}

// Step: queries --------------------------------------------------------------------------------

SceneCounts Scene::counts() const {
    SceneCounts c;
    c.meshes = m_meshes.size();
    c.instances = m_instances.size();
    c.materials = m_materials.size();
    m_meshes.for_each([&](MeshHandle, const MeshRecord& m) { c.triangles += m.triangles.size(); });
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        if (i.visible) c.instanced_triangles += m_meshes.at(i.mesh).triangles.size();
    });
    return c;
}

Bounds3 Scene::world_bounds() const {
    std::unordered_map<uint32_t, Bounds3> mesh_bounds;
    Bounds3 world;
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        if (!i.visible) return;
        auto [it, fresh] = mesh_bounds.try_emplace(i.mesh.index);
        if (fresh) {
            for (const Vec3& p : m_meshes.at(i.mesh).positions) it->second.extend(p);
        }
        world.extend(i.transform.transform_bounds(it->second));
    });
    return world;
}

EditBatch Scene::to_batch() const {
    EditBatch b;
    m_materials.for_each([&](MaterialHandle, const MaterialRecord& m) {
        b.edits.emplace_back(AddMaterial{m.id, m.material});
    });
    m_meshes.for_each([&](MeshHandle, const MeshRecord& m) {
        AddMesh e;
        e.id = m.id;
        e.positions = m.positions;
        e.triangles = m.triangles;
        e.build = m.build;
        if (const MaterialRecord* mat = m_materials.get(m.material)) e.material = mat->id;
        b.edits.emplace_back(std::move(e));
    });
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        AddInstance e;
        e.id = i.id;
        e.mesh = m_meshes.at(i.mesh).id;
        if (const MaterialRecord* mat = m_materials.get(i.material)) e.material = mat->id;
        e.transform = i.transform;
        e.visible = i.visible;
        e.mask = i.mask;
        e.user_id = i.user_id;
        b.edits.emplace_back(std::move(e));
    });
    b.edits.emplace_back(SetCamera{m_camera.eye, m_camera.target, m_camera.up, m_camera.fov_y_deg});
    b.edits.emplace_back(SetLighting{m_lighting.sun_direction, m_lighting.sun_color,
                                     m_lighting.sky_color, m_lighting.sky_intensity});
    return b;
}

}  // namespace strata
