#include "engine/accel/report.h"

#include <cstdio>

namespace strata {

const char* tlas_action_name(TlasAction a) {
    switch (a) {
        case TlasAction::None: return "none";
        case TlasAction::Update: return "update";
        case TlasAction::Rebuild: return "rebuild";
    }
    return "none";
}

const char* build_reason_name(BuildReason r) {
    switch (r) {
        case BuildReason::Added: return "added";
        case BuildReason::TopologyChanged: return "topology_changed";
        case BuildReason::RebuildRequested: return "rebuild_requested";
        case BuildReason::RefitNotAllowed: return "refit_not_allowed";
        case BuildReason::BoundsGrowth: return "bounds_growth";
        case BuildReason::TriangleGrowth: return "triangle_growth";
        case BuildReason::RefitLimit: return "refit_limit";
        case BuildReason::Clustered: return "clustered";
        case BuildReason::Shared: return "shared";
        case BuildReason::Unshared: return "unshared";
        case BuildReason::PositionsChanged: return "positions_changed";
        case BuildReason::TrianglesReplaced: return "triangles_replaced";
        case BuildReason::KeysChanged: return "keys_changed";
        case BuildReason::RefitRequested: return "refit_requested";
    }
    return "added";
}

std::string RebuildReport::summary() const {
    char buf[256];
    std::snprintf(buf, sizeof buf, "v%llu tlas=%s(%llu) rebuilds=%u refits=%u prims=%llu ms=%.3f",
                  static_cast<unsigned long long>(version), tlas_action_name(tlas_action),
                  static_cast<unsigned long long>(tlas_instances), blas_rebuilds, blas_refits,
                  static_cast<unsigned long long>(primitives_built + primitives_refit),
                  phases.total_ms);
    return buf;
}

}  // namespace strata
