#include "engine/scene/budget.h"

namespace strata {

std::string budget_message(const MeshTotals& totals, const SceneBudget& budget) {
    if (totals.texture_bytes > budget.max_texture_bytes &&
        totals.triangles <= budget.max_triangles && totals.vertices <= budget.max_vertices)
        return "the scene's textures would take " + std::to_string(totals.texture_bytes) +
               " bytes (texels and image files), over its budget of " +
               std::to_string(budget.max_texture_bytes) +
               " (max_texture_mb)";
    const bool triangles = totals.triangles > budget.max_triangles;
    return "the scene would hold " +
           std::to_string(triangles ? totals.triangles : totals.vertices) +
           (triangles ? " triangles" : " vertices") + ", over its budget of " +
           std::to_string(triangles ? budget.max_triangles : budget.max_vertices) +
           (triangles ? " (max_scene_triangles)" : " (max_scene_vertices)");
}

}  // namespace strata
