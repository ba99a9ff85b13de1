#pragma once
// Small PNG and JPEG files made in memory for the texture tests.

#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <turbojpeg.h>

#include "engine/image/png.h"

namespace strata::test {

/// An 8-bit RGB PNG of `w` x `h` pixels (row-major from the top, 3 bytes a pixel).
inline std::string png_bytes(uint32_t w, uint32_t h, const std::vector<uint8_t>& rgb) {
    auto png = encode_png(rgb.data(), w, h, 3);
    EXPECT_TRUE(png.has_value());
    return png.has_value() ? png.value() : std::string();
}

/// A 2x2 PNG: red, green / blue, white.
inline std::string four_colour_png() {
    return png_bytes(2, 2, {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255});
}

/// A baseline JPEG of `w` x `h` pixels of one colour, at the best quality (4:4:4).
inline std::string jpeg_bytes(uint32_t w, uint32_t h, uint8_t r, uint8_t g, uint8_t b) {
    std::vector<uint8_t> rgb(std::size_t(w) * h * 3);
    for (std::size_t i = 0; i < rgb.size(); i += 3) {
        rgb[i] = r;
        rgb[i + 1] = g;
        rgb[i + 2] = b;
    }
    tjhandle tj = tjInitCompress();
    unsigned char* out = nullptr;
    unsigned long size = 0;
    const int rc =
        tjCompress2(tj, rgb.data(), int(w), 0, int(h), TJPF_RGB, &out, &size, TJSAMP_444, 100, 0);
    EXPECT_EQ(rc, 0) << tjGetErrorStr2(tj);
    std::string bytes(reinterpret_cast<const char*>(out), size);
    tjFree(out);
    tjDestroy(tj);
    return bytes;
}

/// CRC-32 (ISO-HDLC) as PNG chunks use it.
inline uint32_t png_crc(const std::string& bytes, std::size_t begin, std::size_t end) {
    uint32_t c = 0xFFFFFFFFu;
    for (std::size_t i = begin; i < end; ++i) {
        c ^= uint8_t(bytes[i]);
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return c ^ 0xFFFFFFFFu;
}

/// A valid PNG whose header claims `w` x `h` (with a correct CRC), over a 1x1 image's data: what
/// a decompression bomb looks like before its pixels are read.
inline std::string png_claiming(uint32_t w, uint32_t h) {
    std::string png = png_bytes(1, 1, {10, 20, 30});
    // Signature (8), then the IHDR chunk: length (4), "IHDR" (4), width (4), height (4), ...
    auto put_be = [&](std::size_t at, uint32_t v) {
        for (int k = 0; k < 4; ++k) png[at + k] = char((v >> (24 - 8 * k)) & 0xFF);
    };
    put_be(16, w);
    put_be(20, h);
    put_be(29, png_crc(png, 12, 29));  // over type and data (13 bytes)
    return png;
}

}  // namespace strata::test
