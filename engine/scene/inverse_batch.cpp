// The inverse of an applied batch (inverse_batch.h): its undo log played backwards as edits.

#include "engine/scene/inverse_batch.h"

#include <algorithm>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

#include "engine/scene/bulk_packing.h"
#include "engine/scene/scene.h"
#include "engine/scene/undo_log.h"

namespace strata {

namespace {

template <class H>
uint64_t key(H h) {
    return uint64_t(h.index) << 32 | h.generation;
}

/// A copy-on-write array's values, moved out when nothing else shares them.
template <class T>
std::vector<T> take(CowVector<T>& v) {
    if (v.empty()) return {};
    return std::move(v.mut());
}

/// Turns undo records into edits. Handles become ids: a live object's from the scene, one the
/// batch removed from its record in the log (an object the batch added and removed again is in
/// both, and only the log still knows its id).
class Inverter {
public:
    explicit Inverter(const Scene& scene) : m_scene(scene) {}

    /// Learns the ids of the objects `log` removed.
    void note_removed(const std::vector<UndoRecord>& records) {
        for (const UndoRecord& r : records) {
            std::visit(
                [&](const auto& x) {
                    if constexpr (requires { x.record.id; })
                        removed<decltype(x.handle)>().emplace(key(x.handle), x.record.id);
                },
                r);
        }
    }

    /// The inverse of `records` (in reverse order), appended to `out`.
    void invert(std::vector<UndoRecord>& records, EditBatch& out) {
        m_out = &out;
        for (std::size_t i = records.size(); i-- > 0;) {
            // A topology change saved its other attributes in the record just before it: they go
            // back with the topology (a vertex count change needs them in the same edit).
            auto* topology = std::get_if<undo::MeshTopology>(&records[i]);
            auto* attributes = i > 0 ? std::get_if<undo::MeshAttributes>(&records[i - 1]) : nullptr;
            if (topology && attributes && attributes->handle == topology->handle) {
                invert_topology(*topology, attributes);
                --i;
                continue;
            }
            std::visit([&](auto& x) { (*this)(x); }, records[i]);
        }
    }

    template <class H>
    void operator()(undo::Inserted<H>& r) {
        std::string id = id_of(r.handle);
        if constexpr (std::is_same_v<H, MeshHandle>)
            emit(RemoveMesh{std::move(id)});
        else if constexpr (std::is_same_v<H, InstanceHandle>)
            emit_remove_instance(std::move(id));
        else if constexpr (std::is_same_v<H, MaterialHandle>)
            emit(RemoveMaterial{std::move(id)});
        else if constexpr (std::is_same_v<H, GroupHandle>)
            emit(RemoveGroup{std::move(id), false});
        else if constexpr (std::is_same_v<H, TextureHandle>)
            emit(RemoveTexture{std::move(id)});
        else
            emit(RemoveLight{std::move(id)});
    }

    void operator()(undo::Removed<MeshHandle, MeshRecord>& r) {
        MeshRecord& m = r.record;
        AddMesh e;
        e.id = m.id;
        e.positions = take(m.positions);
        e.triangles = take(m.triangles);
        e.strands = std::move(m.strands);
        e.build = m.build;
        e.material = id_or_none(m.material);
        for_each_vertex_attribute(
            [&](auto a) { decltype(a)::of(e) = std::move(decltype(a)::of(m)); });
        copy_to_add<MeshFields>(e, m);
        emit(std::move(e));
    }

    void operator()(undo::Removed<InstanceHandle, InstanceRecord>& r) {
        const InstanceRecord& i = r.record;
        AddInstance e;
        e.id = i.id;
        e.mesh = id_of(i.mesh);
        e.material = id_or_none(i.material);
        e.parent = id_or_none(i.parent);
        copy_to_add<InstanceFields>(e, i);
        append_add_instance(*m_out, std::move(e));
    }

    void operator()(undo::Removed<MaterialHandle, MaterialRecord>& r) {
        AddMaterial e{r.record.id, std::move(r.record.material)};
        for (std::size_t s = 0; s < TEXTURE_SLOT_COUNT; ++s)
            e.textures[s] = id_or_none(r.record.textures[s]);
        emit(std::move(e));
    }

    void operator()(undo::Removed<GroupHandle, GroupRecord>& r) {
        AddGroup e;
        e.id = r.record.id;
        e.parent = id_or_none(r.record.parent);
        copy_to_add<GroupFields>(e, r.record);
        emit(std::move(e));
    }

    void operator()(undo::Removed<TextureHandle, TextureRecord>& r) {
        AddTexture e{r.record.id, *r.record.encoded};
        copy_to_add<TextureFields>(e, r.record);
        emit(std::move(e));
    }

    void operator()(undo::Removed<LightHandle, LightRecord>& r) {
        emit(AddLight{r.record.id, std::move(r.record.light)});
    }

    void operator()(undo::MeshDirty&) {}  // dirty bits are not scene state

    void operator()(undo::MeshPositions& r) {
        emit(UpdateMeshPositions{id_of(r.handle), r.offset, std::move(r.positions)});
    }

    void operator()(undo::MeshVertexPositions& r) {
        // The forward edit wrote in list order, so a vertex listed twice holds its first old
        // value in the earlier entry; reversed, that entry comes last and wins.
        std::reverse(r.vertices.begin(), r.vertices.end());
        std::reverse(r.positions.begin(), r.positions.end());
        emit(UpdateMeshVertices{id_of(r.handle), std::move(r.vertices), std::move(r.positions)});
    }

    void operator()(undo::MeshPositionsReplaced& r) {
        emit(UpdateMeshPositions{id_of(r.handle), 0, take(r.positions)});
    }

    void operator()(undo::MeshTopology& r) { invert_topology(r, nullptr); }

    void operator()(undo::MeshTriangles& r) {
        emit(ReplaceMeshTriangles{id_of(r.handle), r.first, r.inserted, std::move(r.triangles)});
    }

    void operator()(undo::MeshAttributes& r) {
        // The saved arrays are whole, so they go back whole (offset 0; [] removes them again).
        UpdateMeshPositions e{id_of(r.handle), 0, {}};
        for_each_vertex_attribute(
            [&](auto a) { decltype(a)::of(e) = std::move(decltype(a)::of(r)); });
        emit(std::move(e));
    }

    void operator()(undo::InstanceState& r) {
        UpdateInstance e = update_from<InstanceFields>(std::move(r.fields));
        e.instance = id_of(r.handle);
        e.material.emplace(id_or_none(r.material));
        emit(std::move(e));
    }

    void operator()(undo::InstanceTransform& r) {
        emit_transform(id_of(r.handle), r.transform);
    }

    void operator()(undo::GroupState& r) {
        UpdateGroup e = update_from<GroupFields>(std::move(r.fields));
        e.group = id_of(r.handle);
        emit(std::move(e));
    }

    void operator()(undo::Reparented<InstanceHandle>& r) {
        UpdateInstance e;
        e.instance = id_of(r.handle);
        e.parent.emplace(id_or_none(r.old_parent));
        emit(std::move(e));
    }

    void operator()(undo::Reparented<GroupHandle>& r) {
        UpdateGroup e;
        e.group = id_of(r.handle);
        e.parent.emplace(id_or_none(r.old_parent));
        emit(std::move(e));
    }

    void operator()(undo::MaterialState& r) {
        UpdateMaterial e = update_to<MaterialFields>(r.material);
        e.material = id_of(r.handle);
        for (std::size_t s = 0; s < TEXTURE_SLOT_COUNT; ++s)
            e.textures[s].emplace(id_or_none(r.textures[s]));
        e.wrap = r.material.base_color_sampler.wrap;
        e.filter = r.material.base_color_sampler.filter;
        emit(std::move(e));
    }

    void operator()(undo::LightState& r) {
        UpdateLight e = update_to<LightFields>(r.light);
        e.light = id_of(r.handle);
        emit(std::move(e));
    }

private:
    void emit(Edit&& e) { m_out->edits.push_back(std::move(e)); }

    // Runs of instance removals and of moves become one bulk edit each, with the same effect (a
    // bulk edit applies its items in order): a million-instance add is taken back by one
    // remove_instances, not by a million remove_instance edits.
    void emit_remove_instance(std::string&& id) {
        Edit* last = m_out->edits.empty() ? nullptr : &m_out->edits.back();
        if (auto* bulk = last ? std::get_if<RemoveInstances>(last) : nullptr;
            bulk && bulk->ids.list.size() < MAX_BULK_ITEMS) {
            bulk->ids.list.push_back(std::move(id));
        } else if (auto* one = last ? std::get_if<RemoveInstance>(last) : nullptr) {
            RemoveInstances e;
            e.ids.list = {std::move(one->instance), std::move(id)};
            *last = std::move(e);
        } else {
            emit(RemoveInstance{std::move(id)});
        }
    }
    void emit_transform(std::string&& id, const Affine& t) {
        Edit* last = m_out->edits.empty() ? nullptr : &m_out->edits.back();
        if (auto* bulk = last ? std::get_if<UpdateInstances>(last) : nullptr;
            bulk && bulk->ids.list.size() < MAX_BULK_ITEMS) {
            bulk->ids.list.push_back(std::move(id));
            bulk->transforms.push_back(t);
        } else if (auto* one = last ? std::get_if<SetTransform>(last) : nullptr) {
            UpdateInstances e;
            e.ids.list = {std::move(one->instance), std::move(id)};
            e.transforms = {one->transform, t};
            *last = std::move(e);
        } else {
            emit(SetTransform{std::move(id), t});
        }
    }

    void invert_topology(undo::MeshTopology& r, undo::MeshAttributes* attributes) {
        ReplaceMeshTopology e;
        e.mesh = id_of(r.handle);
        if (r.positions) e.positions = take(*r.positions);
        e.triangles = take(r.triangles);
        e.strands = std::move(r.strands);
        if (attributes) {
            for_each_vertex_attribute(
                [&](auto a) { decltype(a)::of(e) = std::move(decltype(a)::of(*attributes)); });
        }
        emit(std::move(e));
    }

    template <class H>
    std::unordered_map<uint64_t, std::string>& removed() {
        if constexpr (std::is_same_v<H, MeshHandle>)
            return m_meshes;
        else if constexpr (std::is_same_v<H, InstanceHandle>)
            return m_instances;
        else if constexpr (std::is_same_v<H, MaterialHandle>)
            return m_materials;
        else if constexpr (std::is_same_v<H, GroupHandle>)
            return m_groups;
        else if constexpr (std::is_same_v<H, TextureHandle>)
            return m_textures;
        else
            return m_lights;
    }

    template <class H>
    const std::string* live_id(H h) const {
        const auto id = [](const auto* record) { return record ? &record->id : nullptr; };
        if constexpr (std::is_same_v<H, MeshHandle>)
            return id(m_scene.meshes().get(h));
        else if constexpr (std::is_same_v<H, InstanceHandle>)
            return id(m_scene.instances().get(h));
        else if constexpr (std::is_same_v<H, MaterialHandle>)
            return id(m_scene.materials().get(h));
        else if constexpr (std::is_same_v<H, GroupHandle>)
            return id(m_scene.groups().get(h));
        else if constexpr (std::is_same_v<H, TextureHandle>)
            return id(m_scene.textures().get(h));
        else
            return id(m_scene.lights().get(h));
    }

    template <class H>
    std::string id_of(H h) {
        if (const std::string* live = live_id(h)) return *live;
        const auto& ids = removed<H>();
        const auto it = ids.find(key(h));
        STRATA_CHECK(it != ids.end());
        return it->second;
    }

    /// Null handles (the root, "the mesh's default material", "no texture") become nullopt.
    template <class H>
    std::optional<std::string> id_or_none(H h) {
        if (h.is_null()) return std::nullopt;
        return id_of(h);
    }

    const Scene& m_scene;
    EditBatch* m_out = nullptr;
    std::unordered_map<uint64_t, std::string> m_meshes, m_instances, m_materials, m_groups,
        m_textures, m_lights;
};

}  // namespace

EditBatch inverse_batch(UndoLog&& log, const Scene& scene) {
    EditBatch out;
    Inverter inverter(scene);
    inverter.note_removed(log.records);
    inverter.invert(log.records, out);
    // The order of a bulk edit's items only decides slots and child order, which an inverse does
    // not promise: ids that are a numbered range in any order become that range.
    for (Edit& e : out.edits) compact_ids(e, IdOrder::Free);
    // Camera, lighting and timeline were saved whole at the start of the batch.
    if (!(scene.camera() == log.camera))
        out.edits.emplace_back(update_to<CameraFields>(log.camera));
    if (!(scene.lighting() == log.lighting))
        out.edits.emplace_back(update_to<LightingFields>(log.lighting));
    if (!(scene.timeline() == log.timeline))
        out.edits.emplace_back(update_to<TimelineFields>(log.timeline));
    return out;
}

}  // namespace strata
