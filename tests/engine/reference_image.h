#pragma once
// Comparing a rendered PNG with a stored reference image under a tolerance (Embree and libm pick
// different code paths on different CPUs, so the bytes may differ slightly across machines), or
// rewriting the reference under STRATA_UPDATE_REFERENCE=1. Used by the engine's and the asset
// importers' reference-image tests.

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "engine/image/png.h"
#include "engine/render/frame.h"

namespace strata::test {

/// A pixel differs when one of its channels is off by more than this many 8-bit steps.
constexpr int REFERENCE_PIXEL_TOLERANCE = 24;
/// At most this fraction of pixels may differ.
constexpr double REFERENCE_MAX_DIFFERING_FRACTION = 0.01;
/// Largest mean absolute difference over all channels, in 8-bit steps.
constexpr double REFERENCE_MAX_MEAN_DIFFERENCE = 1.0;

inline void write_reference_file(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    ASSERT_TRUE(f.good()) << "cannot write " << path;
}

/// Compares `image` (a width x height PNG) with `dir`/`name`.png under the tolerances above, or
/// rewrites the stored one under STRATA_UPDATE_REFERENCE=1. A mismatch writes the frame it got to
/// <name>_actual.png in the working directory.
inline void expect_matches_reference(const std::filesystem::path& dir, const std::string& name,
                                     const EncodedFrame& image, uint32_t width, uint32_t height) {
    ASSERT_FALSE(image.bytes.empty());
    const std::filesystem::path reference = dir / (name + ".png");
    const std::string actual_name = name + "_actual.png";

    const char* update = std::getenv("STRATA_UPDATE_REFERENCE");
    if (update && std::string(update) == "1") {
        write_reference_file(reference, image.bytes);
        GTEST_SKIP() << "rewrote " << reference;
    }

    std::ifstream f(reference, std::ios::binary);
    ASSERT_TRUE(f.good()) << "missing " << reference
                          << "; regenerate with STRATA_UPDATE_REFERENCE=1";
    const std::vector<uint8_t> stored{std::istreambuf_iterator<char>(f), {}};
    auto expected = decode_png(stored.data(), stored.size());
    auto actual = decode_png(image.bytes);
    ASSERT_TRUE(expected.has_value()) << expected.error().describe();
    ASSERT_TRUE(actual.has_value());
    ASSERT_EQ(expected.value().width, width);
    ASSERT_EQ(expected.value().height, height);
    ASSERT_EQ(expected.value().channels, actual.value().channels);

    const auto& e = expected.value().pixels;
    const auto& a = actual.value().pixels;
    const int channels = actual.value().channels;
    std::size_t differing = 0;
    double total = 0.0;
    for (std::size_t p = 0; p < std::size_t(width) * height; ++p) {
        int worst = 0;
        for (int c = 0; c < channels; ++c) {
            const int d = std::abs(int(e[p * channels + c]) - int(a[p * channels + c]));
            worst = std::max(worst, d);
            total += d;
        }
        differing += worst > REFERENCE_PIXEL_TOLERANCE;
    }
    const double fraction = double(differing) / (double(width) * height);
    const double mean = total / (double(width) * height * channels);
    const bool ok =
        fraction <= REFERENCE_MAX_DIFFERING_FRACTION && mean <= REFERENCE_MAX_MEAN_DIFFERENCE;
    if (!ok) write_reference_file(actual_name, image.bytes);
    EXPECT_LE(fraction, REFERENCE_MAX_DIFFERING_FRACTION) << "wrote " << actual_name;
    EXPECT_LE(mean, REFERENCE_MAX_MEAN_DIFFERENCE) << "wrote " << actual_name;
}

}  // namespace strata::test
