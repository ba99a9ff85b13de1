#pragma once
// Level of detail (OptiX 6's Selector, chosen per ray). A group with `lod: true` makes each of its
// children a level: a child, and everything below it, is drawn only for the rays whose LOD
// distance from the group lies in the child's [lod_near, lod_far). A ray's LOD distance from a
// group is the distance from the ray's eye to the group's origin (the translation of its world
// transform). The eye of every ray a launch traces, camera, shadow and bounce rays alike, is the
// launch's camera, so all of them see the level the camera sees: a far object's shadow rays
// never meet its near level inside its far one. (A ray traced without a camera has its own
// origin as its eye.) Camera moves cost nothing: the choice is made while tracing
// (engine/accel/lod_scenes.h), never built into an acceleration structure.

#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/math.h"
#include "engine/core/result.h"

namespace strata {

/// lod_far's default: no far limit (no ray reaches this far in a scene within MAX_COORDINATE).
inline constexpr float LOD_NO_LIMIT = 1e15f;

/// One level-of-detail group's condition on what lies below one of its children: drawn for rays
/// whose eye lies at a distance in [near, far) from `centre` (the group's world origin).
struct LodBand {
    Vec3 centre{0.0f};
    float near = 0.0f;
    float far = LOD_NO_LIMIT;

    friend bool operator==(const LodBand&, const LodBand&) = default;
};

/// Every LOD group above an object, outermost first: it is drawn for a ray only when each band
/// holds. Empty for an object under no LOD group (the usual case: then it is always drawn).
using LodBands = std::vector<LodBand>;

/// Whether the bands all hold for a ray whose eye is world point `eye`.
inline bool lod_selects(const LodBands& bands, const Vec3& eye) {
    for (const LodBand& b : bands) {
        const Vec3 d = eye - b.centre;
        const float distance = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        if (!(distance >= b.near && distance < b.far)) return false;
    }
    return true;
}

/// Refuses a range whose far end is not above its near end (the error names `lod_far`).
Status check_lod_range(float near, float far);

/// The bands of a child whose own range is [near, far): its parent's (`parent_bands`), and the
/// parent's own condition on the child when the parent is an LOD group (`parent_lod`) at
/// `parent_world`.
LodBands child_lod_bands(const LodBands* parent_bands, bool parent_lod,
                         const Affine& parent_world, float near, float far);

}  // namespace strata
