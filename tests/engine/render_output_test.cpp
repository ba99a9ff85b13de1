// Frame encodings: EXR channels (names, types, sizes, values, compression) read back with
// OpenEXR from memory, PNG decoding, the request checks that tie AOVs to formats, and the tone
// curve.

#include <cmath>
#include <limits>
#include <set>
#include <string>

#include <gtest/gtest.h>

#include "engine/image/png.h"
#include "engine/image/tonemap.h"
#include "engine/render/frame_encode.h"
#include "engine/scene/demo_scene.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

using test::decode_exr_ok;
using test::render_frame_ok;
using test::render_ok;
using test::request;

const std::vector<Aov> ALL_AOVS = {Aov::Color,       Aov::Albedo,   Aov::Normal,
                                   Aov::Depth,       Aov::Position, Aov::InstanceId,
                                   Aov::PrimitiveId, Aov::MeshId,   Aov::UserId};

std::set<std::string> names(const DecodedExr& exr) {
    std::set<std::string> out;
    for (const auto& c : exr.channels) out.insert(c.name);
    return out;
}

class RenderOutput : public ::testing::TestWithParam<ExrCompression> {
protected:
    void SetUp() override { engine = test::engine_with(make_demo_scene()); }
    std::unique_ptr<Engine> engine;
};

TEST_P(RenderOutput, ExrCarriesEveryAovWithOpenExrNames) {
    RenderRequest r = request(67, 39, 2, ALL_AOVS);
    r.compression = GetParam();
    const EncodedFrame image = render_ok(*engine, r);
    EXPECT_EQ(image.content_type, "image/x-exr");
    const Frame frame = render_frame_ok(*engine, r);  // same inputs: same pixels
    const DecodedExr exr = decode_exr_ok(image.bytes);

    ASSERT_EQ(exr.width, 67u);
    ASSERT_EQ(exr.height, 39u);
    EXPECT_EQ(exr.compression, GetParam());
    const std::set<std::string> expected = {
        "R",   "G", "B",   "A",   "albedo.R", "albedo.G",    "albedo.B",     "N.X",     "N.Y",
        "N.Z", "Z", "P.X", "P.Y", "P.Z",      "instance_id", "primitive_id", "mesh_id", "user_id"};
    EXPECT_EQ(names(exr), expected);

    const std::size_t n = 67u * 39u;
    for (const DecodedExrChannel& c : exr.channels) {
        const bool is_id = c.name.find("_id") != std::string::npos;
        const bool is_float = c.name == "Z" || c.name.starts_with("P.");
        EXPECT_EQ(c.type, is_id      ? ExrPixel::Uint
                          : is_float ? ExrPixel::Float
                                     : ExrPixel::Half)
            << c.name;
        EXPECT_EQ(is_id ? c.u32.size() : c.f32.size(), n) << c.name;
    }

    // Values: floats and ids exact, halves within half precision.
    const FrameBuffers& b = frame.buffers;
    std::size_t hits = 0;
    for (std::size_t i = 0; i < n; ++i) {
        ASSERT_EQ(exr.find("Z")->f32[i], b.depth[i]);
        ASSERT_EQ(exr.find("P.Y")->f32[i], b.position[i].y);
        ASSERT_EQ(exr.find("instance_id")->u32[i], b.instance_id[i]);
        ASSERT_EQ(exr.find("primitive_id")->u32[i], b.primitive_id[i]);
        ASSERT_EQ(exr.find("mesh_id")->u32[i], b.mesh_id[i]);
        ASSERT_EQ(exr.find("user_id")->u32[i], b.user_id[i]);
        ASSERT_EQ(exr.find("A")->f32[i], 1.0f);
        ASSERT_NEAR(exr.find("G")->f32[i], b.color[i].y, 1e-3f + 1e-3f * b.color[i].y);
        ASSERT_NEAR(exr.find("N.Z")->f32[i], b.normal[i].z, 1e-3f);
        ASSERT_NEAR(exr.find("albedo.R")->f32[i], b.albedo[i].x, 1e-3f);
        hits += b.instance_id[i] != MISS_ID;
    }
    EXPECT_GT(hits, n / 2) << "the demo camera sees mostly geometry";
    EXPECT_LT(hits, n) << "and some sky";
}

INSTANTIATE_TEST_SUITE_P(Compressions, RenderOutput,
                         ::testing::Values(ExrCompression::None, ExrCompression::Zip,
                                           ExrCompression::Piz),
                         [](const auto& p) { return std::string(exr_compression_name(p.param)); });

TEST(RenderOutputBasics, ExrWithoutAovsIsRgba) {
    auto engine = test::engine_with(make_demo_scene());
    const DecodedExr exr = decode_exr_ok(render_ok(*engine, request(20, 10, 1)).bytes);
    EXPECT_EQ(names(exr), (std::set<std::string>{"R", "G", "B", "A"}));
    EXPECT_EQ(exr.compression, ExrCompression::Zip) << "zip is the default";
}

TEST(RenderOutputBasics, CompressionShrinksTheFile) {
    auto engine = test::engine_with(make_demo_scene());
    RenderRequest r = request(64, 36, 1, {Aov::Depth, Aov::InstanceId});
    r.compression = ExrCompression::None;
    const std::size_t raw = render_ok(*engine, r).bytes.size();
    r.compression = ExrCompression::Zip;
    EXPECT_LT(render_ok(*engine, r).bytes.size(), raw);
    // Uncompressed size is at least the pixel data: 4 halves + float + uint per pixel.
    EXPECT_GT(raw, 64u * 36u * (4 * 2 + 4 + 4));
}

TEST(RenderOutputBasics, PngDecodesToTheRequestedSize) {
    auto engine = test::engine_with(make_demo_scene());
    const EncodedFrame image =
        render_ok(*engine, request(123, 45, 1, {Aov::Color}, ImageFormat::Png));
    EXPECT_EQ(image.content_type, "image/png");
    auto decoded = decode_png(image.bytes);
    ASSERT_TRUE(decoded.has_value()) << decoded.error().describe();
    EXPECT_EQ(decoded.value().width, 123u);
    EXPECT_EQ(decoded.value().height, 45u);
    EXPECT_EQ(decoded.value().channels, 3);
}

TEST(RenderOutputBasics, PngIsTheToneMappedBeauty) {
    auto engine = test::engine_with(make_demo_scene());
    RenderRequest r = request(40, 24, 2, {}, ImageFormat::Png);
    r.exposure = -0.5f;
    const Frame frame = render_frame_ok(*engine, r);
    const EncodedFrame image = render_ok(*engine, r);
    auto decoded = decode_png(image.bytes);
    ASSERT_TRUE(decoded.has_value());
    std::vector<uint8_t> expected(frame.buffers.pixel_count() * 3);
    tonemap_to_srgb8(frame.buffers.color.data(), frame.buffers.pixel_count(), -0.5f,
                     expected.data());
    EXPECT_EQ(decoded.value().pixels, expected);

    // Exposure is in stops: +1 EV equals doubling the linear image.
    r.exposure = 1.0f;
    std::vector<Vec3> doubled = frame.buffers.color;
    for (Vec3& c : doubled) c *= 2.0f;
    std::vector<uint8_t> a(expected.size()), b(expected.size());
    tonemap_to_srgb8(frame.buffers.color.data(), frame.buffers.pixel_count(), 1.0f, a.data());
    tonemap_to_srgb8(doubled.data(), doubled.size(), 0.0f, b.data());
    EXPECT_EQ(a, b);
    EXPECT_NE(a, expected);
}

TEST(RenderOutputBasics, AovsOtherThanColorNeedExr) {
    auto engine = test::engine_with(make_demo_scene());
    auto r = engine->render(request(8, 8, 1, {Aov::Color, Aov::Depth}, ImageFormat::Png));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::InvalidArgument);
    EXPECT_EQ(r.error().field, "aovs/1");
    EXPECT_TRUE(engine->render(request(8, 8, 1, {Aov::Color}, ImageFormat::Png)).has_value());
}

TEST(RenderOutputBasics, DecodeRefusesGarbage) {
    const std::vector<uint8_t> junk = {'v', '/', '1', 1, 2, 3, 4, 5, 6, 7, 8, 9};
    EXPECT_FALSE(decode_exr(junk.data(), junk.size()).has_value());
    auto engine = test::engine_with(make_demo_scene());
    std::string truncated = render_ok(*engine, request(16, 16, 1)).bytes;
    truncated.resize(truncated.size() / 2);
    EXPECT_FALSE(decode_exr(truncated).has_value());
}

TEST(ToneMap, Srgb8MatchesTheTransferFunctionExactly) {
    for (int i = 0; i <= 200000; ++i) {
        const float v = float(i) / 200000.0f;
        const double x = double(v);
        const double s = x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1.0 / 2.4) - 0.055;
        const double exact = s * 255.0;
        const int got = linear_to_srgb8(v);
        // Exact except within float rounding of a code boundary.
        if (std::abs(exact - std::floor(exact) - 0.5) > 1e-4) {
            ASSERT_EQ(got, int(std::lround(exact))) << "v = " << v;
        }
    }
    EXPECT_EQ(linear_to_srgb8(-1.0f), 0);
    EXPECT_EQ(linear_to_srgb8(2.0f), 255);
    EXPECT_EQ(linear_to_srgb8(std::numeric_limits<float>::quiet_NaN()), 0);
}

TEST(ToneMap, AcesCurveIsMonotonicAndSaturates) {
    float previous = -1.0f;
    for (float x = 0.0f; x < 64.0f; x += 0.01f) {
        const float y = aces_fitted(Vec3(x)).y;
        ASSERT_GE(y, previous) << x;
        previous = y;
    }
    EXPECT_EQ(aces_fitted(Vec3(0.0f)), Vec3(0.0f));
    EXPECT_GT(aces_fitted(Vec3(64.0f)).x, 0.99f);
    EXPECT_NEAR(aces_fitted(Vec3(0.18f)).y, 0.105f, 0.01f) << "mid grey to about 10%, as in ACES";
    EXPECT_NEAR(aces_fitted(Vec3(1.0f)).y, 0.62f, 0.01f);
    uint8_t rgb[3];
    const Vec3 inf(std::numeric_limits<float>::infinity());
    tonemap_to_srgb8(&inf, 1, 0.0f, rgb);
    EXPECT_EQ(rgb[0], 255) << "+inf saturates";
}

}  // namespace
}  // namespace strata
