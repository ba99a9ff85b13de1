#pragma once
// Display transform for 8-bit frames (PNG). EXR frames stay linear and skip all of this.
//
//   1. exposure: linear RGB is multiplied by 2^exposure (exposure in EV stops, 0 = unchanged);
//   2. tone mapping: the ACES filmic curve as fitted by Stephen Hill (ACES input matrix, RRT+ODT
//      rational fit, output matrix), clamped to [0, 1]. As in the ACES reference, scene mid grey
//      0.18 maps to about 0.105 display-linear (sRGB code 91) and 1.0 to about 0.62 (code 206);
//      highlights roll off smoothly and saturate towards white instead of clipping per channel;
//   3. encoding: the sRGB transfer function, rounded to the nearest 8-bit code (exactly: a table
//      lookup corrected against the code boundaries, no pow per pixel).

#include <cstddef>
#include <cstdint>

#include "engine/core/math.h"

namespace strata {

/// The ACES fitted tone curve of a linear color, clamped to [0, 1].
Vec3 aces_fitted(const Vec3& linear);

/// A value in [0, 1] (clamped) through the sRGB transfer function, as the nearest 8-bit code.
uint8_t linear_to_srgb8(float v);

/// Exposure, tone mapping and sRGB encoding of `count` pixels into packed 8-bit RGB; parallel.
void tonemap_to_srgb8(const Vec3* linear, std::size_t count, float exposure_ev, uint8_t* rgb_out);

}  // namespace strata
