// Imported models against stored reference images, compared with a tolerance (as the demo's
// reference test does): Spot, the bunny and the multi-node 2CylinderEngine, each framed by a
// camera computed from its world bounds.
//
// Regenerate after an intended change of the renderer or the importers, then look at them:
//   STRATA_UPDATE_REFERENCE=1 ctest --test-dir build -R AssetReferenceImage
// A mismatch writes the frame it got to <name>_actual.png in the working directory.

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <gtest/gtest.h>

#include "engine/image/png.h"
#include "protocol/assets/asset_batch.h"
#include "tests/assets/asset_test_util.h"
#include "tests/engine/render_test_util.h"

namespace strata::assets::test {
namespace {

constexpr uint32_t WIDTH = 240, HEIGHT = 180, SPP = 8;
constexpr int PIXEL_TOLERANCE = 24;           ///< 8-bit steps on any channel
constexpr double MAX_DIFFERING_FRACTION = 0.01;
constexpr double MAX_MEAN_DIFFERENCE = 1.0;  ///< 8-bit steps over all channels

void write_file(const std::filesystem::path& path, const std::string& bytes) {
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
}

/// Imports `path` as `format`, frames it and compares the frame with data/<name>.png.
void check_reference(const std::string& path, AssetFormat format, const std::string& name) {
    const std::string bytes = read_file(path);
    if (bytes.empty()) GTEST_SKIP() << path << " missing";
    auto asset = import_asset(format, bytes_of(bytes), name, {});
    ASSERT_TRUE(asset.has_value()) << asset.error().describe();
    AssetBatch b = asset_to_batch(std::move(asset.value()), {name, true});
    auto engine = strata::test::engine_with(std::move(b.batch));
    const Bounds3 box = engine->read([](const Scene& s) { return s.world_bounds(); });
    ASSERT_FALSE(box.empty());
    const float size = glm::length(box.extent());
    SetCamera cam;
    cam.target = box.center();
    cam.eye = box.center() + glm::normalize(Vec3(0.6f, 0.45f, 1.0f)) * (1.4f * size);
    cam.fov_y_deg = 40.0f;
    EditBatch view;
    view.edits.emplace_back(cam);
    ASSERT_TRUE(engine->apply(std::move(view)).has_value());
    const EncodedFrame image = strata::test::render_ok(
        *engine, strata::test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png));
    ASSERT_FALSE(image.bytes.empty());

    const std::filesystem::path reference =
        std::filesystem::path(STRATA_ASSET_TEST_DATA_DIR) / (name + ".png");
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
    if (fraction > MAX_DIFFERING_FRACTION || mean > MAX_MEAN_DIFFERENCE)
        write_file(name + "_actual.png", image.bytes);
    EXPECT_LE(fraction, MAX_DIFFERING_FRACTION) << "wrote " << name << "_actual.png";
    EXPECT_LE(mean, MAX_MEAN_DIFFERENCE) << "wrote " << name << "_actual.png";
}

TEST(AssetReferenceImage, SpotMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_MODELS_DIR) + "/spot.obj", AssetFormat::Obj, "spot");
}

TEST(AssetReferenceImage, TheBunnyMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_MODELS_DIR) + "/stanford-bunny.obj", AssetFormat::Obj,
                    "bunny");
}

TEST(AssetReferenceImage, TwoCylinderEngineMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_ASSIMP_MODELS_DIR) +
                        "/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
                    AssetFormat::Glb, "engine");
}

}  // namespace
}  // namespace strata::assets::test
