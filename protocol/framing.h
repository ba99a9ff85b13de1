#pragma once
// Aiming a camera at part of the scene: the world bounds of a group's subtree, and the camera
// that frames a box (a render's `frame`, GET /v1/scene/groups/{id}'s `bounds`, an import's).

#include <optional>
#include <string>
#include <unordered_map>

#include "engine/scene/edits.h"
#include "engine/scene/scene.h"
#include "protocol/problem.h"

namespace strata::protocol {

/// World bounds of instances, each mesh's object-space bounds computed once (for walks over
/// many instances of few meshes).
class InstanceBounds {
public:
    explicit InstanceBounds(const Scene& s) : m_scene(s) {}
    Bounds3 operator()(const InstanceRecord& i);

private:
    const Scene& m_scene;
    std::unordered_map<uint32_t, Bounds3> m_mesh_local;  ///< by mesh slot
};

/// World bounds of every instance in group `g`'s subtree, hidden ones too (as an instance's own
/// `bounds` are); each mesh's object-space bounds are computed once. Empty when there is none.
/// O(instances below + the vertices of their meshes).
Bounds3 subtree_bounds(const Scene& s, GroupHandle g);

/// What a render's `frame` names: a group (its subtree) or an instance.
struct FrameTarget {
    enum class Kind : uint8_t { Group, Instance };
    Kind kind = Kind::Group;
    std::string id;
};

/// The eye and target that frame `box` seen from `camera`: the same viewing direction, up and
/// field of view, the target at the box's centre and the eye far enough back that the box's
/// bounding sphere fits the narrower of the vertical and horizontal fields of view (`aspect`:
/// width / height).
SetCamera frame_box(const Camera& camera, const Bounds3& box, float aspect);

/// The camera override of a render that frames `target`: `override` (its up and fov) with the
/// eye and target that frame it, from the scene camera's direction. An unknown id is an
/// unknown-id problem at /frame/<kind>; nothing to frame (a group without instances) an
/// invalid-value one; an override that sets eye or target too is refused at /camera.
Parsed<SetCamera> framed_override(const Scene& s, const FrameTarget& target,
                                  const std::optional<SetCamera>& override, float aspect);

}  // namespace strata::protocol
