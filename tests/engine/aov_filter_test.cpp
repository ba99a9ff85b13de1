// The à-trous filter (engine/render/aov_filter.h) as a render option: it lowers the error of 1-
// and 4-spp frames against a high-spp reference of a fixed scene and does not raise that of 16-
// and 64-spp frames (known answers, not timings), leaves noise-free frames as they are, keeps
// sky pixels and the requested AOV list as they were, and stays reproducible.

#include <cmath>

#include <gtest/gtest.h>

#include "engine/render/aov_filter.h"
#include "engine/scene/demo_scene.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

constexpr uint32_t W = 96, H = 72;

std::unique_ptr<Engine> demo_engine() {
    auto engine = test::make_engine();
    auto r = engine->apply(make_demo_scene());
    EXPECT_TRUE(r.has_value());
    return engine;
}

RenderRequest request(uint32_t spp, bool filter, std::vector<Aov> aovs = {}) {
    RenderRequest r = test::request(W, H, spp, std::move(aovs));
    r.filter = filter;
    return r;
}

/// RMSE of the colours after compressing each channel with c / (1 + c): the error as a display
/// shows it (a sun highlight of radiance 50 counts like one of 5, not ten times more).
double rmse(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
    double sum = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        const Vec3 d = a[i] / (1.0f + a[i]) - b[i] / (1.0f + b[i]);
        sum += double(glm::dot(d, d));
    }
    return std::sqrt(sum / double(3 * a.size()));
}

/// Display RMSE of the plain and the filtered frame of `spp` samples against `reference`.
std::pair<double, double> errors(Engine& engine, const Frame& reference, uint32_t spp) {
    const Frame plain = test::render_frame_ok(engine, request(spp, false));
    const Frame filtered = test::render_frame_ok(engine, request(spp, true));
    return {rmse(plain.buffers.color, reference.buffers.color),
            rmse(filtered.buffers.color, reference.buffers.color)};
}

// The filter follows each pixel's noise (its variance of the mean), so it must help at a few
// samples per pixel and stay out of the way once the frame has converged. The reference shares
// its first samples with the frames it judges (a 1/1024 to 1/16 share), which flatters neither.
TEST(AovFilter, LowersTheErrorOfOneAndFourSampleFramesOfTheDemoScene) {
    auto engine = demo_engine();
    const Frame reference = test::render_frame_ok(*engine, request(1024, false));
    // At 96x72 the demo's spheres are a few pixels across, so 4 spp gains less than on the
    // bench's 200x150 frame (tests/bench/NOTES.md).
    for (const auto& [spp, most] : {std::pair{1u, 0.8}, std::pair{4u, 0.92}}) {
        const auto [before, after] = errors(*engine, reference, spp);
        EXPECT_LT(after, most * before) << spp << " spp: " << before << " -> " << after;
    }
}

TEST(AovFilter, DoesNotRaiseTheErrorOfSixteenAndSixtyFourSampleFrames) {
    auto engine = demo_engine();
    const Frame reference = test::render_frame_ok(*engine, request(1024, false));
    for (uint32_t spp : {16u, 64u}) {
        const auto [before, after] = errors(*engine, reference, spp);
        EXPECT_LT(after, 1.05 * before) << spp << " spp: " << before << " -> " << after;
    }
}

/// A 32x32 frame of flat, facing surfaces whose lighting varies smoothly, with a step in the
/// middle: what a converged frame looks like to the filter.
FrameBuffers converged_frame() {
    FrameBuffers b;
    b.allocate(32, 32, AovSet({Aov::Albedo, Aov::Normal, Aov::Depth}));
    for (uint32_t y = 0; y < 32; ++y) {
        for (uint32_t x = 0; x < 32; ++x) {
            const std::size_t p = y * 32 + x;
            const float light = 0.5f + 0.02f * float(x) + (y >= 16 ? 0.4f : 0.0f);
            b.albedo[p] = Vec3(0.6f, 0.5f, 0.4f);
            b.color[p] = light * b.albedo[p];
            b.normal[p] = Vec3(0, 0, 1);
            b.depth[p] = 5.0f;
        }
    }
    return b;
}

TEST(AovFilter, ANoiseFreeFramePassesThroughUnchanged) {
    // The renderer measured no variance in any pixel (every sample alike): nothing may move.
    FrameBuffers b = converged_frame();
    const std::vector<Vec3> before = b.color;
    const std::vector<float> variance(before.size(), 0.0f);
    filter_frame(b, variance);
    for (std::size_t p = 0; p < before.size(); ++p) {
        EXPECT_NEAR(b.color[p].x, before[p].x, 1e-6f) << p;
        EXPECT_NEAR(b.color[p].y, before[p].y, 1e-6f) << p;
        EXPECT_NEAR(b.color[p].z, before[p].z, 1e-6f) << p;
    }
}

TEST(AovFilter, NoPixelMovesFartherThanItsNoiseAllows) {
    // A small measured noise everywhere: a pixel's lighting moves at most k / 2 of its (3x3
    // smoothed, here uniform) standard deviation, however far the taps disagree; k is
    // change_sigmas from converged_samples on, 0.5 more per halving below, at most
    // few_samples_change_sigmas.
    const AovFilterSettings settings;
    for (const auto& [samples, k] :
         {std::pair{64u, 1.0f}, std::pair{16u, 2.0f}, std::pair{4u, 3.0f}, std::pair{2u, 3.0f}}) {
        FrameBuffers b = converged_frame();
        const std::vector<Vec3> before = b.color;
        const float deviation = 1e-3f;
        // The renderer passes s^2 / n; the filter divides by n once more (stratified samples).
        const std::vector<float> variance(before.size(), deviation * deviation * float(samples));
        filter_frame(b, variance, samples, settings);
        std::size_t moved = 0;
        for (std::size_t p = 0; p < before.size(); ++p) {
            // The lighting luminance (the colour over the albedo) moved by at most k s / 2, s
            // the deviation carried into lighting units as demodulation scales the luminance.
            const Vec3 albedo(0.6f, 0.5f, 0.4f);
            const float lighting = luminance(before[p] / albedo);
            const float s = deviation * lighting / luminance(before[p]);
            const float lighting_change = std::abs(luminance(b.color[p] / albedo) - lighting);
            EXPECT_LE(lighting_change, 0.5f * k * s * 1.01f) << samples << " samples, " << p;
            moved += b.color[p] != before[p];
        }
        EXPECT_GT(moved, 0u) << "the noise allows some smoothing";
    }
}

TEST(AovFilter, TakesFirefliesDownAndKeepsConvergedHighlights) {
    // Two pixels five times brighter than a flat surround: one whose 4 samples disagree as a
    // rare bright path makes them (one sample of 17, three of 0.5: spread 7.1), one whose
    // samples all agree (a highlight). The first is a firefly, the second is signal.
    FrameBuffers b = converged_frame();
    std::vector<float> variance(b.pixel_count(), 1e-4f);
    const Vec3 albedo(0.6f, 0.5f, 0.4f);
    const std::size_t firefly = 8 * 32 + 8, highlight = 8 * 32 + 24;
    for (std::size_t p : {firefly, highlight})
        b.color[p] = 5.0f * luminance(b.color[p]) * albedo / luminance(albedo);
    const float l = luminance(b.color[firefly]);
    variance[firefly] = (l * 1.4f) * (l * 1.4f) / 4.0f;  // s^2 / n, s = 1.4 times the mean
    variance[highlight] = 0.0f;
    const Vec3 highlight_before = b.color[highlight];
    const float surround = luminance(b.color[firefly + 1]);
    filter_frame(b, variance, 4);
    EXPECT_LT(luminance(b.color[firefly]), 1.2f * surround) << "the firefly is taken down";
    EXPECT_NEAR(b.color[highlight].x, highlight_before.x, 1e-5f) << "the highlight stays";
    EXPECT_NEAR(b.color[highlight].y, highlight_before.y, 1e-5f);
}

TEST(AovFilter, ReusedWorkingMemoryGivesTheSameFrames) {
    // Frames of two sizes and different content through one FilterScratch, against the same
    // frames filtered with memory of their own: a reused buffer must carry nothing over.
    auto engine = demo_engine();
    FilterScratch scratch;
    const uint32_t sizes[][2] = {{W, H}, {W, H}, {50, 31}, {W, H}};
    for (uint32_t i = 0; i < 4; ++i) {
        RenderRequest r = request(1 + i, false, {Aov::Albedo, Aov::Normal, Aov::Depth});
        r.width = sizes[i][0];
        r.height = sizes[i][1];
        const Frame frame = test::render_frame_ok(*engine, r);
        FrameBuffers own = frame.buffers, reused = frame.buffers;
        filter_frame(own, {});
        filter_frame(reused, {}, 1, {}, &scratch);
        EXPECT_EQ(own.color, reused.color) << i;
        EXPECT_GT(scratch.bytes(), std::size_t(r.width) * r.height * 20 * sizeof(float));
    }
    scratch.release();
    EXPECT_EQ(scratch.bytes(), 0u);
}

TEST(AovFilter, AConstantFrameStaysConstantWhateverItsNoise) {
    FrameBuffers b;
    b.allocate(24, 24, AovSet({Aov::Albedo, Aov::Normal, Aov::Depth}));
    for (std::size_t p = 0; p < b.pixel_count(); ++p) {
        b.albedo[p] = Vec3(0.8f);
        b.color[p] = Vec3(0.3f, 0.4f, 0.5f);
        b.normal[p] = Vec3(0, 1, 0);
        b.depth[p] = 3.0f;
    }
    const std::vector<float> variance(b.pixel_count(), 0.05f);
    filter_frame(b, variance);
    for (const Vec3& c : b.color) {
        EXPECT_NEAR(c.x, 0.3f, 1e-5f);
        EXPECT_NEAR(c.y, 0.4f, 1e-5f);
        EXPECT_NEAR(c.z, 0.5f, 1e-5f);
    }
}

TEST(AovFilter, LeavesSkyPixelsAndTheRequestedAovsAsTheyWere) {
    auto engine = demo_engine();
    const Frame plain = test::render_frame_ok(*engine, request(1, false, {Aov::Depth}));
    const Frame filtered = test::render_frame_ok(*engine, request(1, true, {Aov::Depth}));
    ASSERT_EQ(filtered.buffers.depth.size(), plain.buffers.depth.size());
    EXPECT_TRUE(filtered.buffers.albedo.empty()) << "a guide that was not asked for is dropped";
    EXPECT_TRUE(filtered.buffers.normal.empty());
    EXPECT_FALSE(filtered.buffers.aovs.has(Aov::Albedo));
    std::size_t sky = 0, changed = 0;
    for (std::size_t p = 0; p < plain.buffers.color.size(); ++p) {
        if (std::isfinite(plain.buffers.depth[p])) {
            changed += plain.buffers.color[p] != filtered.buffers.color[p];
            continue;
        }
        ++sky;
        EXPECT_EQ(plain.buffers.color[p], filtered.buffers.color[p]);
    }
    EXPECT_GT(sky, 0u);
    EXPECT_GT(changed, plain.buffers.color.size() / 4);
}

TEST(AovFilter, FilteredFramesAreReproducible) {
    auto engine = demo_engine();
    for (uint32_t spp : {1u, 2u, 5u}) {
        const Frame a = test::render_frame_ok(*engine, request(spp, true));
        const Frame b = test::render_frame_ok(*engine, request(spp, true));
        EXPECT_EQ(a.buffers.color, b.buffers.color) << spp;
    }
}

TEST(AovFilter, AnAccumulatedFilteredFrameEqualsOneLaunchOfAsManySamples) {
    // The filter's noise level comes from per-pixel sums that accumulate like the colour.
    auto engine = demo_engine();
    RenderRequest step = request(3, true);
    step.accumulate = true;
    test::render_frame_ok(*engine, step);
    const Frame accumulated = test::render_frame_ok(*engine, step);
    ASSERT_EQ(accumulated.info.samples, 6u);
    const Frame once = test::render_frame_ok(*engine, request(6, true));
    EXPECT_EQ(accumulated.buffers.color, once.buffers.color);
}

TEST(AovFilter, KeepsTextureDetailByFilteringTheLightingOnly) {
    // A flat, evenly lit checkerboard of albedos: the demodulated lighting is smooth, so the
    // filter must give back each pixel's own albedo times the lighting, not a grey blur.
    FrameBuffers b;
    b.allocate(16, 16, AovSet({Aov::Albedo, Aov::Normal, Aov::Depth}));
    for (uint32_t y = 0; y < 16; ++y) {
        for (uint32_t x = 0; x < 16; ++x) {
            const std::size_t p = y * 16 + x;
            const float a = (x + y) % 2 ? 0.9f : 0.1f;
            b.albedo[p] = Vec3(a);
            b.color[p] = Vec3(a * 2.0f);
            b.normal[p] = Vec3(0, 0, 1);
            b.depth[p] = 5.0f;
        }
    }
    const std::vector<Vec3> before = b.color;
    filter_frame(b, {});
    for (std::size_t p = 0; p < before.size(); ++p) {
        EXPECT_NEAR(b.color[p].x, before[p].x, 1e-4f) << p;
    }
}

}  // namespace
}  // namespace strata
