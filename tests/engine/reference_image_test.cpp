// Frames against stored reference images (the demo scene; a coarse sphere with and without
// shading normals), compared with a tolerance: Embree and libm
// pick different code paths on different CPUs, so the bytes may differ slightly across machines
// (on one machine they never do, see render_determinism_test).
//
// Regenerate after an intended change of the renderer or of the demo scene, then look at it:
//   STRATA_UPDATE_REFERENCE=1 ctest --test-dir build -R ReferenceImage
// On a mismatch the test writes the frame it got to <name>_actual.png in its working
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

void write_file(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
    ASSERT_TRUE(f.good()) << "cannot write " << path;
}

/// Compares `image` (a WIDTH x HEIGHT PNG) with the stored `name` under the tolerances above, or
/// rewrites the stored one under STRATA_UPDATE_REFERENCE=1.
void expect_matches_reference(const std::string& name, const EncodedFrame& image,
                              uint32_t width = WIDTH, uint32_t height = HEIGHT) {
    ASSERT_FALSE(image.bytes.empty());
    const std::filesystem::path reference =
        std::filesystem::path(STRATA_TEST_DATA_DIR) / (name + ".png");
    const std::string actual_name = name + "_actual.png";

    const char* update = std::getenv("STRATA_UPDATE_REFERENCE");
    if (update && std::string(update) == "1") {
        write_file(reference, image.bytes);
        GTEST_SKIP() << "rewrote " << reference;
    }

    std::ifstream f(reference, std::ios::binary);
    ASSERT_TRUE(f.good()) << "missing " << reference << "; see the top of this file";
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
        differing += worst > PIXEL_TOLERANCE;
    }
    const double fraction = double(differing) / (double(width) * height);
    const double mean = total / (double(width) * height * channels);
    const bool ok = fraction <= MAX_DIFFERING_FRACTION && mean <= MAX_MEAN_DIFFERENCE;
    if (!ok) write_file(actual_name, image.bytes);
    EXPECT_LE(fraction, MAX_DIFFERING_FRACTION) << "wrote " << actual_name;
    EXPECT_LE(mean, MAX_MEAN_DIFFERENCE) << "wrote " << actual_name;
}

TEST(ReferenceImage, DemoSceneMatchesTheStoredFrame) {
    auto engine = test::engine_with(make_demo_scene());
    expect_matches_reference(
        "demo_reference",
        test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png)));
}

/// A 12-segment sphere on a floor, lit by the default sun and sky; with the sphere's own
/// normals when `smooth`.
EncodedFrame sphere_frame(bool smooth) {
    auto engine = test::make_engine();
    AddMesh ball = test::mesh_edit("ball", make_sphere(1.0f, 12));
    if (smooth) {
        for (const Vec3& p : ball.positions) ball.normals.push_back(glm::normalize(p));
    }
    AddMaterial clay{"clay", Material{Vec3(0.8f, 0.45f, 0.3f), 0.6f, 0.0f, Vec3(0.0f)}};
    ball.material = "clay";
    test::apply_ok(*engine, clay, ball, test::instance_edit("ball-1", "ball", {0, 1, 0}),
                   test::mesh_edit("floor", make_plane(Vec3(8.0f), 1, 1)),
                   test::instance_edit("floor-1", "floor"),
                   SetCamera{Vec3(0, 2, 4.5f), Vec3(0, 0.8f, 0), Vec3(0, 1, 0), 40.0f});
    return test::render_ok(*engine, test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png));
}

TEST(ReferenceImage, SmoothAndFacetedSpheresMatchTheirStoredFrames) {
    const EncodedFrame smooth = sphere_frame(true);
    const EncodedFrame faceted = sphere_frame(false);
    EXPECT_NE(smooth.bytes, faceted.bytes);
    expect_matches_reference("sphere_smooth_reference", smooth);
    expect_matches_reference("sphere_faceted_reference", faceted);
}

}  // namespace
}  // namespace strata
