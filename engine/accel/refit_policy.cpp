#include "engine/accel/refit_policy.h"

#include <cstdio>

namespace strata {

namespace {

double growth(double now, double then) {
    if (then <= 0.0) return now > 0.0 ? 1e30 : 1.0;
    return now / then;
}

std::string format_growth(const char* what, double value, double limit) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%s grew %.2fx since the last build (limit %.2fx)", what, value,
                  limit);
    return buf;
}

}  // namespace

RefitDecision decide_refit(const RefitPolicy& policy, const BuildOptions& options,
                           const BuildBaseline& baseline, const MeshMetrics& now,
                           BuildReason reason) {
    if (!options.allow_refit)
        return {true, BuildReason::RefitNotAllowed, "build options do not allow refit"};
    const RefitLimits& limits = policy.limits_for(options.prefer);
    if (limits.max_refits != 0 && baseline.refits_since_build >= limits.max_refits)
        return {true, BuildReason::RefitLimit,
                std::to_string(baseline.refits_since_build) + " refits since the last build (limit " +
                    std::to_string(limits.max_refits) + ")"};
    const double bounds = growth(now.bounds_area, baseline.metrics.bounds_area);
    if (bounds > double(limits.max_bounds_growth))
        return {true, BuildReason::BoundsGrowth,
                format_growth("bounding-box area", bounds, double(limits.max_bounds_growth))};
    const double tris = growth(now.triangle_area, baseline.metrics.triangle_area);
    if (tris > double(limits.max_triangle_growth))
        return {true, BuildReason::TriangleGrowth,
                format_growth("triangle box area", tris, double(limits.max_triangle_growth))};
    char buf[128];
    std::snprintf(buf, sizeof buf, "refit %u since build; bounds %.2fx, triangles %.2fx",
                  baseline.refits_since_build + 1, bounds, tris);
    return {false, reason, buf};
}

}  // namespace strata
