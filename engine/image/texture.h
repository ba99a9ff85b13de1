#pragma once
// A decoded texture: linear RGB texels, 16 bits per channel (6 bytes a texel: the precision of
// an 8-bit sRGB image's darkest steps with room to spare, at half the memory of float), and its
// lookup with wrap modes and bilinear or nearest filtering.
//
// Texture coordinates follow glTF: (0, 0) is the top-left corner of the image, u grows to the
// right and v downward; texel (x, y) covers [x, x + 1) / width by [y, y + 1) / height. Filtering
// happens on linear values (the sRGB decode is done once, at decode time).

#include <cmath>
#include <cstdint>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/types.h"

namespace strata {

/// Bytes one decoded texel takes (what counts against the scene's texture budget).
constexpr uint64_t TEXTURE_BYTES_PER_TEXEL = 6;
/// Bytes a texel's alpha adds, for images whose alpha is not everywhere opaque.
constexpr uint64_t TEXTURE_BYTES_PER_ALPHA = 1;

struct TextureImage {
    uint32_t width = 0;
    uint32_t height = 0;
    /// Linear RGB, row-major from the top, 0..65535 meaning 0..1.
    std::vector<uint16_t> texels;
    /// Coverage, row-major from the top, 0..255 meaning 0..1; empty: opaque everywhere.
    std::vector<uint8_t> alpha;

    /// Decoded bytes (what the budget counts).
    uint64_t bytes() const {
        return uint64_t(width) * height * TEXTURE_BYTES_PER_TEXEL + alpha.size();
    }

    /// Texel (x, y), both inside the image, as linear RGB in [0, 1].
    Vec3 texel(uint32_t x, uint32_t y) const {
        const uint16_t* t = &texels[(std::size_t(y) * width + x) * 3];
        constexpr float SCALE = 1.0f / 65535.0f;
        return Vec3(float(t[0]) * SCALE, float(t[1]) * SCALE, float(t[2]) * SCALE);
    }

    /// The filtered linear colour at texture coordinate `uv` (finite).
    Vec3 sample(Vec2 uv, const TextureSampler& s) const {
        return filtered(uv, s, [&](uint32_t x, uint32_t y) { return texel(x, y); });
    }

    /// The filtered coverage at texture coordinate `uv` (finite): 1 for an opaque image.
    float sample_alpha(Vec2 uv, const TextureSampler& s) const {
        if (alpha.empty()) return 1.0f;
        return filtered(uv, s, [&](uint32_t x, uint32_t y) {
            return float(alpha[std::size_t(y) * width + x]) * (1.0f / 255.0f);
        });
    }

    /// Texel index `i` (any integer) wrapped into [0, n).
    static uint32_t wrap(int64_t i, uint32_t n, TextureWrap mode) {
        const int64_t size = n;
        switch (mode) {
            case TextureWrap::Clamp:
                return uint32_t(i < 0 ? 0 : (i >= size ? size - 1 : i));
            case TextureWrap::Mirror: {
                const int64_t period = 2 * size;
                int64_t m = i % period;
                if (m < 0) m += period;
                return uint32_t(m < size ? m : period - 1 - m);
            }
            default: {
                int64_t m = i % size;
                if (m < 0) m += size;
                return uint32_t(m);
            }
        }
    }

private:
    /// `fetch(x, y)` (a texel's value) filtered at texture coordinate `uv` as `s` says.
    template <class Fetch>
    auto filtered(Vec2 uv, const TextureSampler& s, Fetch&& fetch) const
        -> decltype(fetch(0u, 0u)) {
        // Far coordinates keep finite texel arithmetic (they only lose precision).
        uv = glm::clamp(uv, Vec2(-1e6f), Vec2(1e6f));
        const float fx = uv.x * float(width);
        const float fy = uv.y * float(height);
        if (s.filter == TextureFilter::Nearest)
            return fetch(wrap(floor_index(fx), width, s.wrap),
                         wrap(floor_index(fy), height, s.wrap));
        // Bilinear: texel centres sit at half-integers.
        const float gx = fx - 0.5f, gy = fy - 0.5f;
        const float x0f = std::floor(gx), y0f = std::floor(gy);
        const float tx = gx - x0f, ty = gy - y0f;
        const int64_t x0 = clamp_index(x0f), y0 = clamp_index(y0f);
        const uint32_t xa = wrap(x0, width, s.wrap), xb = wrap(x0 + 1, width, s.wrap);
        const uint32_t ya = wrap(y0, height, s.wrap), yb = wrap(y0 + 1, height, s.wrap);
        const auto top = fetch(xa, ya) * (1.0f - tx) + fetch(xb, ya) * tx;
        const auto bottom = fetch(xa, yb) * (1.0f - tx) + fetch(xb, yb) * tx;
        return top * (1.0f - ty) + bottom * ty;
    }

    /// A float texel coordinate as an integer index, kept where int64 arithmetic cannot overflow
    /// (uvs are finite but may be huge; the wrap makes any far index equivalent to a near one
    /// only approximately there, which is fine for coordinates beyond 2^40).
    static int64_t clamp_index(float f) {
        constexpr float LIMIT = 1099511627776.0f;  // 2^40
        return int64_t(f < -LIMIT ? -LIMIT : (f > LIMIT ? LIMIT : f));
    }
    static int64_t floor_index(float f) { return clamp_index(std::floor(f)); }
};

}  // namespace strata
