// The rules of the group ops (add_group, update_group, remove_group), in the manner of
// scene_rules.cpp: check against the scene as the batch left it, then change it, recording what
// the change overwrote. World transforms are not touched here: flatten() does that once the
// whole batch passed (scene_graph.cpp).

#include "engine/scene/animation.h"
#include "engine/scene/child_list.h"
#include "engine/scene/object_fields.h"
#include "engine/scene/scene.h"
#include "engine/scene/undo_log.h"

namespace strata {

Status Scene::apply_edit(AddGroup&& e, UndoLog& undo) {
    if (Status s = check_new_id(e.id, !find_group(e.id).is_null(), "group"); !s) return s;
    auto parent = find_parent(e.parent, "parent");
    if (!parent) return Unexpected(parent.error());
    if (Status s = check_group_move(GroupHandle{}, parent.value()); !s) return s;
    if (Status s = check_fields<GroupFields>(e); !s) return s;
    if (Status s = check_lod_range(e.lod_near, e.lod_far); !s) return s;
    if (Status s = check_keys(e.motion, e.animation); !s) return s;

    GroupRecord r;
    r.id = e.id;
    r.parent = parent.value();
    copy_added<GroupFields>(r, e);
    std::vector<GroupHandle>& siblings = children_of(r.parent).groups;
    r.child_slot = static_cast<uint32_t>(siblings.size());
    bool reused = false;
    const bool animated = !r.animation.empty();
    const GroupHandle h = m_groups.insert(std::move(r), &reused);
    undo.records.emplace_back(undo::Inserted<GroupHandle>{h, reused});
    if (animated) m_animated_groups.push_back(h);
    ++m_totals.groups;
    children_of(parent.value()).groups.push_back(h);
    m_group_ids.insert(e.id, h);
    mark(h, GroupDirty::Added);
    return {};
}

Status Scene::apply_edit(UpdateGroup&& e, UndoLog& undo) {
    const GroupHandle h = find_group(e.group);
    if (h.is_null())
        return failure(ErrorCode::UnknownId, "unknown group '" + e.group + "'", "group");
    GroupHandle parent;
    if (e.parent) {
        auto found = find_parent(*e.parent, "parent");
        if (!found) return Unexpected(found.error());
        parent = found.value();
        if (parent == h)
            return failure(ErrorCode::Cycle,
                           "group '" + e.group + "' cannot be its own parent (the cycle '" +
                               e.group + "' > '" + e.group + "')",
                           "parent");
        if (Status s = check_group_move(h, parent); !s) return s;
    }
    if (Status s = check_update<GroupFields>(e); !s) return s;
    const GroupRecord& current = m_groups.at(h);
    if (Status s = check_lod_range(e.lod_near.value_or(current.lod_near),
                                   e.lod_far.value_or(current.lod_far));
        !s)
        return s;
    if (Status s = check_keys(e.motion ? *e.motion : current.motion,
                              e.animation ? *e.animation : current.animation);
        !s)
        return s;

    save_group(h, undo);
    DirtyBits<GroupDirty> bits;
    if (e.parent && !(parent == m_groups.at(h).parent)) {
        reparent_group(h, parent, undo);
        bits |= GroupDirty::Parent;
    }
    bits |= apply_update<GroupFields>(m_groups.at(h), e);
    if (bits.any()) mark(h, bits);
    if (e.animation && !e.animation->empty()) m_animated_groups.push_back(h);
    return {};
}

Status Scene::apply_edit(RemoveGroup&& e, UndoLog& undo) {
    const GroupHandle h = find_group(e.group);
    if (h.is_null())
        return failure(ErrorCode::UnknownId, "unknown group '" + e.group + "'", "group");
    const Children& c = m_groups.at(h).children;
    if (!c.empty() && !e.recursive)
        return failure(ErrorCode::InUse,
                       "group '" + e.group + "' still has " + std::to_string(c.groups.size()) +
                           " group(s) and " + std::to_string(c.instances.size()) +
                           " instance(s); remove them first or pass \"recursive\": true",
                       "group");
    remove_subtree(h, undo);
    return {};
}

}  // namespace strata
