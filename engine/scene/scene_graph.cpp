// The scene graph: parents, child lists and the flattening of transforms. Groups form a forest
// under an implicit root; instances hang from groups or from the root. An edit that changes a
// group's transform, visibility or parent only marks the group; flatten() then recomputes the
// world transforms below each dirty group once per batch (Hydra's DirtyTransform flattening, done
// incrementally: the cost follows the dirtied subtrees, never the scene), and hands the instances
// whose world changed to the TLAS as ordinary transform/visibility changes.

#include <algorithm>

#include "engine/scene/animation.h"
#include "engine/scene/child_list.h"
#include "engine/scene/scene.h"
#include "engine/scene/undo_log.h"

namespace strata {

const Children& Scene::children(GroupHandle parent) const {
    return parent.is_null() ? m_root : m_groups.at(parent).children;
}

Children& Scene::children_of(GroupHandle parent) {
    return parent.is_null() ? m_root : m_groups.at(parent).children;
}

std::vector<std::string> Scene::group_path(GroupHandle parent) const {
    std::vector<std::string> path;
    for (GroupHandle g = parent; !g.is_null(); g = m_groups.at(g).parent)
        path.push_back(m_groups.at(g).id);
    std::reverse(path.begin(), path.end());
    return path;
}

Result<GroupHandle> Scene::find_parent(const std::optional<std::string>& id,
                                       const char* field) const {
    if (!id) return GroupHandle{};
    const GroupHandle g = find_group(*id);
    if (g.is_null())
        return failure(ErrorCode::UnknownId, "unknown group '" + *id + "'", field);
    return g;
}

Status Scene::check_group_move(GroupHandle g, GroupHandle parent) const {
    if (parent.is_null()) return {};
    // Step: cycle. Walking up from the new parent must not meet the group itself.
    std::vector<GroupHandle> up;
    uint32_t parent_depth = 0;
    for (GroupHandle p = parent; !p.is_null(); p = m_groups.at(p).parent) {
        up.push_back(p);
        ++parent_depth;
        if (p == g) {
            std::string cycle;
            for (auto it = up.rbegin(); it != up.rend(); ++it)
                cycle += "'" + m_groups.at(*it).id + "' > ";
            cycle += "'" + m_groups.at(g).id + "'";
            return failure(ErrorCode::Cycle,
                           "group '" + m_groups.at(g).id + "' cannot move under '" +
                               m_groups.at(parent).id + "': that makes the cycle " + cycle,
                           "parent");
        }
    }
    // Step: depth. The deepest group of the moved subtree lands at parent_depth + its height.
    uint32_t height = 1;
    if (!g.is_null()) {
        std::vector<std::pair<GroupHandle, uint32_t>> stack{{g, 1}};
        while (!stack.empty()) {
            auto [h, level] = stack.back();
            stack.pop_back();
            height = std::max(height, level);
            for (GroupHandle c : m_groups.at(h).children.groups) stack.emplace_back(c, level + 1);
        }
    }
    if (parent_depth + height > MAX_GROUP_DEPTH)
        return failure(ErrorCode::InvalidArgument,
                       "groups would nest " + std::to_string(parent_depth + height) +
                           " deep under '" + m_groups.at(parent).id + "'; the limit is " +
                           std::to_string(MAX_GROUP_DEPTH),
                       "parent");
    return {};
}

void Scene::reparent_instance(InstanceHandle h, GroupHandle parent, UndoLog& undo) {
    InstanceRecord& r = m_instances.at(h);
    undo.records.emplace_back(undo::Reparented<InstanceHandle>{h, r.parent, r.child_slot});
    detach_child(children_of(r.parent).instances, m_instances, r.child_slot);
    std::vector<InstanceHandle>& list = children_of(parent).instances;
    r.parent = parent;
    r.child_slot = static_cast<uint32_t>(list.size());
    list.push_back(h);
    mark_instance_world(h);
}

void Scene::reparent_group(GroupHandle g, GroupHandle parent, UndoLog& undo) {
    GroupRecord& r = m_groups.at(g);
    undo.records.emplace_back(undo::Reparented<GroupHandle>{g, r.parent, r.child_slot});
    detach_child(children_of(r.parent).groups, m_groups, r.child_slot);
    std::vector<GroupHandle>& list = children_of(parent).groups;
    GroupRecord& moved = m_groups.at(g);
    moved.parent = parent;
    moved.child_slot = static_cast<uint32_t>(list.size());
    list.push_back(g);
}

void Scene::save_group(GroupHandle g, UndoLog& undo) const {
    const GroupRecord& r = m_groups.at(g);
    undo.records.emplace_back(undo::GroupState{g, save_fields<GroupFields>(r), r.dirty});
}

void Scene::remove_group(GroupHandle g, UndoLog& undo) {
    GroupRecord& r = m_groups.at(g);
    STRATA_CHECK(r.children.empty());
    detach_child(children_of(r.parent).groups, m_groups, r.child_slot);
    m_group_ids.erase(r.id, g);
    m_changes.mark(SceneDirty::Groups);
    --m_totals.groups;
    undo.records.emplace_back(undo::Removed<GroupHandle, GroupRecord>{g, m_groups.take(g)});
}

void Scene::remove_subtree(GroupHandle g, UndoLog& undo) {
    // Depth-first, children before their parent; the depth limit bounds the recursion.
    GroupRecord& r = m_groups.at(g);
    while (!r.children.instances.empty()) remove_instance(r.children.instances.back(), undo);
    while (!r.children.groups.empty()) remove_subtree(r.children.groups.back(), undo);
    remove_group(g, undo);
}

// Step: flattening -------------------------------------------------------------------------------

namespace {

/// Whether an object and its parent are still over the frame: no keys to compose (the common
/// case, kept off the pose machinery).
template <class Record>
bool still(const Record& r, const GroupRecord* parent) {
    const auto& rare = rare_of(r);
    return rare.motion.empty() && rare.animation.empty() && (!parent || parent->world_keys.empty());
}

template <class Record>
FramePose pose_of(const Record& r, const GroupRecord* parent, const Timeline& clock) {
    const auto& rare = rare_of(r);
    FramePose pose = local_pose(
        {r.transform, rare.motion, rare.animation, rare.animation_loop, rare.motion_interpolation},
        clock);
    if (!parent) return pose;
    return compose({parent->world, parent->world_keys, parent->world_interpolation}, pose);
}

/// Drops from `list` the handles of objects gone or no longer animated, and repeats (an update
/// that gave an animated object another animation lists it again).
template <class Handle, class Slots>
void prune_animated(std::vector<Handle>& list, const Slots& slots) {
    std::sort(list.begin(), list.end(), [](Handle a, Handle b) {
        return std::pair(a.index, a.generation) < std::pair(b.index, b.generation);
    });
    list.erase(std::unique(list.begin(), list.end()), list.end());
    std::erase_if(list, [&](Handle h) {
        const auto* r = slots.get(h);
        return !r || rare_of(*r).animation.empty();
    });
}

/// Whether a group's world, and its keys' (at rest), are finite under `parent_world`: what its
/// subtree's composition needs.
bool finite_under(const GroupRecord& group, const Affine& parent_world) {
    const Affine world = parent_world * group.transform;
    bool finite = world.is_finite();
    for (const Affine& k : group.motion) finite = finite && (world * k).is_finite();
    for (const Keyframe& k : group.animation)
        finite = finite && (parent_world * k.transform).is_finite();
    return finite;
}

}  // namespace

void Scene::refresh_instance_world(InstanceHandle h, InstanceRecord& r) {
    const GroupRecord* p = m_groups.get(r.parent);
    Affine world;
    std::vector<Affine> keys;
    const InstanceRare& rare = *r.rare;
    MotionInterpolation how = rare.motion_interpolation;
    if (still(r, p)) {
        world = p ? p->world * r.transform : r.transform;
    } else {
        FramePose pose = pose_of(r, p, m_shown);
        world = pose.start;
        keys = std::move(pose.keys);
        how = pose.how;
    }
    bool visible = r.visible;
    LodBands lod;
    if (p) {
        visible = visible && p->world_visible;
        lod = child_lod_bands(&p->world_lod, p->lod, p->world, rare.lod_near, rare.lod_far);
    }
    m_changes.count_world_transforms();
    DirtyBits<InstanceDirty> bits;
    if (!(world == r.world) || keys != rare.world_motion || how != rare.world_interpolation)
        bits |= InstanceDirty::Transform;
    if (visible != r.world_visible) bits |= InstanceDirty::Visibility;
    if (lod != rare.world_lod) bits |= InstanceDirty::Lod;
    r.world = world;
    r.world_visible = visible;
    // Still instances outside LOD groups (nearly all) leave their box empty.
    if (r.rare || !lod.empty() || !keys.empty() || how != MotionInterpolation::Linear) {
        InstanceRare& box = r.rare.mut();
        box.world_lod = std::move(lod);
        box.world_motion = std::move(keys);
        box.world_interpolation = how;
    }
    if (bits.any()) mark(h, bits);
}

void Scene::refresh_group_world(GroupRecord& group) {
    const GroupRecord* p = m_groups.get(group.parent);
    if (still(group, p)) {
        group.world = p ? p->world * group.transform : group.transform;
        group.world_keys.clear();
    } else {
        FramePose pose = pose_of(group, p, m_shown);
        group.world = pose.start;
        group.world_keys = std::move(pose.keys);
        group.world_interpolation = pose.how;
    }
    group.world_visible = group.visible && (!p || p->world_visible);
    group.world_lod.clear();
    if (p)
        group.world_lod =
            child_lod_bands(&p->world_lod, p->lod, p->world, group.lod_near, group.lod_far);
    group.dirty = {};
    m_changes.count_world_transforms();
}

bool Scene::under_dirty(GroupHandle g) const {
    for (; !g.is_null(); g = m_groups.at(g).parent)
        if (m_groups.at(g).dirty.any()) return true;
    return false;
}

void Scene::show(const Timeline& clock) {
    if (clock == m_shown) return;
    m_shown = clock;
    prune_animated(m_animated, m_instances);
    prune_animated(m_animated_groups, m_groups);
    for (GroupHandle g : m_animated_groups) mark(g, GroupDirty::Transform);
    // An instance below a marked group is refreshed by the group's walk.
    for (InstanceHandle h : m_animated)
        if (!under_dirty(m_instances.at(h).parent)) mark_instance_world(h);
    flatten_marked();
}

std::string Scene::group_chain(GroupHandle g) const {
    std::vector<const std::string*> ids;
    for (; !g.is_null(); g = m_groups.at(g).parent) ids.push_back(&m_groups.at(g).id);
    std::string chain;
    for (auto it = ids.rbegin(); it != ids.rend(); ++it)
        chain += (chain.empty() ? "'" : " > '") + **it + "'";
    return chain;
}

Status Scene::check_world_transforms() const {
    // An instance's world must pass the rule a root instance's transform passes (rays in its
    // space stay finite and invertible); a group's world must be finite to compose. The same
    // walk as flatten(), composing into locals: a dirty subtree top-down, each group carrying
    // its new world, then the single instances outside dirty subtrees.
    auto refuse = [&](GroupHandle g, const std::string& what, const char* why) {
        return failure(why ? ErrorCode::DegenerateTransform : ErrorCode::NotFinite,
                       what + "'s world transform " +
                           (why ? std::string("breaks the transform rule (") + why + ")"
                                : std::string("is not finite")) +
                           " through the group chain " + group_chain(g));
    };
    auto check_instance = [&](GroupHandle g, const Affine& parent_world,
                              const InstanceRecord& i) -> Status {
        const Affine world = parent_world * i.transform;
        if (const char* why = transform_problem(world))
            return refuse(g, "instance '" + i.id + "'", world.is_finite() ? why : nullptr);
        const InstanceRare& rare = *i.rare;
        for (std::size_t k = 0; k < rare.motion.size(); ++k) {
            const Affine key = world * rare.motion[k];
            if (const char* why = transform_problem(key))
                return refuse(g, "instance '" + i.id + "' (motion key " + std::to_string(k) + ")",
                              key.is_finite() ? why : nullptr);
        }
        for (std::size_t k = 0; k < rare.animation.size(); ++k) {
            const Affine key = parent_world * rare.animation[k].transform;
            if (const char* why = transform_problem(key))
                return refuse(g, "instance '" + i.id + "' (keyframe " + std::to_string(k) + ")",
                              key.is_finite() ? why : nullptr);
        }
        return {};
    };
    // Entries: a group and its parent's world.
    std::vector<std::pair<GroupHandle, Affine>> stack;
    for (GroupHandle top : m_world_groups) {
        const GroupRecord* r = m_groups.get(top);
        if (!r || r->dirty.none() || under_dirty(r->parent)) continue;
        const GroupRecord* parent = m_groups.get(r->parent);
        stack.emplace_back(top, parent ? parent->world : Affine::identity());
        while (!stack.empty()) {
            const auto [g, parent_world] = stack.back();
            stack.pop_back();
            const GroupRecord& group = m_groups.at(g);
            if (!finite_under(group, parent_world))
                return refuse(g, "group '" + group.id + "'", nullptr);
            const Affine world = parent_world * group.transform;
            for (InstanceHandle h : group.children.instances) {
                if (Status s = check_instance(g, world, m_instances.at(h)); !s) return s;
            }
            for (GroupHandle c : group.children.groups) stack.emplace_back(c, world);
        }
    }
    for (InstanceHandle h : m_world_instances) {
        const InstanceRecord* i = m_instances.get(h);
        const GroupRecord* parent = i ? m_groups.get(i->parent) : nullptr;
        // A root instance's transform passed the field rule; its motion keys times it did not.
        if (i && !parent && !i->rare->motion.empty()) {
            if (Status s = check_instance(i->parent, Affine::identity(), *i); !s) return s;
        }
        if (!parent || under_dirty(i->parent)) continue;
        if (Status s = check_instance(i->parent, parent->world, *i); !s) return s;
    }
    return {};
}

void Scene::flatten() {
    flatten_marked();
    show(m_timeline);
}

void Scene::flatten_marked() {
    // Step: dirty subtrees. A dirty group under another dirty group is done by the upper one;
    // every group a subtree walk visits is cleaned, so no group is visited twice.
    std::vector<GroupHandle> stack;
    for (GroupHandle top : m_world_groups) {
        const GroupRecord* r = m_groups.get(top);
        if (!r || r->dirty.none() || under_dirty(r->parent)) continue;
        stack.push_back(top);
        while (!stack.empty()) {
            const GroupHandle g = stack.back();
            stack.pop_back();
            GroupRecord& group = m_groups.at(g);
            refresh_group_world(group);
            for (InstanceHandle h : group.children.instances)
                refresh_instance_world(h, m_instances.at(h));
            stack.insert(stack.end(), group.children.groups.begin(), group.children.groups.end());
        }
    }
    // Step: single instances (added, moved, shown, hidden or reparented). Their parents are clean.
    for (InstanceHandle h : m_world_instances) {
        if (InstanceRecord* r = m_instances.get(h)) refresh_instance_world(h, *r);
    }
    m_world_groups.clear();
    m_world_instances.clear();
}

}  // namespace strata
