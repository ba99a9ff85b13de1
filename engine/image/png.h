#pragma once
// PNG encoding in memory with libpng, and the linear-to-sRGB conversion for 8-bit frames.

#include <cstdint>
#include <vector>

#include "engine/core/math.h"
#include "engine/core/result.h"

namespace strata {

/// Encodes 8-bit pixels (`channels` = 3 for RGB or 4 for RGBA, row-major from the top) as PNG.
/// `zlib_level` 0..9: low levels with the cheap "sub" filter keep a 1080p frame in tens of ms.
Result<std::vector<uint8_t>> encode_png(const uint8_t* pixels, uint32_t width, uint32_t height,
                                        int channels, int zlib_level = 2);

/// Linear RGB to 8-bit sRGB, clamped; `exposure` scales before conversion.
void linear_to_srgb8(const Vec3* linear, std::size_t count, float exposure, uint8_t* rgb_out);

/// Decodes a PNG (for tests and tools): RGB or RGBA 8-bit.
struct DecodedImage {
    uint32_t width = 0;
    uint32_t height = 0;
    int channels = 0;
    std::vector<uint8_t> pixels;
};
Result<DecodedImage> decode_png(const uint8_t* data, std::size_t size);

}  // namespace strata
