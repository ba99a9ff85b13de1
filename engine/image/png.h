#pragma once
// PNG encoding and decoding in memory with libpng (tone mapping lives in tonemap.h).

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"

namespace strata {

/// Encodes 8-bit pixels (`channels` = 3 for RGB or 4 for RGBA, row-major from the top) as PNG.
/// Speed over size: the "sub" filter and zlib's run-length strategy at `zlib_level` (0..9) keep
/// a 1080p frame in tens of milliseconds (tests/bench/NOTES.md).
Result<std::string> encode_png(const uint8_t* pixels, uint32_t width, uint32_t height, int channels,
                               int zlib_level = 1);

/// Decodes a PNG (for tests and tools): RGB or RGBA 8-bit.
struct DecodedImage {
    uint32_t width = 0;
    uint32_t height = 0;
    int channels = 0;
    std::vector<uint8_t> pixels;
};
Result<DecodedImage> decode_png(const uint8_t* data, std::size_t size);
/// The same over encoded bytes held in a string (what encode_png returns).
inline Result<DecodedImage> decode_png(std::string_view bytes) {
    return decode_png(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

}  // namespace strata
