#include "engine/image/tonemap.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace strata {

namespace {

/// Bins of the lookup from [0, 1] to 8-bit sRGB codes. With 4096 bins the steepest part of the
/// curve (slope 12.92 * 255) moves less than one code per bin, so one correction step is exact.
constexpr int SRGB_BINS = 4096;

struct SrgbTables {
    /// boundary[k]: smallest linear value whose code is k + 1; boundary[255] is +inf.
    std::array<float, 256> boundary;
    /// code[i]: code of the bin's lower edge i / (SRGB_BINS - 1).
    std::array<uint8_t, SRGB_BINS> code;

    SrgbTables() {
        for (int k = 0; k < 255; ++k) {
            const double s = (k + 0.5) / 255.0;
            const double lin = s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4);
            boundary[k] = static_cast<float>(lin);
        }
        boundary[255] = std::numeric_limits<float>::infinity();
        for (int i = 0; i < SRGB_BINS; ++i) {
            const float v = float(i) / float(SRGB_BINS - 1);
            code[i] = static_cast<uint8_t>(std::upper_bound(boundary.begin(), boundary.end(), v) -
                                           boundary.begin());
        }
    }
};

const SrgbTables& srgb_tables() {
    static const SrgbTables tables;
    return tables;
}

uint8_t encode(const SrgbTables& t, float v) {
    v = std::clamp(v, 0.0f, 1.0f);  // NaN stays NaN here and fails both tests below
    if (!(v > 0.0f)) return 0;
    const int bin = static_cast<int>(v * float(SRGB_BINS - 1));
    const uint8_t c = t.code[bin];
    return static_cast<uint8_t>(c + (v >= t.boundary[c] ? 1 : 0));
}

float rrt_odt_fit(float v) {
    const float a = v * (v + 0.0245786f) - 0.000090537f;
    const float b = v * (0.983729f * v + 0.4329510f) + 0.238081f;
    return a / b;
}

/// Pixels tone mapped per block: the curve runs over structure-of-arrays lanes in loops the
/// compiler vectorises (the same arithmetic as aces_fitted), the table lookups after.
constexpr std::size_t BLOCK = 64;

float clamp01(float v, float hi) {
    v = v > 0.0f ? v : 0.0f;  // NaN becomes 0
    return v < hi ? v : hi;
}

void tonemap_block(const float* rgb, std::size_t n, float scale, const SrgbTables& t,
                   uint8_t* out) {
    alignas(64) float r[BLOCK], g[BLOCK], b[BLOCK];
    for (std::size_t k = 0; k < n; ++k) {
        // Clamped so +inf saturates to white; NaN ends up black.
        r[k] = clamp01(rgb[3 * k + 0] * scale, 65504.0f);
        g[k] = clamp01(rgb[3 * k + 1] * scale, 65504.0f);
        b[k] = clamp01(rgb[3 * k + 2] * scale, 65504.0f);
    }
    for (std::size_t k = 0; k < BLOCK; ++k) {
        const float ar = 0.59719f * r[k] + 0.35458f * g[k] + 0.04823f * b[k];
        const float ag = 0.07600f * r[k] + 0.90834f * g[k] + 0.01566f * b[k];
        const float ab = 0.02840f * r[k] + 0.13383f * g[k] + 0.83777f * b[k];
        const float fr = rrt_odt_fit(ar), fg = rrt_odt_fit(ag), fb = rrt_odt_fit(ab);
        r[k] = clamp01(1.60475f * fr - 0.53108f * fg - 0.07367f * fb, 1.0f);
        g[k] = clamp01(-0.10208f * fr + 1.10813f * fg - 0.00605f * fb, 1.0f);
        b[k] = clamp01(-0.00327f * fr - 0.07276f * fg + 1.07602f * fb, 1.0f);
    }
    for (std::size_t k = 0; k < n; ++k) {
        out[3 * k + 0] = encode(t, r[k]);
        out[3 * k + 1] = encode(t, g[k]);
        out[3 * k + 2] = encode(t, b[k]);
    }
}

}  // namespace

Vec3 aces_fitted(const Vec3& c) {
    // sRGB -> ACES AP1 (with the RRT's saturation tweak), then back; rows of Hill's matrices.
    const Vec3 a(0.59719f * c.x + 0.35458f * c.y + 0.04823f * c.z,
                 0.07600f * c.x + 0.90834f * c.y + 0.01566f * c.z,
                 0.02840f * c.x + 0.13383f * c.y + 0.83777f * c.z);
    const Vec3 f(rrt_odt_fit(a.x), rrt_odt_fit(a.y), rrt_odt_fit(a.z));
    const Vec3 o(1.60475f * f.x - 0.53108f * f.y - 0.07367f * f.z,
                 -0.10208f * f.x + 1.10813f * f.y - 0.00605f * f.z,
                 -0.00327f * f.x - 0.07276f * f.y + 1.07602f * f.z);
    return {clamp01(o.x, 1.0f), clamp01(o.y, 1.0f), clamp01(o.z, 1.0f)};
}

uint8_t linear_to_srgb8(float v) {
    return encode(srgb_tables(), v);
}

void tonemap_to_srgb8(const Vec3* linear, std::size_t count, float exposure_ev, uint8_t* rgb_out) {
    const float scale = std::exp2(exposure_ev);
    const SrgbTables& t = srgb_tables();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 16384),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t b = r.begin(); b < r.end(); b += BLOCK) {
                              const std::size_t n = std::min(BLOCK, r.end() - b);
                              tonemap_block(&linear[b].x, n, scale, t, rgb_out + 3 * b);
                          }
                      });
}

}  // namespace strata
