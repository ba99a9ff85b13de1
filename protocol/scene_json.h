#pragma once
// Scene state as JSON for GET /v1/scene and
// GET /v1/scene/{meshes,instances,materials,groups,textures}/{id}.
// Call these under the engine's read lock (Engine::read) so one document shows one version.

#include <optional>
#include <string_view>

#include "engine/scene/scene.h"
#include "protocol/json_document.h"

namespace strata::protocol {

/// The shortest decimal that reads back as `f` (0.45f prints as 0.45).
Json float_to_json(float f);
Json vec3_to_json(const Vec3& v);
/// 4x4 row-major, 16 numbers.
Json affine_to_json(const Affine& a);
Json camera_to_json(const Camera& c);
Json lighting_to_json(const Lighting& l);
Json timeline_to_json(const Timeline& t);
/// {"min": [3], "max": [3]}, or null for an empty box.
Json bounds_to_json(const Bounds3& b);

/// Version, counts, world bounds, camera and lighting.
Json scene_summary_to_json(const Scene& s);

/// Object-space bounds of a mesh's vertices (O(vertices)).
Bounds3 mesh_bounds(const MeshRecord& m);

/// One live object's document (GET by id, and each item of a listing). An instance's world
/// bounds come from its mesh's object-space bounds, which a listing computes once per mesh.
Json mesh_json(const Scene& s, MeshHandle h, const MeshRecord& m);
Json instance_json(const Scene& s, InstanceHandle h, const InstanceRecord& i,
                   const Bounds3& mesh_local_bounds);
Json material_json(const Scene& s, const MaterialRecord& m);
Json light_json(const Scene& s, const LightRecord& l);
/// A group: parent, own and world transform and visibility, and how many children it has.
Json group_json(const Scene& s, GroupHandle h, const GroupRecord& g);
/// A texture: its size, format and the bytes it takes encoded and decoded.
Json texture_json(const Scene& s, const TextureRecord& t);

/// One object's state, or nullopt when no object has that id.
std::optional<Json> mesh_to_json(const Scene& s, std::string_view id);
std::optional<Json> instance_to_json(const Scene& s, std::string_view id);
std::optional<Json> material_to_json(const Scene& s, std::string_view id);
std::optional<Json> group_to_json(const Scene& s, std::string_view id);
std::optional<Json> light_to_json(const Scene& s, std::string_view id);
std::optional<Json> texture_to_json(const Scene& s, std::string_view id);

}  // namespace strata::protocol
