// The viewer's selection highlight (engine/image/highlight.h): exactly the pixels whose
// instance_id is the selected slot change, edges take the highlight colour, the rest keep their
// bytes; on a real render of the demo scene too.

#include <gtest/gtest.h>

#include "engine/image/highlight.h"
#include "engine/image/tonemap.h"
#include "engine/scene/demo_scene.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

uint8_t blended(uint8_t v, int c) {
    return uint8_t((v * (256u - HIGHLIGHT_BLEND) + HIGHLIGHT_RGB[c] * HIGHLIGHT_BLEND + 128u) >> 8);
}

TEST(Highlight, OnlyTheSlotsPixelsChangeItsEdgeTakesTheColourItsInsideIsBlended) {
    // 6x5 ids: slot 3 covers a 4x3 block (x 1..4, y 1..3); around it slot 1 and misses.
    const uint32_t W = 6, H = 5;
    std::vector<uint32_t> ids(W * H, 1);
    for (uint32_t x = 0; x < W; ++x) ids[x] = MISS_ID;
    for (uint32_t y = 1; y <= 3; ++y)
        for (uint32_t x = 1; x <= 4; ++x) ids[y * W + x] = 3;
    std::vector<uint8_t> rgb(W * H * 3);
    for (std::size_t i = 0; i < rgb.size(); ++i) rgb[i] = uint8_t(40 + i % 7);
    const std::vector<uint8_t> before = rgb;

    EXPECT_EQ(highlight_instance(rgb.data(), ids.data(), W, H, 3), 12u);
    for (uint32_t y = 0; y < H; ++y) {
        for (uint32_t x = 0; x < W; ++x) {
            const std::size_t p = y * W + x;
            for (int c = 0; c < 3; ++c) {
                const uint8_t was = before[3 * p + c], now = rgb[3 * p + c];
                if (ids[p] != 3) {
                    EXPECT_EQ(now, was) << "pixel " << x << "," << y << " is not the instance's";
                } else if (x == 1 || x == 4 || y == 1 || y == 3) {
                    EXPECT_EQ(now, HIGHLIGHT_RGB[c]) << "edge pixel " << x << "," << y;
                } else {
                    EXPECT_EQ(now, blended(was, c)) << "inner pixel " << x << "," << y;
                    EXPECT_NE(now, was);
                }
            }
        }
    }
}

TEST(Highlight, AnInstanceAtTheFramesBorderIsOutlinedThereAndMissIdTintsNothing) {
    const uint32_t W = 3, H = 3;
    std::vector<uint32_t> ids(W * H, 7);
    ids[4] = MISS_ID;  // the centre shows nothing
    std::vector<uint8_t> rgb(W * H * 3, 10);
    EXPECT_EQ(highlight_instance(rgb.data(), ids.data(), W, H, MISS_ID), 0u);
    EXPECT_EQ(rgb, std::vector<uint8_t>(W * H * 3, 10));
    EXPECT_EQ(highlight_instance(rgb.data(), ids.data(), W, H, 9), 0u);
    EXPECT_EQ(highlight_instance(rgb.data(), ids.data(), W, H, 7), 8u);
    for (uint32_t p = 0; p < W * H; ++p)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(rgb[3 * p + c], p == 4 ? 10 : HIGHLIGHT_RGB[c]) << "pixel " << p;
}

TEST(Highlight, OnARenderOfTheDemoTheChangedPixelsAreExactlyTheBallsPixels) {
    auto engine = test::engine_with(make_demo_scene());
    const uint32_t ball =
        engine->read([](const Scene& s) { return s.find_instance("ball").index; });
    const Frame frame = test::render_frame_ok(*engine, test::request(96, 54, 1, {Aov::InstanceId}));
    ASSERT_EQ(frame.buffers.instance_id.size(), 96u * 54u);
    std::vector<uint8_t> rgb(96 * 54 * 3);
    tonemap_to_srgb8(frame.buffers.color.data(), 96 * 54, 0.0f, rgb.data());
    std::vector<uint8_t> tinted = rgb;
    const std::size_t n =
        highlight_instance(tinted.data(), frame.buffers.instance_id.data(), 96, 54, ball);
    std::size_t ball_pixels = 0, changed = 0;
    for (std::size_t p = 0; p < 96 * 54; ++p) {
        const bool is_ball = frame.buffers.instance_id[p] == ball;
        const bool differs = tinted[3 * p] != rgb[3 * p] || tinted[3 * p + 1] != rgb[3 * p + 1] ||
                             tinted[3 * p + 2] != rgb[3 * p + 2];
        ball_pixels += is_ball;
        changed += differs;
        if (!is_ball) {
            EXPECT_FALSE(differs) << "pixel " << p << " is not the ball's";
        }
    }
    EXPECT_GT(ball_pixels, 50u) << "the ball should fill part of the frame";
    EXPECT_EQ(n, ball_pixels);
    // Nearly all ball pixels visibly change (one already of the highlight colour would not).
    EXPECT_GE(changed, ball_pixels * 95 / 100);
}

}  // namespace
}  // namespace strata
