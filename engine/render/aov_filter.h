#pragma once
// A cheap edge-aware filter for frames of a few samples per pixel: the edge-avoiding à-trous
// wavelet filter (Dammertz et al. 2010) steered by each pixel's own noise level, as SVGF
// (Schied et al. 2017) does, and guided by the frame's AOVs.
//
//   1. demodulate: divide the colour by the albedo, so that texture and material detail is not
//      blurred (only the lighting is filtered), and remodulate at the end;
//   2. noise level: the variance of each pixel's mean luminance (`variance`, from the
//      renderer's per-pixel sums of squares), smoothed over 3x3 pixels. Without it (a 1-sample
//      frame) the spatial variance of the luminance over 3x3 pixels stands in. As samples add
//      up it shrinks, and with it everything the filter may do: at high spp it is (almost) the
//      identity;
//   3. fireflies: a pixel brighter than all 8 neighbours is brought down toward the brightest
//      of them, by at most `firefly_sigmas` of its noise deviations (so a converged highlight,
//      whose deviation is tiny, stays);
//   4. `iterations` passes of a 5x5 B3-spline kernel with holes (step 1, 2, 4, ...), each tap
//      weighted by how alike the two pixels' surfaces are: normals (cosine to a power), depth
//      (relative difference, scaled by the tap's distance), albedo, and lighting luminance in
//      units of the pixel's noise deviation. Each pass also carries the variance through its
//      weights (sum w^2 var / (sum w)^2) and smooths it over 3x3 pixels, so that later, wider
//      passes stop at smaller differences;
//   5. each pixel keeps the change d of its lighting luminance scaled by 1 / (1 + (d / (k s))^2),
//      s its noise deviation and k `change_sigmas` (`spatial_change_sigmas` without a measured
//      variance): a change within the noise is kept, one far past it (more likely lost detail
//      than removed noise) fades out; no pixel moves more than k s / 2.
//
// Pixels whose camera ray missed (infinite depth) are left as they are and are never taps. The
// filter is a pure function of the buffers, so filtered frames stay reproducible.

#include <cstdint>
#include <span>

#include "engine/render/aov_buffers.h"

namespace strata {

struct AovFilterSettings {
    uint32_t iterations = 3;         ///< passes; the widest reaches 2^(iterations+1) pixels out
    uint32_t normal_power = 64;      ///< weight max(0, n_p . n_q)^normal_power
    float depth_sigma = 0.03f;       ///< relative depth difference per pixel of tap distance
    float albedo_sigma = 0.05f;      ///< albedo difference (max channel) at which weight is 1/e
    float luminance_sigma = 4.0f;    ///< lighting luminance difference, in noise deviations
    float firefly_sigmas = 3.0f;     ///< most a firefly is brought down, in noise deviations
    /// A change of this many measured noise deviations is kept by half (step 5).
    float change_sigmas = 1.0f;
    /// The same against the spatial estimate of a 1-sample frame, which also counts the image's
    /// own detail as noise and so reads high.
    float spatial_change_sigmas = 2.0f;
};

/// Rec. 709 luminance of linear RGB: the quantity whose noise the filter measures.
inline float luminance(const Vec3& c) {
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}

/// Filters `buffers.color` in place using `albedo`, `normal` and `depth`, which must be present
/// (same size). `variance`: per pixel, the variance of the mean of the colour's luminance as the
/// caller estimates it (the renderer: the samples' variance over the count squared), or empty
/// when unknown (fewer than 2 samples).
void filter_frame(FrameBuffers& buffers, std::span<const float> variance = {},
                  const AovFilterSettings& settings = {});

}  // namespace strata
