#pragma once
// A blue-noise mask: a 64x64 tile (repeated over the image) holding each rank 0..4095 once, laid
// out so that the pixels of any range of ranks are spread evenly, without clumps or holes
// (Ulichney's void-and-cluster method, 1993: Gaussian energy, sigma 1.5, on a torus).
//
// The sampler (sampler.h) uses it to give neighbouring pixels unlike first samples: the error of a
// frame of a few samples per pixel then sits at high spatial frequencies (fine, even grain
// instead of blotches), which the eye minds less and the filter (aov_filter.h) removes better.
// It is computed once, on first use, by plain arithmetic, so it is the same on every machine.

#include <array>
#include <cstdint>

namespace strata {

/// log2 of the tile's side.
constexpr uint32_t BLUE_NOISE_LOG2 = 6;
constexpr uint32_t BLUE_NOISE_SIZE = 1u << BLUE_NOISE_LOG2;
constexpr uint32_t BLUE_NOISE_PIXELS = BLUE_NOISE_SIZE * BLUE_NOISE_SIZE;

using BlueNoiseMask = std::array<uint16_t, BLUE_NOISE_PIXELS>;

/// The ranks, row-major: rank of pixel (x, y) at y * BLUE_NOISE_SIZE + x.
const BlueNoiseMask& blue_noise_mask();

/// The same made on demand (tests compare, measure and time it).
BlueNoiseMask make_blue_noise_mask();

}  // namespace strata
