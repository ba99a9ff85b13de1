#pragma once
// The scene budget: how many triangles and vertices the scene's meshes may hold in all. One small
// edit can ask for a lot (a sphere shape of 4M triangles is ~130 bytes of JSON and ~500 MB of BLAS
// at commit), so a batch that leaves the scene past its budget is refused when it is applied,
// before anything is built. Scene::apply keeps the totals as its rules change meshes.

#include <cstdint>
#include <string>

namespace strata {

/// What one mesh costs beyond its triangles, counted as triangles against max_triangles: its
/// records, its BLAS's fixed part and its Embree geometry take about what this many triangles
/// do, so that many tiny meshes cannot hold more memory than the triangle budget allows.
inline constexpr uint64_t MESH_OVERHEAD_TRIANGLES = 128;
/// The same for a group (its record, id, child lists and world transform).
inline constexpr uint64_t GROUP_OVERHEAD_TRIANGLES = 4;

/// Totals a scene may hold, over its meshes (instances share their mesh's BLAS and cost none).
struct SceneBudget {
    uint64_t max_triangles = uint64_t(1) << 24;
    uint64_t max_vertices = uint64_t(1) << 24;
    /// Texture memory over all textures: decoded texels (6 bytes each, engine/image/texture.h)
    /// and the image files they were decoded from.
    uint64_t max_texture_bytes = uint64_t(256) << 20;
    /// Instances in all (each costs a few hundred bytes beside its mesh).
    uint64_t max_instances = uint64_t(1) << 24;
};

/// What the scene holds: its meshes' totals (each mesh counted once), and its instances.
struct MeshTotals {
    uint64_t vertices = 0;
    /// Vertex keys after the first (motion_positions): each takes a vertex's memory in the scene
    /// and the BLAS, so the vertex budget counts them.
    uint64_t key_positions = 0;
    uint64_t triangles = 0;
    uint64_t texture_bytes = 0;  ///< decoded texels and image files of every texture
    uint64_t meshes = 0;
    uint64_t groups = 0;
    uint64_t instances = 0;

    /// Triangles as the budget counts them: each mesh's, plus each mesh's and group's overhead.
    uint64_t budget_triangles() const {
        return triangles + meshes * MESH_OVERHEAD_TRIANGLES + groups * GROUP_OVERHEAD_TRIANGLES;
    }
    /// Vertex positions as the budget counts them: every key of every vertex.
    uint64_t budget_vertices() const { return vertices + key_positions; }
    bool grew_from(const MeshTotals& before) const {
        return budget_vertices() > before.budget_vertices() ||
               budget_triangles() > before.budget_triangles() ||
               texture_bytes > before.texture_bytes || instances > before.instances;
    }
};

/// True when `totals` exceed `budget`.
inline bool over_budget(const MeshTotals& totals, const SceneBudget& budget) {
    return totals.budget_triangles() > budget.max_triangles ||
           totals.budget_vertices() > budget.max_vertices ||
           totals.texture_bytes > budget.max_texture_bytes ||
           totals.instances > budget.max_instances;
}

/// "the scene would hold N triangles, over its budget of M (max_scene_triangles)".
std::string budget_message(const MeshTotals& totals, const SceneBudget& budget);

}  // namespace strata
