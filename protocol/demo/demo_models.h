#pragma once
// The demo scene with a real model in it: the engine's procedural demo scene
// (engine/scene/demo_scene.h) plus Keenan Crane's "Spot" (CC0, protocol/demo/SOURCES.md), read
// from the OBJ file compiled into the binary through the same importer as POST /v1/assets. This
// is what `strata-server --demo` and `strata play --embedded --demo` start from.

#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"
#include "engine/scene/edits.h"

namespace strata::demo {

/// Id prefix of what the model adds: the group "spot" and, under it, its mesh, material and
/// instance ("spot.…").
inline constexpr std::string_view MODEL_PREFIX = "spot";

/// make_demo_scene()'s batch with the model appended (one batch: the scene starts at version 1).
/// Fails only if the compiled-in file does not import, which a test rules out.
Result<EditBatch> scene_with_models();

/// Smooth per-vertex normals of a triangle mesh: the area-weighted sum of the normals of the
/// triangles around each position. Vertices at one position (split by a UV seam, say) share
/// their normal, so a seam does not show in the shading. A position no triangle with an area
/// touches gets +Y.
std::vector<Vec3> smooth_normals(const std::vector<Vec3>& positions,
                                 const std::vector<Triangle>& triangles);

}  // namespace strata::demo
