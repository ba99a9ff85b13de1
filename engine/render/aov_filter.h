#pragma once
// A cheap edge-aware filter for frames of a few samples per pixel: the edge-avoiding à-trous
// wavelet filter (Dammertz et al. 2010, as SVGF uses it), guided by the frame's own AOVs.
//
//   1. demodulate: divide the colour by the albedo, so that texture and material detail is not
//      blurred (only the lighting is filtered), and remodulate at the end; a pixel brighter than
//      all 8 neighbours is clamped to the brightest of them (a firefly would spread otherwise);
//   2. `iterations` passes of a 5x5 B3-spline kernel with holes (step 1, 2, 4, ...), each tap
//      weighted by how alike the two pixels' surfaces are: normals (cosine to a power), depth
//      (relative difference, scaled by the tap's distance), albedo, and lighting luminance
//      relative to the local noise level (the standard deviation of the demodulated luminance
//      over the 3x3 neighbourhood, measured once before the passes).
//
// Pixels whose camera ray missed (infinite depth) are left as they are and are never taps. The
// filter is a pure function of the buffers, so filtered frames stay reproducible.

#include <cstdint>

#include "engine/render/aov_buffers.h"

namespace strata {

struct AovFilterSettings {
    uint32_t iterations = 3;       ///< passes; the widest reaches 2^(iterations+1) pixels out
    float normal_power = 64.0f;    ///< weight max(0, n_p . n_q)^normal_power
    float depth_sigma = 0.03f;     ///< relative depth difference per pixel of tap distance
    float albedo_sigma = 0.05f;    ///< albedo difference (max channel) at which weight is 1/e
    float luminance_sigma = 2.0f;  ///< luminance difference, in local standard deviations
};

/// Filters `buffers.color` in place using `albedo`, `normal` and `depth`, which must be present
/// (same size).
void filter_frame(FrameBuffers& buffers, const AovFilterSettings& settings = {});

}  // namespace strata
