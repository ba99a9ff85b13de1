#include "engine/scene/scene.h"

#include <algorithm>

#include "engine/core/utf8.h"
#include "engine/scene/bulk_packing.h"
#include "engine/scene/inverse_batch.h"
#include "engine/scene/object_fields.h"
#include "engine/scene/undo_log.h"

namespace strata {

namespace {

Error stale(const char* kind) {
    return make_error(ErrorCode::StaleHandle, std::string(kind) + " handle is stale or invalid");
}

}  // namespace

void apply_to(Camera& c, const SetCamera& e) {
    apply_update<CameraFields>(c, e);
}

void apply_to(Lighting& l, const SetLighting& e) {
    apply_update<LightingFields>(l, e);
}

void apply_to(Timeline& t, const SetTime& e) {
    apply_update<TimelineFields>(t, e);
}

void apply_to(Light& l, const UpdateLight& e) {
    apply_update<LightFields>(l, e);
}

void apply_to(Material& m, const UpdateMaterial& e) {
    apply_update<MaterialFields>(m, e);
    if (e.wrap) m.base_color_sampler.wrap = *e.wrap;
    if (e.filter) m.base_color_sampler.filter = *e.filter;
}

MeshHandle Scene::find_mesh(std::string_view id) const {
    return m_mesh_ids.find(id, m_meshes);
}
InstanceHandle Scene::find_instance(std::string_view id) const {
    return m_instance_ids.find(id, m_instances);
}
MaterialHandle Scene::find_material(std::string_view id) const {
    return m_material_ids.find(id, m_materials);
}
GroupHandle Scene::find_group(std::string_view id) const {
    return m_group_ids.find(id, m_groups);
}
LightHandle Scene::find_light(std::string_view id) const {
    return m_light_ids.find(id, m_lights);
}
TextureHandle Scene::find_texture(std::string_view id) const {
    return m_texture_ids.find(id, m_textures);
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
Result<const GroupRecord*> Scene::group(GroupHandle h) const {
    if (const GroupRecord* r = m_groups.get(h)) return r;
    return Unexpected(stale("group"));
}
Result<const TextureRecord*> Scene::texture(TextureHandle h) const {
    if (const TextureRecord* r = m_textures.get(h)) return r;
    return Unexpected(stale("texture"));
}

Material Scene::resolved_material(const InstanceRecord& inst) const {
    if (const MaterialRecord* m = m_materials.get(inst.material)) return m->material;
    if (const MeshRecord* mesh = m_meshes.get(inst.mesh)) {
        if (const MaterialRecord* m = m_materials.get(mesh->material)) return m->material;
    }
    return Material{};
}

Result<uint64_t> Scene::apply(EditBatch&& batch,
                             const std::function<Status(uint64_t)>& before_done,
                             EditBatch* inverse) {
    if (const char* why = text_problem(batch.info.message, MAX_BATCH_MESSAGE_BYTES))
        return failure(ErrorCode::InvalidArgument,
                       std::string("the batch's message ") + why +
                           (batch.info.message.size() > MAX_BATCH_MESSAGE_BYTES
                                ? " (at most " + std::to_string(MAX_BATCH_MESSAGE_BYTES) + " bytes)"
                                : std::string()),
                       "message");
    UndoLog undo;
    undo.camera = m_camera;
    undo.lighting = m_lighting;
    undo.timeline = m_timeline;
    undo.changes = m_changes.position();
    undo.totals = m_totals;
    undo.world_instances = m_world_instances.size();
    undo.world_groups = m_world_groups.size();
    // The budget applies to where the batch leaves the scene; the error names the edit after
    // which it stayed over, to point the client at what to split or shrink.
    std::size_t over_from = over_budget(m_totals, m_budget) ? 0 : Error::NO_INDEX;
    for (std::size_t i = 0; i < batch.edits.size(); ++i) {
        Status s = std::visit([&](auto&& e) { return apply_edit(std::move(e), undo); },
                              std::move(batch.edits[i]));
        if (!s) {
            roll_back(undo);
            Error e = std::move(s).error();
            e.edit_index = i;
            return Unexpected(std::move(e));
        }
        if (!over_budget(m_totals, m_budget)) {
            over_from = Error::NO_INDEX;
        } else if (over_from == Error::NO_INDEX) {
            over_from = i;
        }
    }
    if (over_from != Error::NO_INDEX && m_totals.grew_from(undo.totals)) {
        Error e = make_error(ErrorCode::TooLarge, budget_message(m_totals, m_budget));
        e.edit_index = over_from;
        roll_back(undo);
        return Unexpected(std::move(e));
    }
    if (Status s = check_world_transforms(); !s) {
        roll_back(undo);
        return Unexpected(std::move(s).error());
    }
    if (before_done) {
        if (Status s = before_done(m_version + 1); !s) {
            roll_back(undo);
            return Unexpected(std::move(s).error());
        }
    }
    // The batch stands: bring the world transforms it dirtied up to date (cannot fail).
    flatten();
    if (inverse) *inverse = inverse_batch(std::move(undo), *this);
    return ++m_version;
}

Status Scene::load(Edit&& edit) {
    // The rules record what they overwrite; a load never rolls back, so the log is dropped at once
    // (its records of a fresh insert are a few bytes, and nothing is copied into it).
    UndoLog discarded;
    return std::visit([&](auto&& e) { return apply_edit(std::move(e), discarded); },
                      std::move(edit));
}

Status Scene::finish_load(uint64_t version) {
    if (Status s = check_world_transforms(); !s) return s;
    flatten();  // the world transforms of everything loaded
    if (over_budget(m_totals, m_budget))
        return failure(ErrorCode::TooLarge, budget_message(m_totals, m_budget));
    m_version = version;
    return {};
}

void Scene::reset() {
    const SceneBudget budget = m_budget;
    *this = Scene();
    m_budget = budget;
}

// Step: change tracking helpers ---------------------------------------------------------------

namespace {

/// Cleans the dirty state of every object of `handles` that still exists.
template <class Slots, class Handles>
void clean(Slots& slots, const Handles& handles) {
    for (const auto h : handles) {
        if (auto* r = slots.get(h)) r->dirty = {};
    }
}

}  // namespace

void Scene::mark(MeshHandle h, DirtyBits<MeshDirty> add) {
    m_changes.mark(h, m_meshes.at(h).dirty.bits, add);
}

void Scene::mark(InstanceHandle h, DirtyBits<InstanceDirty> add) {
    m_changes.mark(h, m_instances.at(h).dirty, add);
}

void Scene::mark(MaterialHandle h, DirtyBits<MaterialDirty> add) {
    m_changes.mark(h, m_materials.at(h).dirty, add);
    m_changes.mark(SceneDirty::Materials);
}

void Scene::mark(GroupHandle g, DirtyBits<GroupDirty> add) {
    // Groups are listed for the batch's flattening, which cleans them, not for the commit.
    GroupRecord& r = m_groups.at(g);
    if (r.dirty.none()) m_world_groups.push_back(g);
    r.dirty |= add;
    m_changes.mark(SceneDirty::Groups);
}

void Scene::save_mesh(MeshHandle h, UndoLog& undo) const {
    undo.records.emplace_back(undo::MeshDirty{h, m_meshes.at(h).dirty});
}

void Scene::save_instance(InstanceHandle h, UndoLog& undo) const {
    const InstanceRecord& r = m_instances.at(h);
    undo.records.emplace_back(
        undo::InstanceState{h, r.material, save_fields<InstanceFields>(r), r.dirty});
}

void Scene::clear_changes() {
    clean(m_meshes, m_changes.meshes());
    clean(m_instances, m_changes.instances());
    clean(m_materials, m_changes.materials());
    m_changes.clean();
}

// Step: queries --------------------------------------------------------------------------------

namespace {

/// Heap bytes of a string beyond its small-string buffer (rounded to the allocator's 16 bytes).
uint64_t heap_bytes(const std::string& s) {
    return s.capacity() > 15 ? (s.capacity() + 1 + 15) / 16 * 16 : 0;
}

}  // namespace

uint64_t Scene::instance_bytes() const {
    using Slots = SlotArray<InstanceRecord, InstanceTag>;
    const uint64_t slots = (uint64_t(m_instances.slot_count()) + Slots::CHUNK - 1) /
                           Slots::CHUNK * Slots::CHUNK;
    uint64_t bytes = slots * (sizeof(InstanceRecord) + sizeof(uint32_t) + sizeof(uint8_t));
    bytes += m_instance_ids.bytes();
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& r) {
        bytes += heap_bytes(r.id);
        if (r.rare) bytes += sizeof(InstanceRare) + heap_bytes(r.rare->name);
    });
    return bytes + m_instances.size() * 2 * sizeof(InstanceHandle);  // users and children
}

SceneCounts Scene::counts() const {
    SceneCounts c;
    c.meshes = m_meshes.size();
    c.instances = m_instances.size();
    c.materials = m_materials.size();
    c.groups = m_groups.size();
    c.lights = m_lights.size();
    c.textures = m_textures.size();
    m_meshes.for_each([&](MeshHandle, const MeshRecord& m) { c.triangles += m.triangles.size(); });
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        if (i.world_visible) c.instanced_triangles += m_meshes.at(i.mesh).triangles.size();
    });
    return c;
}

Bounds3 MeshRecord::bounds() const {
    Bounds3 b;
    if (radii.empty()) {
        for (const Vec3& p : positions) b.extend(p);
        for (const Vec3& p : motion_positions) b.extend(p);
        return b;
    }
    // Points and curves: each key's vertex grown by its radius (the same at every key).
    const std::size_t keys = motion_keys();
    for (std::size_t i = 0; i < positions.size(); ++i) {
        for (std::size_t k = 0; k < keys; ++k) {
            b.extend(key_position(k, i) - Vec3(radii[i]));
            b.extend(key_position(k, i) + Vec3(radii[i]));
        }
    }
    return b;
}

Bounds3 Scene::world_bounds() const {
    std::unordered_map<uint32_t, Bounds3> mesh_bounds;
    Bounds3 world;
    m_instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        if (!i.world_visible) return;
        auto [it, fresh] = mesh_bounds.try_emplace(i.mesh.index);
        if (fresh) it->second = m_meshes.at(i.mesh).bounds();
        world.extend(i.world.transform_bounds(it->second));
    });
    return world;
}

SceneImage Scene::image() const {
    return SceneImage{m_meshes,        m_instances, m_materials, m_groups,  m_lights, m_textures,
                      m_root.groups, m_camera,    m_lighting,  m_version, m_timeline};
}

EditBatch SceneImage::to_batch() const {
    EditBatch b;
    // Textures before the materials that name them.
    textures.for_each([&](TextureHandle, const TextureRecord& t) {
        AddTexture e{t.id, *t.encoded};
        copy_to_add<TextureFields>(e, t);
        b.edits.emplace_back(std::move(e));
    });
    materials.for_each([&](MaterialHandle, const MaterialRecord& m) {
        AddMaterial e{m.id, m.material};
        for (std::size_t s = 0; s < TEXTURE_SLOT_COUNT; ++s)
            if (const TextureRecord* t = textures.get(m.textures[s])) e.textures[s] = t->id;
        b.edits.emplace_back(std::move(e));
    });
    meshes.for_each([&](MeshHandle, const MeshRecord& m) {
        AddMesh e;
        e.id = m.id;
        e.positions = m.positions.get();
        e.triangles = m.triangles.get();
        e.strands = m.strands;
        for_each_vertex_attribute([&](auto a) { decltype(a)::of(e) = decltype(a)::of(m); });
        e.build = m.build;
        if (const MaterialRecord* mat = materials.get(m.material)) e.material = mat->id;
        copy_to_add<MeshFields>(e, m);
        b.edits.emplace_back(std::move(e));
    });
    // Groups parents first (depth-first from the root), so each names a group already added.
    std::vector<GroupHandle> stack(root_groups.rbegin(), root_groups.rend());
    while (!stack.empty()) {
        const GroupRecord& g = groups.at(stack.back());
        stack.pop_back();
        AddGroup e;
        e.id = g.id;
        if (!g.parent.is_null()) e.parent = groups.at(g.parent).id;
        copy_to_add<GroupFields>(e, g);
        b.edits.emplace_back(std::move(e));
        stack.insert(stack.end(), g.children.groups.rbegin(), g.children.groups.rend());
    }
    // Instances in slot order, runs of them packed into bulk adds (numbered ids as a range), so a
    // snapshot of a million instances holds a few big edits.
    const std::size_t first_instance = b.edits.size();
    instances.for_each([&](InstanceHandle, const InstanceRecord& i) {
        AddInstance e;
        e.id = i.id;
        e.mesh = meshes.at(i.mesh).id;
        if (const MaterialRecord* mat = materials.get(i.material)) e.material = mat->id;
        copy_to_add<InstanceFields>(e, i);
        if (!i.parent.is_null()) e.parent = groups.at(i.parent).id;
        append_add_instance(b, std::move(e));
    });
    for (std::size_t k = first_instance; k < b.edits.size(); ++k)
        compact_ids(b.edits[k], IdOrder::Kept);
    lights.for_each(
        [&](LightHandle, const LightRecord& l) { b.edits.emplace_back(AddLight{l.id, l.light}); });
    b.edits.emplace_back(update_to<CameraFields>(camera));
    b.edits.emplace_back(update_to<LightingFields>(lighting));
    // Older files have no clock; a scene at the default one writes none either.
    if (!(timeline == Timeline{})) b.edits.emplace_back(update_to<TimelineFields>(timeline));
    return b;
}

}  // namespace strata
