#pragma once
// JPEG encoding in memory with libjpeg-turbo (TurboJPEG API), for the live viewer's stream: a
// 720p frame costs a few milliseconds where PNG costs tens (tests/bench/NOTES.md).

#include <cstdint>
#include <string>

#include "engine/core/math.h"
#include "engine/core/result.h"

namespace strata {

/// Encodes packed 8-bit RGB (row-major from the top) as a baseline JPEG with 4:2:0 chroma
/// subsampling; `quality` in 1..100.
Result<std::string> encode_jpeg(const uint8_t* rgb, uint32_t width, uint32_t height, int quality);

/// Exposure, tone mapping and sRGB encoding (tonemap.h) of linear colors, then encode_jpeg.
Result<std::string> encode_jpeg_linear(const Vec3* linear, uint32_t width, uint32_t height,
                                       float exposure_ev, int quality);

}  // namespace strata
