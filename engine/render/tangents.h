#pragma once
// Per-vertex tangent frames for normal maps, made at commit from a mesh's positions, triangles,
// normals and texture coordinates.
//
// The convention is MikkTSpace's, which glTF prescribes when a file has no tangents: each
// triangle's tangent is the direction in which u grows (dP/du), the triangles around a vertex
// contribute it weighted by their corner angle there, and the vertex's tangent is that sum made
// orthogonal to the vertex normal. The bitangent is not stored: it is cross(normal, tangent)
// times the handedness w = +-1, with w chosen so that the bitangent points where v falls. glTF's
// v grows downward in the image, and a normal map's +Y (green) means up in the image, so +Y
// follows the bitangent. Unlike MikkTSpace proper, vertices are not split where handedness
// changes across a uv seam (a mirrored half takes the handedness of the larger angle sum).
// Triangles without uv area contribute nothing; a vertex none contributes to gets any tangent
// orthogonal to its normal.

#include <vector>

#include <glm/glm.hpp>

#include "engine/core/math.h"
#include "engine/scene/types.h"

namespace strata {

/// One tangent (xyz, unit) and handedness (w) per vertex; `normals` and `uvs` hold one entry per
/// position, and every triangle indexes within them.
std::vector<glm::vec4> make_tangents(const std::vector<Vec3>& positions,
                                     const std::vector<Triangle>& triangles,
                                     const std::vector<Vec3>& normals,
                                     const std::vector<Vec2>& uvs);

/// A unit vector orthogonal to unit `n`.
Vec3 any_orthogonal(const Vec3& n);

}  // namespace strata
