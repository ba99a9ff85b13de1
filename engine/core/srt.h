#pragma once
// An affine transform as translate * rotate * (scale and skew): Embree's quaternion
// decomposition of an instance's motion keys (rtcSetGeometryTransformQuaternion). Interpolating
// the parts, the rotation by spherical linear interpolation, turns a spinning wheel rigidly
// where a linear blend of matrices would shrink it halfway.

#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "engine/core/math.h"

namespace strata {

/// The parts of an affine transform: translation * rotation * S, where S is upper triangular
/// with `scale` on its diagonal and `skew` (xy, xz, yz) above it.
struct SrtParts {
    Vec3 scale{1.0f};
    Vec3 skew{0.0f};
    glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
    Vec3 translation{0.0f};
};

/// The parts of `a` (its linear part must be invertible; a mirroring transform gets a negative
/// scale_z).
SrtParts decompose_srt(const Affine& a);
/// The transform the parts make.
Affine compose_srt(const SrtParts& p);
/// The parts of each key, each rotation on the same side of the quaternion sphere as the one
/// before, so that every step between keys turns the shorter way (as Embree then interpolates).
std::vector<SrtParts> srt_keys(const std::vector<Affine>& keys);
/// Between `a` (t = 0) and `b` (t = 1): scale, skew and translation linearly, the rotation by
/// slerp along the shorter way.
Affine srt_lerp(const SrtParts& a, const SrtParts& b, float t);

}  // namespace strata
