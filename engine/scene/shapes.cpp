#include "engine/scene/shapes.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace strata {

AddMesh add_mesh_edit(std::string id, MeshData data, BuildOptions build) {
    AddMesh e;
    e.id = std::move(id);
    e.positions = std::move(data.positions);
    e.triangles = std::move(data.triangles);
    e.build = build;
    return e;
}

uint64_t sphere_triangle_count(uint32_t segments) {
    segments = std::max(segments, 3u);
    const uint64_t rings = std::max(segments / 2, 2u);
    return uint64_t(segments) * 2 * (rings - 1);
}

MeshData make_sphere(float radius, uint32_t segments) {
    segments = std::max(segments, 3u);
    const uint32_t rings = std::max(segments / 2, 2u);
    MeshData m;
    // Poles are single vertices; rings 1..rings-1 are full circles of `segments` vertices.
    m.positions.reserve(2 + std::size_t(rings - 1) * segments);
    m.positions.push_back({0.0f, radius, 0.0f});
    for (uint32_t r = 1; r < rings; ++r) {
        const double theta = std::numbers::pi * r / rings;
        const float y = static_cast<float>(std::cos(theta) * double(radius));
        const double ring_radius = std::sin(theta) * double(radius);
        for (uint32_t s = 0; s < segments; ++s) {
            const double phi = 2.0 * std::numbers::pi * s / segments;
            m.positions.push_back({static_cast<float>(ring_radius * std::cos(phi)), y,
                                   static_cast<float>(ring_radius * std::sin(phi))});
        }
    }
    const uint32_t south = static_cast<uint32_t>(m.positions.size());
    m.positions.push_back({0.0f, -radius, 0.0f});

    auto ring_vertex = [&](uint32_t r, uint32_t s) {
        return 1 + (r - 1) * segments + s % segments;
    };
    m.triangles.reserve(sphere_triangle_count(segments));
    for (uint32_t s = 0; s < segments; ++s)
        m.triangles.push_back({0, ring_vertex(1, s + 1), ring_vertex(1, s)});
    for (uint32_t r = 1; r + 1 < rings; ++r) {
        for (uint32_t s = 0; s < segments; ++s) {
            const uint32_t a = ring_vertex(r, s), b = ring_vertex(r, s + 1);
            const uint32_t c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
            m.triangles.push_back({a, b, d});
            m.triangles.push_back({a, d, c});
        }
    }
    for (uint32_t s = 0; s < segments; ++s)
        m.triangles.push_back({south, ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1)});
    return m;
}

MeshData make_box(const Vec3& size) {
    const Vec3 h = 0.5f * size;
    MeshData m;
    for (int i = 0; i < 8; ++i)
        m.positions.push_back({(i & 1) ? h.x : -h.x, (i & 2) ? h.y : -h.y, (i & 4) ? h.z : -h.z});
    // Counter-clockwise seen from outside.
    m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                   {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    return m;
}

MeshData make_plane(const Vec3& size, uint32_t nx, uint32_t nz) {
    nx = std::max(nx, 1u);
    nz = std::max(nz, 1u);
    MeshData m;
    m.positions.reserve(std::size_t(nx + 1) * (nz + 1));
    for (uint32_t z = 0; z <= nz; ++z) {
        for (uint32_t x = 0; x <= nx; ++x) {
            m.positions.push_back(
                {(float(x) / nx - 0.5f) * size.x, 0.0f, (float(z) / nz - 0.5f) * size.z});
        }
    }
    m.triangles.reserve(std::size_t(nx) * nz * 2);
    for (uint32_t z = 0; z < nz; ++z) {
        for (uint32_t x = 0; x < nx; ++x) {
            const uint32_t a = z * (nx + 1) + x, b = a + 1, c = a + nx + 1, d = c + 1;
            m.triangles.push_back({a, c, b});  // +Y facing
            m.triangles.push_back({b, c, d});
        }
    }
    return m;
}

}  // namespace strata
