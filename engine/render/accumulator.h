#pragma once
// Progressive refinement: per-pixel running sums that successive launches add samples to.
//
// A launch with `accumulate` continues the previous result only when its key matches: the same
// scene version (any edit, including a lighting or material edit, bumps it), the same effective
// camera (the request's override, else the scene camera) and the same width and height. Anything
// else - exposure, format, compression, the AOV list - is applied after the sums and does not
// restart it (albedo and normal sums are always kept, so asking for them later costs nothing).
// A mismatch restarts from sample 0. Renders without `accumulate` neither read nor change the
// state. The engine keeps one state, so interleaved accumulating clients restart each other.
//
// Sample i of a pixel is the same whichever launch traces it, and sums are added in sample order,
// so k + k accumulated samples give exactly the bytes of one launch of 2k samples.

#include <cstdint>
#include <optional>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/types.h"

namespace strata {

/// Most samples per pixel one accumulation gathers; launches beyond it add nothing.
constexpr uint32_t MAX_ACCUMULATED_SAMPLES = 1u << 16;
/// Largest frame that can be accumulated (the sums take 40 bytes per pixel).
constexpr uint64_t MAX_ACCUMULATE_PIXELS = 16ull * 1024 * 1024;

/// What must match for a launch to continue the previous accumulation.
struct AccumulationKey {
    uint64_t version = 0;
    Camera camera;
    uint32_t width = 0;
    uint32_t height = 0;
    Timeline clock;  ///< the time the animated instances show

    friend bool operator==(const AccumulationKey&, const AccumulationKey&) = default;
};

/// Running sums of one pixel's samples.
struct PixelSums {
    Vec3 color{0.0f};
    Vec3 albedo{0.0f};
    Vec3 normal{0.0f};
    /// Sum of the squared luminance of the colour samples: with `color`, the pixel's sample
    /// variance, which the filter (aov_filter.h) uses as its noise level.
    float luminance2 = 0.0f;
};

/// Samples a launch should trace: [first, first + count).
struct SampleRange {
    uint32_t first = 0;
    uint32_t count = 0;
};

class Accumulator {
public:
    /// Starts a launch that wants `spp` more samples under `key`: keeps the sums when the key
    /// matches, else clears them. Returns the samples to trace (fewer once the cap is reached).
    SampleRange begin(const AccumulationKey& key, uint32_t spp);
    /// Records that the launch begun last traced its samples into sums().
    void finish(const SampleRange& range);
    /// Drops the state (after a failed launch, the sums are no longer trustworthy).
    void reset();

    /// Per-pixel sums, row-major; valid between begin() and finish().
    PixelSums* sums() { return m_sums.data(); }
    /// Samples per pixel the sums hold.
    uint32_t samples() const { return m_samples; }

private:
    std::optional<AccumulationKey> m_key;
    uint32_t m_samples = 0;
    std::vector<PixelSums> m_sums;
};

}  // namespace strata
