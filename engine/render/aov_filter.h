#pragma once
// A cheap edge-aware filter for frames of a few samples per pixel: the edge-avoiding à-trous
// wavelet filter (Dammertz et al. 2010) steered by each pixel's own noise level, as SVGF
// (Schied et al. 2017) does, and guided by the frame's AOVs.
//
//   1. demodulate: divide the colour by the albedo, so that texture and material detail is not
//      blurred (only the lighting is filtered), and remodulate at the end;
//   2. noise level: the variance of each pixel's mean luminance, from the renderer's
//      per-pixel sums of squares (`variance` over `samples`, see filter_frame), smoothed over
//      3x3 pixels. Without it (a 1-sample frame) the spatial variance of the luminance over 3x3
//      pixels stands in. As samples add up it shrinks, and with it everything the filter may
//      do: at high spp it is (almost) the identity;
//   3. fireflies: a pixel brighter than all 8 neighbours is a firefly when its excess over the
//      brightest of them is within `firefly_noise_sigmas` of its samples' own spread, and is
//      taken down to that neighbour (a converged highlight, whose samples agree, stays); with
//      the spatial estimate, it is taken down by at most `firefly_sigmas` deviations;
//   4. `iterations` passes of a 5x5 B3-spline kernel with holes (step 1, 2, 4, ...), each tap
//      weighted by how alike the two pixels' surfaces are: normals (cosine to a power), depth
//      (relative difference, scaled by the tap's distance), albedo, and lighting luminance in
//      units of the pixel's noise deviation. Each pass also carries the variance through its
//      weights (sum w^2 var / (sum w)^2) and smooths it over 3x3 pixels, so that later, wider
//      passes stop at smaller differences;
//   5. each pixel keeps the change d of its lighting luminance (by the passes) scaled by
//      1 / (1 + (d / (k s))^2), s its noise deviation and k from `change_sigmas` at
//      `converged_samples` up to `few_samples_change_sigmas` at a few samples
//      (`spatial_change_sigmas` without a measured variance): a change within the noise is
//      kept, one far past it (more likely lost detail than removed noise) fades out; no pixel
//      moves more than k s / 2.
//
// Pixels whose camera ray missed (infinite depth) are left as they are and are never taps. The
// filter is a pure function of the buffers, so filtered frames stay reproducible.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>

#include "engine/render/aov_buffers.h"

namespace strata {

struct AovFilterSettings {
    /// Passes (at most 6); the widest reaches 2^iterations pixels out.
    uint32_t iterations = 3;
    uint32_t normal_power = 64;    ///< weight max(0, n_p . n_q)^normal_power
    float depth_sigma = 0.03f;     ///< relative depth difference per pixel of tap distance
    float albedo_sigma = 0.05f;    ///< albedo difference (max channel) at which weight is 1/e
    float luminance_sigma = 4.0f;  ///< lighting luminance difference, in noise deviations
    /// Spatial noise: most a firefly is brought down, in noise deviations (step 3).
    float firefly_sigmas = 3.0f;
    /// A change of this many measured noise deviations is kept by half (step 5), from
    /// `converged_samples` samples on; 0.5 more for each halving of the count below it, up to
    /// `few_samples_change_sigmas`.
    float change_sigmas = 1.0f;
    uint32_t converged_samples = 64;
    float few_samples_change_sigmas = 3.0f;
    /// The same against the spatial estimate of a 1-sample frame, which also counts the image's
    /// own detail as noise and so reads high.
    float spatial_change_sigmas = 3.0f;
    /// Measured noise: a pixel brighter than all its neighbours by at most this many of its
    /// deviations (its samples' spread, not divided again: a rare bright path is not helped by
    /// stratification) is a firefly (step 3).
    float firefly_noise_sigmas = 2.0f;
};

/// The filter's working memory (about 100 bytes a pixel), kept between frames by a caller that
/// filters many: allocating and first touching it each frame cost about as much as one pass.
/// One filter_frame at a time may use it.
class FilterScratch {
public:
    FilterScratch();
    ~FilterScratch();
    FilterScratch(const FilterScratch&) = delete;
    FilterScratch& operator=(const FilterScratch&) = delete;
    /// Bytes held.
    std::size_t bytes() const;
    /// Frees it all.
    void release();

    struct Buffers;  // aov_filter.cpp
    std::unique_ptr<Buffers> buffers;
};

/// Filters `buffers.color` in place using `albedo`, `normal` and `depth`, which must be present
/// (same size). `variance`: per pixel, the variance of the mean of the colour's luminance were
/// its `samples` samples independent (the sample variance over the count), or empty when unknown
/// (fewer than 2 samples). The firefly step takes it as it is (a rare bright path is not helped
/// by stratification); the rest divides it by `samples` once more, since the renderer's
/// stratified samples converge about like 1/n, not 1/sqrt(n) (tests/bench/NOTES.md: over the
/// count alone, converged detail was taken for noise at 64 spp). `scratch`: working memory to
/// reuse, or null for memory of its own.
void filter_frame(FrameBuffers& buffers, std::span<const float> variance = {}, uint32_t samples = 1,
                  const AovFilterSettings& settings = {}, FilterScratch* scratch = nullptr);

}  // namespace strata
