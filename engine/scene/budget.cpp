#include "engine/scene/budget.h"

namespace strata {

std::string budget_message(const MeshTotals& totals, const SceneBudget& budget) {
    const bool triangles = totals.triangles > budget.max_triangles;
    return "the scene would hold " +
           std::to_string(triangles ? totals.triangles : totals.vertices) +
           (triangles ? " triangles" : " vertices") + ", over its budget of " +
           std::to_string(triangles ? budget.max_triangles : budget.max_vertices) +
           (triangles ? " (max_scene_triangles)" : " (max_scene_vertices)");
}

}  // namespace strata
