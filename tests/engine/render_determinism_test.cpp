// Determinism and progressive refinement: the same inputs give the same bytes whatever the thread
// count, accumulated samples equal one launch of the total, and accumulation converges and
// restarts on any change.

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "engine/image/tonemap.h"
#include "engine/scene/demo_scene.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::render_frame_ok;
using test::render_ok;
using test::request;

const std::vector<Aov> ALL_AOVS = {Aov::Albedo,     Aov::Normal,      Aov::Depth, Aov::Position,
                                   Aov::InstanceId, Aov::PrimitiveId, Aov::MeshId};

class RenderDeterminism : public ::testing::Test {
protected:
    void SetUp() override { engine = test::engine_with(make_demo_scene()); }

    RenderRequest exr(uint32_t spp, bool accumulate = false) const {
        RenderRequest r = request(96, 54, spp, ALL_AOVS);
        r.compression = ExrCompression::None;
        r.accumulate = accumulate;
        return r;
    }

    std::unique_ptr<Engine> engine;
};

TEST_F(RenderDeterminism, SameInputsGiveIdenticalBytes) {
    const EncodedFrame a = render_ok(*engine, exr(4));
    const EncodedFrame b = render_ok(*engine, exr(4));
    ASSERT_FALSE(a.bytes.empty());
    EXPECT_EQ(a.bytes, b.bytes);

    RenderRequest png = request(96, 54, 4, {}, ImageFormat::Png);
    EXPECT_EQ(render_ok(*engine, png).bytes, render_ok(*engine, png).bytes);

    // Compression runs on OpenEXR's thread pool; the file is the same bytes every time.
    for (ExrCompression c : {ExrCompression::Zip, ExrCompression::Piz}) {
        RenderRequest compressed = exr(4);
        compressed.compression = c;
        compressed.width = 300;  // several compressed blocks
        compressed.height = 200;
        EXPECT_EQ(render_ok(*engine, compressed).bytes, render_ok(*engine, compressed).bytes);
    }

    // A fresh engine with the same scene gives the same frame too.
    auto other = test::engine_with(make_demo_scene());
    EXPECT_EQ(render_ok(*other, exr(4)).bytes, a.bytes);
}

TEST_F(RenderDeterminism, ThreadCountDoesNotChangeTheBytes) {
    auto render_in = [&](int threads) {
        tbb::task_arena arena(threads);
        EncodedFrame image;
        arena.execute([&] { image = render_ok(*engine, exr(3)); });
        return image.bytes;
    };
    const std::string one = render_in(1);
    ASSERT_FALSE(one.empty());
    EXPECT_EQ(render_in(2), one);
    EXPECT_EQ(render_in(5), one);
}

TEST_F(RenderDeterminism, MoreSamplesChangeTheImage) {
    // Guards the tests above against a renderer that ignores its samples.
    EXPECT_NE(render_ok(*engine, exr(1)).bytes, render_ok(*engine, exr(2)).bytes);
}

TEST_F(RenderDeterminism, AccumulatingKPlusKEqualsOneLaunchOf2K) {
    const EncodedFrame single = render_ok(*engine, exr(6));
    EXPECT_EQ(single.info.samples, 6u);

    const EncodedFrame first = render_ok(*engine, exr(3, true));
    EXPECT_EQ(first.info.samples, 3u);
    EXPECT_EQ(first.bytes, render_ok(*engine, exr(3)).bytes) << "a restart is a plain render";
    const EncodedFrame second = render_ok(*engine, exr(3, true));
    EXPECT_EQ(second.info.samples, 6u);
    EXPECT_EQ(second.bytes, single.bytes);

    // Uneven steps give the same total too.
    const EncodedFrame third = render_ok(*engine, exr(1, true));
    const EncodedFrame fourth = render_ok(*engine, exr(2, true));
    EXPECT_EQ(third.info.samples, 7u);
    EXPECT_EQ(fourth.info.samples, 9u);
    EXPECT_EQ(fourth.bytes, render_ok(*engine, exr(9)).bytes);
}

TEST_F(RenderDeterminism, AccumulationConverges) {
    // d(k) = RMS difference between the images of k and 2k samples: it shrinks like 1/sqrt(k).
    // Compared after the tone curve: a few pixels of the sun's highlight in the chrome ball are
    // thousands of times brighter than the rest and would dominate a linear RMS.
    RenderRequest r = request(64, 36, 1);
    r.accumulate = true;
    std::vector<std::vector<Vec3>> images;  // 1, 2, 4, ..., 64 samples
    for (uint32_t total = 1, step = 1; total <= 64; step = total, total *= 2) {
        r.spp = step;
        const Frame f = render_frame_ok(*engine, r);
        ASSERT_EQ(f.info.samples, total);
        images.push_back(f.buffers.color);
        for (Vec3& c : images.back()) c = aces_fitted(c);
    }
    std::vector<double> d;
    for (std::size_t i = 0; i + 1 < images.size(); ++i)
        d.push_back(test::rms_difference(images[i], images[i + 1]));
    ASSERT_GT(d.front(), 0.0);
    EXPECT_LT(d[2], 0.75 * d[0]) << "k = 4 vs k = 1";
    EXPECT_LT(d[4], 0.75 * d[2]) << "k = 16 vs k = 4";
    EXPECT_LT(d[5], d[0] / 3.0) << "k = 32 vs k = 1";
}

TEST_F(RenderDeterminism, AnyEditOrCameraChangeRestartsAccumulation) {
    EXPECT_EQ(render_ok(*engine, exr(2, true)).info.samples, 2u);
    EXPECT_EQ(render_ok(*engine, exr(2, true)).info.samples, 4u);

    // Post-processing options and plain renders in between do not restart it.
    RenderRequest png = request(96, 54, 2, {}, ImageFormat::Png);
    png.accumulate = true;
    png.exposure = 1.5f;
    EXPECT_EQ(render_ok(*engine, png).info.samples, 6u);
    EXPECT_EQ(render_ok(*engine, exr(1)).info.samples, 1u);
    EXPECT_EQ(render_ok(*engine, exr(2, true)).info.samples, 8u);

    // A lighting edit bumps the version: restart.
    SetLighting light;
    light.sky_intensity = 0.3f;
    apply_ok(*engine, light);
    EXPECT_EQ(render_ok(*engine, exr(2, true)).info.samples, 2u);

    // A camera override restarts; going back to the scene camera restarts again.
    RenderRequest moved = exr(2, true);
    SetCamera cam;
    cam.eye = Vec3(3.0f, 4.0f, 9.0f);
    moved.camera = cam;
    EXPECT_EQ(render_ok(*engine, moved).info.samples, 2u);
    EXPECT_EQ(render_ok(*engine, moved).info.samples, 4u);
    EXPECT_EQ(render_ok(*engine, exr(2, true)).info.samples, 2u);

    // A new size restarts.
    RenderRequest bigger = exr(2, true);
    bigger.width = 100;
    EXPECT_EQ(render_ok(*engine, bigger).info.samples, 2u);

    // An instance edit restarts, and the result matches a fresh render of the new scene.
    apply_ok(*engine, SetTransform{"crate-a", Affine::translation({-1.0f, 0.5f, 3.0f})});
    const EncodedFrame restarted = render_ok(*engine, exr(2, true));
    EXPECT_EQ(restarted.info.samples, 2u);
    EXPECT_EQ(restarted.bytes, render_ok(*engine, exr(2)).bytes);
}

TEST_F(RenderDeterminism, AccumulationStopsAtItsCap) {
    RenderRequest r = request(4, 4, MAX_RENDER_SPP);
    r.accumulate = true;
    uint32_t samples = 0;
    while (samples < MAX_ACCUMULATED_SAMPLES) {
        const Frame f = render_frame_ok(*engine, r);
        ASSERT_GT(f.info.samples, samples);
        samples = f.info.samples;
    }
    const Frame capped = render_frame_ok(*engine, r);
    EXPECT_EQ(capped.info.samples, MAX_ACCUMULATED_SAMPLES);
    EXPECT_EQ(capped.info.samples_added, 0u);
}

}  // namespace
}  // namespace strata

namespace strata {
namespace {

TEST(RenderCameraOverride, MissingFieldsComeFromTheCameraOfTheRenderedVersion) {
    auto engine = test::make_engine();
    ASSERT_TRUE(engine
                    ->apply(EditBatch{{test::mesh_edit("ball", make_sphere(1.0f, 32)),
                                       test::instance_edit("ball", "ball")}})
                    .has_value());
    RenderRequest request;
    request.width = 16;
    request.height = 16;
    request.format = ImageFormat::Exr;
    request.camera = SetCamera{};
    request.camera->fov_y_deg = 30.0f;  // eye and target come from the scene
    const auto before = engine->render(request);
    ASSERT_TRUE(before.has_value());

    // The same override after the scene camera moved renders from the new eye: it is completed
    // inside the launch, from the committed camera, not from whatever the caller saw earlier.
    SetCamera moved;
    moved.eye = Vec3(0.0f, 0.0f, 5.0f);
    ASSERT_TRUE(engine->apply(EditBatch{{moved}}).has_value());
    RenderRequest explicit_camera = request;
    explicit_camera.camera->eye = Vec3(0.0f, 0.0f, 5.0f);
    explicit_camera.camera->target = Vec3(0.0f);
    const auto after = engine->render(request);
    const auto expected = engine->render(explicit_camera);
    ASSERT_TRUE(after.has_value() && expected.has_value());
    EXPECT_NE(after.value().bytes, before.value().bytes);
    EXPECT_EQ(after.value().bytes, expected.value().bytes);

    // An override that only makes sense against the scene camera is checked there.
    request.camera = SetCamera{};
    request.camera->target = Vec3(0.0f, 0.0f, 5.0f);  // the scene eye: eye == target
    const auto bad = engine->render(request);
    ASSERT_FALSE(bad.has_value());
    EXPECT_EQ(bad.error().field, "camera/target");
}

}  // namespace
}  // namespace strata
