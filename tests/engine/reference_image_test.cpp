// The demo scene against a stored reference image, compared with a tolerance: Embree and libm
// pick different code paths on different CPUs, so the bytes may differ slightly across machines
// (on one machine they never do, see render_determinism_test).
//
// Regenerate after an intended change of the renderer or of the demo scene, then look at it:
//   STRATA_UPDATE_REFERENCE=1 ctest --test-dir build -R ReferenceImage
// On a mismatch the test writes the frame it got to demo_reference_actual.png in its working
// directory (build/tests/engine under ctest).

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "engine/image/png.h"
#include "engine/scene/demo_scene.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

constexpr uint32_t WIDTH = 320, HEIGHT = 180, SPP = 16;
/// A pixel differs when one of its channels is off by more than this many 8-bit steps.
constexpr int PIXEL_TOLERANCE = 24;
/// At most this fraction of pixels may differ.
constexpr double MAX_DIFFERING_FRACTION = 0.01;
/// Largest mean absolute difference over all channels, in 8-bit steps.
constexpr double MAX_MEAN_DIFFERENCE = 1.0;

const std::filesystem::path REFERENCE =
    std::filesystem::path(STRATA_TEST_DATA_DIR) / "demo_reference.png";

void write_file(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    ASSERT_TRUE(f.good()) << "cannot write " << path;
}

TEST(ReferenceImage, DemoSceneMatchesTheStoredFrame) {
    auto engine = test::engine_with(make_demo_scene());
    const EncodedFrame image =
        test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png));
    ASSERT_FALSE(image.bytes.empty());

    const char* update = std::getenv("STRATA_UPDATE_REFERENCE");
    if (update && std::string(update) == "1") {
        write_file(REFERENCE, image.bytes);
        GTEST_SKIP() << "rewrote " << REFERENCE;
    }

    std::ifstream f(REFERENCE, std::ios::binary);
    ASSERT_TRUE(f.good()) << "missing " << REFERENCE << "; see the top of this file";
    const std::vector<uint8_t> stored{std::istreambuf_iterator<char>(f), {}};
    auto expected = decode_png(stored.data(), stored.size());
    auto actual = decode_png(image.bytes);
    ASSERT_TRUE(expected.has_value()) << expected.error().describe();
    ASSERT_TRUE(actual.has_value());
    ASSERT_EQ(expected.value().width, WIDTH);
    ASSERT_EQ(expected.value().height, HEIGHT);
    ASSERT_EQ(expected.value().channels, actual.value().channels);

    const auto& e = expected.value().pixels;
    const auto& a = actual.value().pixels;
    const int channels = actual.value().channels;
    std::size_t differing = 0;
    double total = 0.0;
    for (std::size_t p = 0; p < std::size_t(WIDTH) * HEIGHT; ++p) {
        int worst = 0;
        for (int c = 0; c < channels; ++c) {
            const int d = std::abs(int(e[p * channels + c]) - int(a[p * channels + c]));
            worst = std::max(worst, d);
            total += d;
        }
        differing += worst > PIXEL_TOLERANCE;
    }
    const double fraction = double(differing) / (double(WIDTH) * HEIGHT);
    const double mean = total / (double(WIDTH) * HEIGHT * channels);
    const bool ok = fraction <= MAX_DIFFERING_FRACTION && mean <= MAX_MEAN_DIFFERENCE;
    if (!ok) write_file("demo_reference_actual.png", image.bytes);
    EXPECT_LE(fraction, MAX_DIFFERING_FRACTION) << "wrote demo_reference_actual.png";
    EXPECT_LE(mean, MAX_MEAN_DIFFERENCE) << "wrote demo_reference_actual.png";
}

}  // namespace
}  // namespace strata
