#include "engine/scene/budget.h"

namespace strata {

std::string budget_message(const MeshTotals& totals, const SceneBudget& budget) {
    if (totals.instances > budget.max_instances)
        return "the scene would hold " + std::to_string(totals.instances) +
               " instances, over its budget of " + std::to_string(budget.max_instances) +
               " (max_scene_instances)";
    const bool triangles = totals.budget_triangles() > budget.max_triangles;
    if (totals.texture_bytes > budget.max_texture_bytes && !triangles &&
        totals.budget_vertices() <= budget.max_vertices)
        return "the scene's textures would take " + std::to_string(totals.texture_bytes) +
               " bytes (texels and image files), over its budget of " +
               std::to_string(budget.max_texture_bytes) + " (max_texture_mb)";
    if (!triangles && totals.key_positions == 0)
        return "the scene would hold " + std::to_string(totals.vertices) +
               " vertices, over its budget of " + std::to_string(budget.max_vertices) +
               " (max_scene_vertices)";
    if (!triangles)
        return "the scene would hold " + std::to_string(totals.vertices) + " vertices and " +
               std::to_string(totals.key_positions) + " vertex keys (motion_positions), " +
               std::to_string(totals.budget_vertices()) + " positions in all, over its budget of " +
               std::to_string(budget.max_vertices) + " (max_scene_vertices)";
    return "the scene would hold " + std::to_string(totals.triangles) + " triangles in " +
           std::to_string(totals.meshes) + " meshes, and " + std::to_string(totals.groups) +
           " groups, which count " + std::to_string(totals.budget_triangles()) +
           " with each mesh's overhead of " + std::to_string(MESH_OVERHEAD_TRIANGLES) +
           " and each group's of " + std::to_string(GROUP_OVERHEAD_TRIANGLES) +
           ", over its budget of " + std::to_string(budget.max_triangles) +
           " (max_scene_triangles)";
}

}  // namespace strata
