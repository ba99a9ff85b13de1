#pragma once
// An instance's transform in a TLAS: one transform, or motion keys (Embree time steps, evenly
// spaced over ray time [0, 1], interpolated linearly or, as quaternion decompositions, by SRT).

#include <cstdint>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/types.h"

struct RTCGeometryTy;
struct RTCSceneTy;

namespace strata {

/// Gives instance geometry `g` its world transform: `world` (12 floats, 3x4 row-major) when
/// `keys` is empty, else the world-space motion keys `keys` (at least two) as its time steps,
/// interpolated as `how` says. The caller commits the geometry.
void set_instance_transform(RTCGeometryTy* g, const float* world, const std::vector<Affine>& keys,
                            MotionInterpolation how);

/// Makes instance geometry `g` an instance of `blas` placed as set_instance_transform() says,
/// seen by rays whose mask shares a bit with `mask`, and commits it.
void set_instance(RTCGeometryTy* g, RTCSceneTy* blas, const float* world,
                  const std::vector<Affine>& keys, MotionInterpolation how, uint32_t mask);

}  // namespace strata
