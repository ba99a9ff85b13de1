#pragma once
// The op families, one file each; edit_ops.cpp joins them into the one op list (internal to the
// protocol).

#include <span>

#include "protocol/edit_ops.h"

namespace strata::protocol::ops {

/// add_mesh, update_mesh, replace_triangles, remove_mesh (mesh_ops.cpp).
std::span<const EditOp> mesh_ops();
/// add_material, update_material (material_ops.cpp).
std::span<const EditOp> material_ops();
/// add_texture, remove_texture (texture_ops.cpp).
std::span<const EditOp> texture_ops();
/// add_instance, update_instance, set_transform, remove_instance (instance_ops.cpp).
std::span<const EditOp> instance_ops();
/// add_instances, update_instances, remove_instances (bulk_instance_ops.cpp).
std::span<const EditOp> bulk_instance_ops();
/// add_group, update_group, remove_group (group_ops.cpp).
std::span<const EditOp> group_ops();

/// add_light, update_light, remove_light (light_ops.cpp).
std::span<const EditOp> light_ops();

/// Reads an optional `parent` member: absent leaves `out` unset; null sets it to the root
/// (nullopt inside); a string sets the group id (group_ops.cpp).
void read_parent(OpFields& f, std::optional<std::optional<std::string>>& out);
/// mark_dirty, set_camera, set_lighting, clear (scene_ops.cpp).
std::span<const EditOp> scene_ops();

}  // namespace strata::protocol::ops
