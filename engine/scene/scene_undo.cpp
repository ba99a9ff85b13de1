// Undoing a refused batch: the undo log (undo_log.h) played backwards. Each step reverses one
// change of scene_rules.cpp exactly, in reverse order, so slot arrays hand back the same slots
// and generations and every record, id, dirty bit and change list is as before the batch.

#include <type_traits>
#include <vector>

#include "engine/scene/child_list.h"
#include "engine/scene/scene.h"
#include "engine/scene/undo_log.h"

namespace strata {

namespace {

/// The list of `c` that holds children of handle type H (instances or groups).
template <class H>
std::vector<H>& child_list(Children& c) {
    if constexpr (std::is_same_v<H, InstanceHandle>) return c.instances;
    else return c.groups;
}

/// Reverses one undo record on the scene's storage. A friend-free helper: Scene passes in the
/// pieces it owns.
struct Reverser {
    SlotArray<MeshRecord, MeshTag>& meshes;
    SlotArray<InstanceRecord, InstanceTag>& instances;
    SlotArray<MaterialRecord, MaterialTag>& materials;
    IdIndex<MeshHandle>& mesh_ids;
    IdIndex<InstanceHandle>& instance_ids;
    IdIndex<MaterialHandle>& material_ids;
    SlotArray<GroupRecord, GroupTag>& groups;
    IdIndex<GroupHandle>& group_ids;
    SlotArray<LightRecord, LightTag>& lights;
    IdIndex<LightHandle>& light_ids;
    Children& root;
    SlotArray<TextureRecord, TextureTag>& textures;
    IdIndex<TextureHandle>& texture_ids;

    Children& children_of(GroupHandle parent) {
        return parent.is_null() ? root : groups.at(parent).children;
    }

    void operator()(undo::Inserted<MeshHandle>& r) {
        mesh_ids.erase(meshes.at(r.handle).id, r.handle);
        meshes.undo_insert(r.handle, r.reused_slot);
    }

    void operator()(undo::Inserted<InstanceHandle>& r) {
        const InstanceRecord& inst = instances.at(r.handle);
        MeshRecord& mesh = meshes.at(inst.mesh);
        STRATA_CHECK(!mesh.users.empty() && mesh.users.back() == r.handle);
        mesh.users.mut().pop_back();
        std::vector<InstanceHandle>& siblings = children_of(inst.parent).instances;
        STRATA_CHECK(!siblings.empty() && siblings.back() == r.handle);
        siblings.pop_back();
        instance_ids.erase(inst.id, r.handle);
        instances.undo_insert(r.handle, r.reused_slot);
    }

    void operator()(undo::Inserted<MaterialHandle>& r) {
        material_ids.erase(materials.at(r.handle).id, r.handle);
        materials.undo_insert(r.handle, r.reused_slot);
    }

    void operator()(undo::Removed<MeshHandle, MeshRecord>& r) {
        mesh_ids.insert(r.record.id, r.handle);
        meshes.undo_erase(r.handle, std::move(r.record));
    }

    void operator()(undo::Removed<InstanceHandle, InstanceRecord>& r) {
        // Reverse the swap-remove from the mesh's user list.
        MeshRecord& mesh = meshes.at(r.record.mesh);
        const uint32_t slot = r.record.user_slot;
        std::vector<InstanceHandle>& users = mesh.users.mut();
        if (slot == users.size()) {
            users.push_back(r.handle);
        } else {
            const InstanceHandle moved = users[slot];
            instances.at(moved).user_slot = static_cast<uint32_t>(users.size());
            users.push_back(moved);
            users[slot] = r.handle;
        }
        undo_detach_child(children_of(r.record.parent).instances, instances, r.handle,
                          r.record.child_slot);
        instance_ids.insert(r.record.id, r.handle);
        instances.undo_erase(r.handle, std::move(r.record));
    }

    void operator()(undo::Inserted<GroupHandle>& r) {
        const GroupRecord& g = groups.at(r.handle);
        std::vector<GroupHandle>& siblings = children_of(g.parent).groups;
        STRATA_CHECK(!siblings.empty() && siblings.back() == r.handle);
        siblings.pop_back();
        group_ids.erase(g.id, r.handle);
        groups.undo_insert(r.handle, r.reused_slot);
    }

    void operator()(undo::Removed<GroupHandle, GroupRecord>& r) {
        undo_detach_child(children_of(r.record.parent).groups, groups, r.handle,
                          r.record.child_slot);
        group_ids.insert(r.record.id, r.handle);
        groups.undo_erase(r.handle, std::move(r.record));
    }

    void operator()(undo::GroupState& r) {
        GroupRecord& g = groups.at(r.handle);
        restore_fields<GroupFields>(g, std::move(r.fields));
        g.dirty = r.dirty;
    }

    void operator()(undo::MeshDirty& r) { meshes.at(r.handle).dirty = r.dirty; }

    template <class H>
    void operator()(undo::Reparented<H>& r) {
        auto& records = [&]() -> auto& {
            if constexpr (std::is_same_v<H, InstanceHandle>) return instances;
            else return groups;
        }();
        auto& rec = records.at(r.handle);
        std::vector<H>& now = child_list<H>(children_of(rec.parent));
        STRATA_CHECK(!now.empty() && now.back() == r.handle);
        now.pop_back();
        std::vector<H>& old = child_list<H>(children_of(r.old_parent));
        undo_detach_child(old, records, r.handle, r.old_slot);
        rec.parent = r.old_parent;
        rec.child_slot = r.old_slot;
    }

    void operator()(undo::Removed<MaterialHandle, MaterialRecord>& r) {
        material_ids.insert(r.record.id, r.handle);
        materials.undo_erase(r.handle, std::move(r.record));
    }

    void operator()(undo::Inserted<TextureHandle>& r) {
        texture_ids.erase(textures.at(r.handle).id, r.handle);
        textures.undo_insert(r.handle, r.reused_slot);
    }

    void operator()(undo::Removed<TextureHandle, TextureRecord>& r) {
        texture_ids.insert(r.record.id, r.handle);
        textures.undo_erase(r.handle, std::move(r.record));
    }

    void operator()(undo::MeshPositions& r) {
        MeshRecord& mesh = meshes.at(r.handle);
        std::copy(r.positions.begin(), r.positions.end(), mesh.positions.mut().begin() + r.offset);
    }

    void operator()(undo::MeshVertexPositions& r) {
        std::vector<Vec3>& positions = meshes.at(r.handle).positions.mut();
        for (std::size_t i = r.vertices.size(); i-- > 0;) positions[r.vertices[i]] = r.positions[i];
    }

    void operator()(undo::MeshPositionsReplaced& r) {
        meshes.at(r.handle).positions = std::move(r.positions);
    }

    void operator()(undo::MeshTopology& r) {
        MeshRecord& mesh = meshes.at(r.handle);
        if (r.positions) mesh.positions = std::move(*r.positions);
        mesh.triangles = std::move(r.triangles);
        if (r.strands) mesh.strands = std::move(*r.strands);
    }

    void operator()(undo::MeshTriangles& r) {
        std::vector<Triangle>& tris = meshes.at(r.handle).triangles.mut();
        const auto at = tris.begin() + std::ptrdiff_t(r.first);
        if (r.inserted == r.triangles.size()) {
            std::copy(r.triangles.begin(), r.triangles.end(), at);
            return;
        }
        tris.erase(at, at + std::ptrdiff_t(r.inserted));
        tris.insert(tris.begin() + std::ptrdiff_t(r.first), r.triangles.begin(),
                    r.triangles.end());
    }

    void operator()(undo::MeshAttributes& r) {
        MeshRecord& mesh = meshes.at(r.handle);
        for_each_vertex_attribute([&](auto a) {
            if (auto& saved = decltype(a)::of(r)) decltype(a)::of(mesh) = std::move(*saved);
        });
    }

    void operator()(undo::InstanceTransform& r) {
        InstanceRecord& inst = instances.at(r.handle);
        inst.transform = r.transform;
        inst.dirty = r.dirty;
    }

    void operator()(undo::InstanceState& r) {
        InstanceRecord& inst = instances.at(r.handle);
        inst.material = r.material;
        restore_fields<InstanceFields>(inst, std::move(r.fields));
        inst.dirty = r.dirty;
    }

    void operator()(undo::Inserted<LightHandle>& r) {
        light_ids.erase(lights.at(r.handle).id, r.handle);
        lights.undo_insert(r.handle, r.reused_slot);
    }

    void operator()(undo::Removed<LightHandle, LightRecord>& r) {
        light_ids.insert(r.record.id, r.handle);
        lights.undo_erase(r.handle, std::move(r.record));
    }

    void operator()(undo::LightState& r) { lights.at(r.handle).light = r.light; }

    void operator()(undo::MaterialState& r) {
        MaterialRecord& m = materials.at(r.handle);
        m.material = r.material;
        m.dirty = r.dirty;
        m.textures = r.textures;
    }
};

}  // namespace

void Scene::roll_back(UndoLog& undo) {
    Reverser reverse{m_meshes,       m_instances, m_materials, m_mesh_ids, m_instance_ids,
                     m_material_ids, m_groups,    m_group_ids, m_lights,   m_light_ids,
                     m_root,         m_textures,  m_texture_ids};
    for (auto it = undo.records.rbegin(); it != undo.records.rend(); ++it) std::visit(reverse, *it);
    m_camera = undo.camera;
    m_lighting = undo.lighting;
    m_timeline = undo.timeline;
    m_totals = undo.totals;
    m_changes.rewind(undo.changes);
    m_world_instances.resize(undo.world_instances);
    m_world_groups.resize(undo.world_groups);
}

}  // namespace strata
