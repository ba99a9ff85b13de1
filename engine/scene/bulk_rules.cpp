// The rules of the bulk instance ops (edits.h: AddInstances, UpdateInstances, RemoveInstances).
// Each item is checked and applied as its single edit would be (scene_rules.cpp), with what the
// items share (mesh, material, parent) looked up once; the first refused item refuses the edit,
// and Scene::apply undoes the batch. Errors name the item: "item 17 ('tree-17'): ..." at field
// "ids/17" (or the per-item array the problem is in).

#include <limits>
#include <string>

#include "engine/scene/budget.h"
#include "engine/scene/object_fields.h"
#include "engine/scene/scene.h"
#include "engine/scene/undo_log.h"

namespace strata {

namespace {

/// "field/i": item i of a per-item array.
std::string item_field(const char* field, std::size_t i) {
    return std::string(field) + "/" + std::to_string(i);
}

/// Prefixes an item's error with the item, and points it at `field`.
Status for_item(Status s, std::size_t i, const std::string& id, std::string field) {
    if (s) return s;
    Error e = std::move(s).error();
    e.message = "item " + std::to_string(i) + " ('" + id + "'): " + e.message;
    e.field = std::move(field);
    return Unexpected(std::move(e));
}

/// Item i names no instance.
Status unknown_item(std::size_t i, const std::string& id) {
    return for_item(failure(ErrorCode::UnknownId, "unknown instance '" + id + "'"), i, id,
                    item_field("ids", i));
}

Status check_ids(const BulkIds& ids) {
    if (!ids.list.empty() && ids.count != 0)
        return failure(ErrorCode::InvalidArgument, "give a list of ids or a range, not both",
                       "ids");
    const uint64_t n = ids.list.empty() ? ids.count : ids.list.size();
    if (n > MAX_BULK_ITEMS)
        return failure(ErrorCode::TooLarge,
                       std::to_string(n) + " items, over the limit of " +
                           std::to_string(MAX_BULK_ITEMS) + " per bulk edit",
                       "ids");
    if (ids.list.empty() && ids.first > std::numeric_limits<uint64_t>::max() - ids.count)
        return failure(ErrorCode::OutOfRange, "the id range runs past 2^64 - 1", "ids");
    return {};
}

/// An array of one value per item, or (when `one_allowed`) one value for all, or (when
/// `none_allowed`) none.
template <class T>
Status check_per_item(const std::vector<T>& v, std::size_t n, const char* field, bool one_allowed,
                      bool none_allowed) {
    if (v.size() == n || (one_allowed && v.size() == 1) || (none_allowed && v.empty())) return {};
    return failure(ErrorCode::InvalidArgument,
                   std::string(field) + " has " + std::to_string(v.size()) + " values for " +
                       std::to_string(n) + " ids",
                   field);
}

}  // namespace

Status Scene::apply_edit(AddInstances&& e, UndoLog& undo) {
    if (Status s = check_ids(e.ids); !s) return s;
    const std::size_t n = e.ids.size();
    if (Status s = check_per_item(e.meshes, n, "mesh", true, false); !s) return s;
    if (Status s = check_per_item(e.materials, n, "material", true, true); !s) return s;
    if (Status s = check_per_item(e.transforms, n, "transforms", false, true); !s) return s;
    auto parent = find_parent(e.parent, "parent");
    if (!parent) return Unexpected(parent.error());
    static const FieldInfo& TRANSFORM = field_info<InstanceFields>("transform");
    // Refused before anything is built when this edit alone takes the scene past its budget (a
    // range of ids is a few bytes that can ask for 2^24 instances).
    if (m_totals.instances + n > m_budget.max_instances) {
        MeshTotals after = m_totals;
        after.instances += n;
        return failure(ErrorCode::TooLarge, budget_message(after, m_budget), "ids");
    }

    const bool mesh_each = e.meshes.size() > 1;
    const bool material_each = e.materials.size() > 1;
    MeshHandle shared_mesh;
    if (!mesh_each && !e.meshes.empty()) {
        shared_mesh = find_mesh(e.meshes[0]);
        if (shared_mesh.is_null())
            return failure(ErrorCode::UnknownId, "unknown mesh '" + e.meshes[0] + "'", "mesh");
    }
    MaterialHandle shared_material;
    if (!material_each && !e.materials.empty()) {
        shared_material = find_material(e.materials[0]);
        if (shared_material.is_null())
            return failure(ErrorCode::UnknownId, "unknown material '" + e.materials[0] + "'",
                           "material");
    }
    m_instance_ids.reserve(m_instance_ids.size() + n);
    undo.records.reserve(undo.records.size() + n);
    m_world_instances.reserve(m_world_instances.size() + n);
    for (std::size_t i = 0; i < n; ++i) {
        std::string id = e.ids.at(i);
        if (Status s = check_new_id(id, !find_instance(id).is_null(), "instance"); !s)
            return for_item(std::move(s), i, id, item_field("ids", i));
        InstanceRecord r;
        r.mesh = mesh_each ? find_mesh(e.meshes[i]) : shared_mesh;
        if (r.mesh.is_null())
            return for_item(failure(ErrorCode::UnknownId, "unknown mesh '" + e.meshes[i] + "'"), i,
                            id, item_field("mesh", i));
        r.material = material_each ? find_material(e.materials[i]) : shared_material;
        if (material_each && r.material.is_null())
            return for_item(
                failure(ErrorCode::UnknownId, "unknown material '" + e.materials[i] + "'"), i, id,
                item_field("material", i));
        if (!e.transforms.empty()) {
            if (Status s = check_value(TRANSFORM, e.transforms[i]); !s)
                return for_item(std::move(s), i, id, item_field("transforms", i));
            r.transform = e.transforms[i];
        }
        r.visible = e.visible;
        r.parent = parent.value();
        insert_instance(std::move(r), std::move(id), undo);
    }
    return {};
}

Status Scene::apply_edit(UpdateInstances&& e, UndoLog& undo) {
    if (Status s = check_ids(e.ids); !s) return s;
    const std::size_t n = e.ids.size();
    if (Status s = check_per_item(e.transforms, n, "transforms", false, true); !s) return s;
    if (e.transforms.empty() && !e.visible)
        return failure(ErrorCode::InvalidArgument, "nothing to change: give transforms or visible");
    static const FieldInfo& TRANSFORM = field_info<InstanceFields>("transform");
    undo.records.reserve(undo.records.size() + n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::string id = e.ids.at(i);
        const InstanceHandle h = find_instance(id);
        if (h.is_null()) return unknown_item(i, id);
        if (!e.transforms.empty()) {
            if (Status s = check_value(TRANSFORM, e.transforms[i]); !s)
                return for_item(std::move(s), i, id, item_field("transforms", i));
        }
        InstanceRecord& r = m_instances.at(h);
        DirtyBits<InstanceDirty> bits;
        if (e.visible && *e.visible != r.visible) {
            save_instance(h, undo);
            r.visible = *e.visible;
            bits |= InstanceDirty::Visibility;
        } else if (!e.transforms.empty()) {
            undo.records.emplace_back(undo::InstanceTransform{h, r.transform, r.dirty});
        }
        if (!e.transforms.empty()) {
            r.transform = e.transforms[i];
            bits |= InstanceDirty::Transform;
        }
        if (bits.any()) {
            mark(h, bits);
            mark_instance_world(h);
        }
    }
    return {};
}

Status Scene::apply_edit(RemoveInstances&& e, UndoLog& undo) {
    if (Status s = check_ids(e.ids); !s) return s;
    const std::size_t n = e.ids.size();
    for (std::size_t i = 0; i < n; ++i) {
        const std::string id = e.ids.at(i);
        const InstanceHandle h = find_instance(id);
        if (h.is_null()) return unknown_item(i, id);
        remove_instance(h, undo);
    }
    return {};
}

}  // namespace strata
