#pragma once
// Procedural meshes for demos, tests and benchmarks.

#include <cstdint>
#include <string>
#include <vector>

#include "engine/scene/edits.h"
#include "engine/scene/types.h"

namespace strata {

/// An indexed triangle mesh.
struct MeshData {
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;
};

/// UV sphere centred at the origin. `segments` (>= 3) slices around the axis and segments / 2
/// rings give segments * (segments - 2) triangles: 1000 segments is about a million.
MeshData make_sphere(float radius, uint32_t segments);

/// Axis-aligned box centred at the origin: 8 vertices, 12 triangles.
MeshData make_box(const Vec3& size);

/// Grid in the XZ plane centred at the origin, facing +Y: (nx + 1) * (nz + 1) vertices and
/// 2 * nx * nz triangles.
MeshData make_plane(const Vec3& size, uint32_t nx, uint32_t nz);

/// An add_mesh edit that moves `data` into the scene under `id`.
AddMesh add_mesh_edit(std::string id, MeshData data, BuildOptions build = {});

/// Triangle count make_sphere(.., segments) produces.
uint64_t sphere_triangle_count(uint32_t segments);

}  // namespace strata
