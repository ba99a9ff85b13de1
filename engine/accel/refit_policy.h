#pragma once
// When a refit stops paying off. Refitting keeps a BVH's topology and only widens its boxes, so as
// vertices drift from where the BVH was built, boxes overlap more and tracing slows down. The
// policy measures drift since the last build and turns a refit into a rebuild past a limit.
//
//   bounds growth    surface area of the mesh's box now / at the last build. Catches explosions
//                    and large motions: the tree's top boxes grow with it.
//   triangle growth  sum over triangles of their own boxes' surface areas, now / at the last
//                    build. Catches stretching deformations that leave the outer box alone.
//   refit count      refits since the last build; 0 means unlimited.
//
// Limits differ by the mesh's build preference: fast_trace meshes rebuild sooner.

#include <cstdint>
#include <string>

#include "engine/accel/report.h"
#include "engine/scene/types.h"

namespace strata {

struct RefitLimits {
    float max_bounds_growth = 1.5f;
    float max_triangle_growth = 1.5f;
    uint32_t max_refits = 0;  ///< 0: unlimited
};

struct RefitPolicy {
    RefitLimits fast_trace{1.5f, 1.5f, 256};
    RefitLimits fast_build{4.0f, 4.0f, 0};

    const RefitLimits& limits_for(BuildPreference p) const {
        return p == BuildPreference::FastTrace ? fast_trace : fast_build;
    }
};

/// Drift measurements of one mesh's current positions.
struct MeshMetrics {
    double bounds_area = 0.0;    ///< surface area of the mesh's bounding box
    double triangle_area = 0.0;  ///< sum of the surface areas of each triangle's bounding box
};

/// What a mesh's BLAS looked like when it was last built.
struct BuildBaseline {
    MeshMetrics metrics;
    uint32_t refits_since_build = 0;
};

struct RefitDecision {
    bool rebuild = false;
    BuildReason reason = BuildReason::PositionsChanged;
    std::string detail;
};

/// Decides whether a refit requested for `reason` (PositionsChanged or RefitRequested) stays a
/// refit, given the mesh's options, its baseline and its metrics now.
RefitDecision decide_refit(const RefitPolicy& policy, const BuildOptions& options,
                           const BuildBaseline& baseline, const MeshMetrics& now,
                           BuildReason reason);

}  // namespace strata
