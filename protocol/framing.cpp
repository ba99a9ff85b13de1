#include "protocol/framing.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/render/render_request.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

Bounds3 InstanceBounds::operator()(const InstanceRecord& i) {
    auto [it, fresh] = m_mesh_local.try_emplace(i.mesh.index);
    if (fresh) it->second = mesh_bounds(m_scene.meshes().at(i.mesh));
    return i.world.transform_bounds(it->second);
}

Bounds3 subtree_bounds(const Scene& s, GroupHandle g) {
    InstanceBounds world(s);
    Bounds3 out;
    std::vector<GroupHandle> pending{g};
    while (!pending.empty()) {
        const Children& c = s.children(pending.back());
        pending.pop_back();
        pending.insert(pending.end(), c.groups.begin(), c.groups.end());
        for (InstanceHandle h : c.instances) out.extend(world(s.instances().at(h)));
    }
    return out;
}

SetCamera frame_box(const Camera& camera, const Bounds3& box, float aspect) {
    Vec3 forward = camera.target - camera.eye;
    const float length = glm::length(forward);
    forward = length > 0.0f && std::isfinite(length) ? forward / length : Vec3(0.0f, 0.0f, -1.0f);
    const float half_v = 0.5f * glm::radians(camera.fov_y_deg);
    const float half_h = std::atan(std::tan(half_v) * std::max(aspect, 1e-3f));
    const float half = std::min(half_v, half_h);
    // The bounding sphere fits the cone of half-angle `half` at distance radius / sin(half); a
    // point-sized box still gets a small distance, so eye and target differ.
    const float radius = std::max(0.5f * glm::length(box.extent()), 1e-3f);
    const float distance = 1.05f * radius / std::sin(half);
    SetCamera out;
    out.target = box.center();
    out.eye = box.center() - forward * distance;
    return out;
}

Parsed<SetCamera> framed_override(const Scene& s, const FrameTarget& target,
                                  const std::optional<SetCamera>& override, float aspect) {
    const bool group = target.kind == FrameTarget::Kind::Group;
    const std::string where = group ? "/frame/group" : "/frame/instance";
    if (override && (override->eye || override->target))
        return Unexpected(problem_at(ProblemType::InvalidRequest, "/camera",
                                     "give frame or the camera's eye and target, not both"));
    Bounds3 box;
    if (group) {
        const GroupHandle h = s.find_group(target.id);
        if (!s.group(h))
            return Unexpected(
                problem_at(ProblemType::UnknownId, where, "no group with id '" + target.id + "'"));
        box = subtree_bounds(s, h);
        if (box.empty())
            return Unexpected(problem_at(ProblemType::InvalidValue, where,
                                         "group '" + target.id + "' has no instances to frame"));
    } else {
        const auto r = s.instance(s.find_instance(target.id));
        if (!r)
            return Unexpected(problem_at(ProblemType::UnknownId, where,
                                         "no instance with id '" + target.id + "'"));
        box = InstanceBounds(s)(*r.value());
    }
    // The override's up and field of view, checked as the launch will check them.
    auto camera = resolve_camera(override, s.camera());
    if (!camera) return Unexpected(problem_from(camera.error()));
    SetCamera out = override.value_or(SetCamera{});
    const SetCamera framed = frame_box(camera.value(), box, aspect);
    out.eye = framed.eye;
    out.target = framed.target;
    return out;
}

}  // namespace strata::protocol
