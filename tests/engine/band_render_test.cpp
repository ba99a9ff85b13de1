// Bands of a frame (RenderRequest::band) and their assembly (band_assembly.h): a band holds
// exactly the same rows of a whole render, and bands rendered apart, sent as their EXR and
// assembled, give the bytes of the whole render, PNG or EXR, filtered or not.

#include <algorithm>
#include <cstring>

#include <gtest/gtest.h>

#include "engine/render/band_assembly.h"
#include "engine/render/frame_encode.h"
#include "engine/scene/demo_scene.h"
#include "tests/engine/render_test_util.h"

namespace strata {
namespace {

using test::render_frame_ok;
using test::render_ok;
using test::request;

const std::vector<Aov> ALL_AOVS = {Aov::Albedo,     Aov::Normal,      Aov::Depth,  Aov::Position,
                                   Aov::InstanceId, Aov::PrimitiveId, Aov::MeshId, Aov::UserId};

/// True when rows [y0, y0 + band.height) of `whole` hold the bytes of `band`, buffer by buffer.
template <class T>
::testing::AssertionResult same_rows(const std::vector<T>& whole, const std::vector<T>& band,
                                     uint32_t width, uint32_t y0, const char* what) {
    const std::size_t n = band.size();
    if (n == 0 && whole.empty()) return ::testing::AssertionSuccess();
    const std::size_t offset = std::size_t(y0) * width;
    if (offset + n > whole.size())
        return ::testing::AssertionFailure() << what << ": band of " << n << " values past the end";
    if (std::memcmp(whole.data() + offset, band.data(), n * sizeof(T)) != 0) {
        std::size_t i = 0;
        while (std::memcmp(&whole[offset + i], &band[i], sizeof(T)) == 0) ++i;
        return ::testing::AssertionFailure()
               << what << " differs at band pixel " << i % width << "," << i / width;
    }
    return ::testing::AssertionSuccess();
}

void expect_band_is_rows_of(const FrameBuffers& whole, const FrameBuffers& band, uint32_t y0) {
    ASSERT_EQ(band.width, whole.width);
    EXPECT_TRUE(band.aovs == whole.aovs);
    EXPECT_TRUE(same_rows(whole.color, band.color, whole.width, y0, "color"));
    EXPECT_TRUE(same_rows(whole.albedo, band.albedo, whole.width, y0, "albedo"));
    EXPECT_TRUE(same_rows(whole.normal, band.normal, whole.width, y0, "normal"));
    EXPECT_TRUE(same_rows(whole.depth, band.depth, whole.width, y0, "depth"));
    EXPECT_TRUE(same_rows(whole.position, band.position, whole.width, y0, "position"));
    EXPECT_TRUE(same_rows(whole.instance_id, band.instance_id, whole.width, y0, "instance_id"));
    EXPECT_TRUE(same_rows(whole.primitive_id, band.primitive_id, whole.width, y0, "primitive_id"));
    EXPECT_TRUE(same_rows(whole.mesh_id, band.mesh_id, whole.width, y0, "mesh_id"));
    EXPECT_TRUE(same_rows(whole.user_id, band.user_id, whole.width, y0, "user_id"));
}

class BandRender : public ::testing::Test {
protected:
    void SetUp() override { engine = test::engine_with(make_demo_scene()); }

    /// Renders `r` split into `bands` the way a coordinator does: each band on its own (one
    /// launch), sent as its EXR, read back, assembled, finished and encoded.
    std::string split_render(const RenderRequest& r, const std::vector<RowBand>& bands) {
        auto frames = engine->render_bands(band_request(r, RowBand{}), bands);
        EXPECT_TRUE(frames.has_value()) << (frames ? "" : frames.error().describe());
        if (!frames) return {};
        FrameAssembly assembly(r.width, r.height, band_aovs(r));
        for (std::size_t k = 0; k < bands.size(); ++k) {
            const Frame& f = frames.value()[k];
            const RenderRequest wire = band_request(r, bands[k]);
            auto exr = encode_frame(f.buffers, wire, exr_attributes(f));
            EXPECT_TRUE(exr.has_value());
            if (!exr) return {};
            const DecodedExr decoded = test::decode_exr_ok(exr->bytes);
            auto band = band_from_exr(decoded, r.width, bands[k].rows, band_aovs(r));
            EXPECT_TRUE(band.has_value()) << (band ? "" : band.error().describe());
            if (!band) return {};
            Status placed = assembly.place(band->buffers, bands[k].y0, band->names);
            EXPECT_TRUE(placed.has_value()) << (placed ? "" : placed.error().describe());
        }
        auto frame = std::move(assembly).finish(r, frames.value()[0].camera, FrameInfo{});
        EXPECT_TRUE(frame.has_value()) << (frame ? "" : frame.error().describe());
        if (!frame) return {};
        auto encoded = encode_frame(frame->buffers, r, exr_attributes(frame.value()));
        EXPECT_TRUE(encoded.has_value());
        return encoded ? encoded->bytes : std::string();
    }

    std::unique_ptr<Engine> engine;
};

TEST_F(BandRender, EveryBandHoldsTheSameRowsAsAWholeRender) {
    struct Size {
        uint32_t w, h;
    };
    for (const Size size : {Size{96, 54}, Size{37, 29}, Size{50, 17}, Size{23, 5}}) {
        for (const uint32_t spp : {1u, 3u}) {
            const RenderRequest whole = request(size.w, size.h, spp, ALL_AOVS);
            const Frame reference = render_frame_ok(*engine, whole);
            // Aligned and unaligned starts and ends, single rows, the first and last rows.
            const std::vector<RowBand> bands = {
                {0, size.h}, {0, 1}, {size.h - 1, 1}, {1, size.h - 2},
                {3, 2},      {2, 3}, {4, 1},          {size.h / 2, size.h - size.h / 2}};
            for (const RowBand b : bands) {
                SCOPED_TRACE(std::to_string(size.w) + "x" + std::to_string(size.h) + " spp " +
                             std::to_string(spp) + " rows " + std::to_string(b.y0) + "+" +
                             std::to_string(b.rows));
                RenderRequest part = whole;
                part.band = b;
                const Frame band = render_frame_ok(*engine, part);
                ASSERT_EQ(band.buffers.height, b.rows);
                expect_band_is_rows_of(reference.buffers, band.buffers, b.y0);
                EXPECT_EQ(band.info.version, reference.info.version);
                EXPECT_EQ(band.info.samples, spp);
            }
        }
    }
}

TEST_F(BandRender, BandsRenderedInOneLaunchAreThoseRenderedApart) {
    const RenderRequest whole = request(40, 30, 2, ALL_AOVS);
    const std::vector<RowBand> bands = split_rows(30, 3);
    auto frames = engine->render_bands(whole, bands);
    ASSERT_TRUE(frames.has_value()) << frames.error().describe();
    ASSERT_EQ(frames->size(), 3u);
    const Frame reference = render_frame_ok(*engine, whole);
    for (std::size_t k = 0; k < bands.size(); ++k)
        expect_band_is_rows_of(reference.buffers, (*frames)[k].buffers, bands[k].y0);
}

TEST_F(BandRender, AssembledBandsEncodeToTheBytesOfAWholeRender) {
    RenderRequest png = request(61, 37, 2, {}, ImageFormat::Png);
    png.exposure = 0.5f;
    RenderRequest exr = request(61, 37, 2, ALL_AOVS);
    RenderRequest exr_zip = exr;
    exr_zip.compression = ExrCompression::Zip;
    RenderRequest filtered = request(61, 37, 1, {}, ImageFormat::Png);
    filtered.filter = true;
    RenderRequest filtered_exr = request(61, 37, 1, {Aov::Depth, Aov::InstanceId});
    filtered_exr.filter = true;
    RenderRequest moved = request(48, 33, 1, {}, ImageFormat::Png);
    moved.camera = SetCamera{};
    moved.camera->eye = Vec3(3.0f, 4.0f, 9.0f);
    for (const RenderRequest& r : {png, exr, exr_zip, filtered, filtered_exr, moved}) {
        const std::string whole = render_ok(*engine, r).bytes;
        ASSERT_FALSE(whole.empty());
        for (const uint32_t n : {1u, 2u, 3u, 5u}) {
            SCOPED_TRACE(std::string(image_format_name(r.format)) + (r.filter ? " filtered" : "") +
                         " in " + std::to_string(n) + " bands");
            EXPECT_EQ(split_render(r, split_rows(r.height, n)), whole);
        }
        // Unaligned bands trace some rows twice but give the same frame.
        EXPECT_EQ(split_render(r, {{0, 5}, {5, 1}, {6, r.height - 6}}), whole);
    }
}

TEST_F(BandRender, TheBandEncodingKeepsFullPrecisionAndTheWholeFramesMatrices) {
    RenderRequest r = request(32, 20, 1, {Aov::Albedo, Aov::Normal, Aov::InstanceId});
    r.band = RowBand{4, 8};
    const Frame band = render_frame_ok(*engine, r);
    const DecodedExr exr = test::decode_exr_ok(render_ok(*engine, r).bytes);
    EXPECT_EQ(exr.height, 8u);
    for (const char* name : {"R", "G", "B", "albedo.R", "N.Z"}) {
        ASSERT_NE(exr.find(name), nullptr) << name;
        EXPECT_EQ(exr.find(name)->type, ExrPixel::Float) << name;
    }
    EXPECT_EQ(exr.find("R")->f32[5], band.buffers.color[5].x);
    ASSERT_EQ(exr.ids.size(), 1u);
    EXPECT_EQ(exr.ids[0].channel, "instance_id");
    EXPECT_EQ(exr.ids[0].entries, band.names.instances);
    EXPECT_FALSE(exr.ids[0].entries.empty());
    RenderRequest whole = r;
    whole.band.reset();
    const auto band_ndc = exr_attributes(band).world_to_ndc;
    const auto whole_ndc = exr_attributes(render_frame_ok(*engine, whole)).world_to_ndc;
    ASSERT_TRUE(band_ndc && whole_ndc);
    EXPECT_TRUE(*band_ndc == *whole_ndc);
}

TEST_F(BandRender, BandsOutsideTheFrameOrWithAccumulateOrFilterAreRefusedNamingTheBand) {
    RenderRequest r = request(32, 20);
    for (const RowBand b : {RowBand{0, 0}, RowBand{20, 1}, RowBand{10, 11}, RowBand{19, 2},
                            RowBand{UINT32_MAX, 2}, RowBand{1, UINT32_MAX}}) {
        r.band = b;
        auto f = engine->render(r);
        ASSERT_FALSE(f.has_value()) << b.y0 << "+" << b.rows;
        EXPECT_EQ(f.error().field, "band");
        EXPECT_EQ(f.error().code, ErrorCode::InvalidArgument);
    }
    r.band = RowBand{0, 4};
    r.accumulate = true;
    EXPECT_EQ(engine->render(r).error().field, "band");
    r.accumulate = false;
    r.filter = true;
    EXPECT_EQ(engine->render(r).error().field, "band");
    EXPECT_EQ(engine->render_bands(request(32, 20), {{0, 10}, {10, 11}}).error().field, "band");
}

TEST(SplitRows, BandsCoverTheFrameInOrderStartingOnPacketRowsWhereTheyCan) {
    for (uint32_t h : {1u, 2u, 7u, 16u, 33u, 54u, 361u}) {
        for (uint32_t n = 1; n <= std::min(h, 16u); ++n) {
            const std::vector<RowBand> bands = split_rows(h, n);
            ASSERT_EQ(bands.size(), n) << h;
            uint32_t next = 0;
            for (const RowBand& b : bands) {
                EXPECT_EQ(b.y0, next);
                EXPECT_GT(b.rows, 0u);
                if (h >= 4 * n + 4) {
                    EXPECT_EQ(b.y0 % 4, 0u) << h << " in " << n;
                }
                next = b.y0 + b.rows;
            }
            EXPECT_EQ(next, h);
        }
    }
    EXPECT_TRUE(split_rows(3, 4).empty());
    EXPECT_TRUE(split_rows(3, 0).empty());
}

TEST(FrameAssembly, ABandThatDoesNotFitOrMissingRowsAreErrors) {
    AovSet set(std::vector<Aov>{Aov::Depth});
    FrameAssembly a(8, 6, set);
    FrameBuffers band;
    band.allocate(8, 4, set);
    EXPECT_FALSE(a.place(band, 3, {}).has_value());  // rows 3..6 of 6
    FrameBuffers narrow;
    narrow.allocate(7, 2, set);
    EXPECT_FALSE(a.place(narrow, 0, {}).has_value());
    FrameBuffers other;
    other.allocate(8, 2, AovSet{});
    EXPECT_FALSE(a.place(other, 0, {}).has_value());
    ASSERT_TRUE(a.place(band, 0, {}).has_value());
    RenderRequest r = request(8, 6, 1, {Aov::Depth});
    auto frame = std::move(a).finish(r, Camera{}, FrameInfo{});
    ASSERT_FALSE(frame.has_value());
    EXPECT_NE(frame.error().message.find("row 4"), std::string::npos);
}

}  // namespace
}  // namespace strata
