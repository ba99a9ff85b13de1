#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "protocol/render_parser.h"

namespace strata::protocol {
namespace {

TEST(RenderParser, ReadsEveryOptionOfTheBody) {
    auto r =
        parse_render_body(Json::parse(R"({"width": 320, "height": 200, "format": "exr", "spp": 16,
        "aovs": ["albedo", "depth"], "compression": "piz", "accumulate": true, "exposure": -1.5,
        "camera": {"eye": [0, 1, 5], "fov_y_deg": 30}})"));
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    const RenderRequest& q = r.value();
    EXPECT_EQ(q.width, 320u);
    EXPECT_EQ(q.height, 200u);
    EXPECT_EQ(q.format, ImageFormat::Exr);
    EXPECT_EQ(q.spp, 16u);
    EXPECT_THAT(q.aovs, ::testing::ElementsAre(Aov::Albedo, Aov::Depth));
    EXPECT_EQ(q.compression, ExrCompression::Piz);
    EXPECT_TRUE(q.accumulate);
    EXPECT_EQ(q.exposure, -1.5f);
    ASSERT_TRUE(r.value().camera.has_value());
    EXPECT_EQ(r.value().camera->eye, Vec3(0, 1, 5));
    EXPECT_FALSE(r.value().camera->target.has_value());
}

TEST(RenderParser, AnEmptyBodyMeansTheDefaults) {
    auto r = parse_render_body(Json::object());
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r.value().width, RenderRequest{}.width);
    EXPECT_EQ(r.value().format, ImageFormat::Png);
    EXPECT_FALSE(r.value().camera.has_value());
}

TEST(RenderParser, TheQueryStringCarriesTheSameOptions) {
    const std::multimap<std::string, std::string> params = {
        {"width", "64"},          {"height", "48"},        {"format", "png"},   {"spp", "4"},
        {"aovs", "normal,depth"}, {"accumulate", "false"}, {"exposure", "0.5"}, {"eye", "1,2,3"},
        {"fov_y_deg", "60"},      {"compression", "zip"},  {"shutter_close", "0.5"}};
    auto r = parse_render_query(params);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    EXPECT_EQ(r.value().width, 64u);
    EXPECT_EQ(r.value().spp, 4u);
    EXPECT_THAT(r.value().aovs, ::testing::ElementsAre(Aov::Normal, Aov::Depth));
    EXPECT_EQ(r.value().exposure, 0.5f);
    EXPECT_EQ(r.value().camera->eye, Vec3(1, 2, 3));
    EXPECT_EQ(r.value().camera->fov_y_deg, 60.0f);
    EXPECT_EQ(r.value().camera->shutter_close, 0.5f);
    EXPECT_FALSE(r.value().camera->shutter_open.has_value());
}

TEST(RenderParser, FrameNamesAGroupOrAnInstanceInTheBodyOrTheQuery) {
    std::optional<FrameTarget> frame;
    auto r = parse_render_body(Json::parse(R"({"frame": {"group": "car"}})"), nullptr, &frame);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    ASSERT_TRUE(frame.has_value());
    EXPECT_EQ(frame->kind, FrameTarget::Kind::Group);
    EXPECT_EQ(frame->id, "car");
    // A query id that looks like a number stays text.
    frame.reset();
    r = parse_render_query({{"frame_instance", "12"}, {"width", "32"}}, nullptr, &frame);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    ASSERT_TRUE(frame.has_value());
    EXPECT_EQ(frame->kind, FrameTarget::Kind::Instance);
    EXPECT_EQ(frame->id, "12");
    frame.reset();
    EXPECT_TRUE(parse_render_body(Json::object(), nullptr, &frame).has_value());
    EXPECT_FALSE(frame.has_value());

    const auto pointer = [&](const char* body) {
        return parse_render_body(Json::parse(body), nullptr, &frame).error().pointer;
    };
    EXPECT_EQ(pointer(R"({"frame": {"group": "a", "instance": "b"}})"), "/frame");
    EXPECT_EQ(pointer(R"({"frame": {}})"), "/frame");
    EXPECT_EQ(pointer(R"({"frame": {"group": 7}})"), "/frame/group");
    EXPECT_EQ(pointer(R"({"frame": {"mesh": "m"}})"), "/frame/mesh");
    EXPECT_EQ(parse_render_query({{"frame_group", "a"}, {"frame_instance", "b"}}, nullptr, &frame)
                  .error()
                  .pointer,
              "/frame");
    // A caller that does not frame (the stream) refuses the member as unknown.
    EXPECT_EQ(parse_render_body(Json::parse(R"({"frame": {"group": "a"}})")).error().pointer,
              "/frame");
}

TEST(RenderParser, ErrorsPointAtTheMemberOrParameter) {
    EXPECT_EQ(parse_render_body(Json::parse(R"({"width": 0})")).error().pointer, "/width");
    EXPECT_EQ(parse_render_body(Json::parse(R"({"format": "jpg"})")).error().pointer, "/format");
    EXPECT_EQ(parse_render_body(Json::parse(R"({"aovs": ["color", "beauty"]})")).error().pointer,
              "/aovs/1");
    EXPECT_EQ(parse_render_body(Json::parse(R"({"widht": 10})")).error().pointer, "/widht");
    EXPECT_EQ(parse_render_query({{"width", "wide"}}).error().pointer, "/width");
    EXPECT_EQ(parse_render_query({{"size", "10"}}).error().pointer, "/size");
    EXPECT_EQ(parse_render_query({{"width", "10"}, {"width", "20"}}).error().pointer, "/width");
    EXPECT_EQ(parse_render_query({{"eye", "1,2"}}).error().pointer, "/camera/eye");
}

TEST(RenderParser, QueryNumbersAreDecimalOnly) {
    for (const char* text : {"0x10", " 16", "16 ", "+16", "inf", "nan", "1e", "1.", ".5", "--1"}) {
        auto r = parse_render_query({{"width", text}});
        ASSERT_FALSE(r.has_value()) << "'" << text << "'";
        EXPECT_EQ(r.error().pointer, "/width") << text;
        EXPECT_EQ(r.error().type, ProblemType::InvalidRequest) << text;
    }
    for (const char* text : {"16", "016", "1.6e1", "16.0"}) {
        auto r = parse_render_query({{"width", text}});
        ASSERT_TRUE(r.has_value()) << "'" << text << "': " << r.error().detail;
        EXPECT_EQ(r.value().width, 16u) << text;
    }
    auto eye = parse_render_query({{"eye", "1,-2.5,3e-1"}});
    ASSERT_TRUE(eye.has_value()) << eye.error().detail;
    EXPECT_EQ(eye.value().camera->eye, Vec3(1, -2.5f, 0.3f));
    EXPECT_FALSE(parse_render_query({{"eye", "1,0x2,3"}}).has_value());
}

TEST(RenderParser, QueriesTheFuzzerFoundAreRefusedCleanly) {
    // "camera" as a parameter made the eye's slot index into a string (a type_error, so a 500).
    auto camera = parse_render_query({{"camera", "exr"}, {"eye", "1,1,0"}});
    ASSERT_FALSE(camera.has_value());
    EXPECT_EQ(camera.error().pointer, "/camera");
    // A number beyond uint64_t was converted to it first (undefined behaviour), then compared.
    auto big = parse_render_query({{"width", "4.44e62"}});
    ASSERT_FALSE(big.has_value());
    EXPECT_EQ(big.error().pointer, "/width");
}

TEST(RenderParser, ACameraOverrideKeepsOnlyTheFieldsItNames) {
    // The engine completes the rest from the camera of the version it renders.
    const auto r = parse_render_body(Json::parse(R"({"camera": {"fov_y_deg": 20}})"));
    ASSERT_TRUE(r.has_value());
    ASSERT_TRUE(r.value().camera.has_value());
    EXPECT_EQ(r.value().camera->fov_y_deg, 20.0f);
    EXPECT_FALSE(r.value().camera->eye.has_value());
    EXPECT_FALSE(r.value().camera->target.has_value());
}

TEST(RenderParser, BandAndSplitAreReadFromTheBodyAndTheQuery) {
    uint32_t split = 0;
    auto body =
        parse_render_body(Json::parse(R"({"height": 100, "band": [8, 12], "split": 1})"), &split);
    ASSERT_TRUE(body.has_value()) << body.error().detail;
    ASSERT_TRUE(body.value().band.has_value());
    EXPECT_EQ(*body.value().band, (RowBand{8, 12}));
    EXPECT_EQ(split, 1u);
    auto query = parse_render_query({{"height", "90"}, {"split", "3"}}, &split);
    ASSERT_TRUE(query.has_value()) << query.error().detail;
    EXPECT_EQ(split, 3u);
    EXPECT_FALSE(query.value().band.has_value());
    auto band = parse_render_query({{"band", "0,7"}, {"format", "exr"}}, &split);
    ASSERT_TRUE(band.has_value()) << band.error().detail;
    EXPECT_EQ(*band.value().band, (RowBand{0, 7}));
    EXPECT_EQ(split, 1u);  // absent: a plain render
}

TEST(RenderParser, BadBandsAndSplitsAreRefusedNamingTheParameter) {
    uint32_t split = 0;
    auto pointer = [&](std::multimap<std::string, std::string> params) {
        auto r = parse_render_query(params, &split);
        return r.has_value() ? std::string("(accepted)") : r.error().pointer;
    };
    EXPECT_EQ(pointer({{"band", "3"}}), "/band");
    EXPECT_EQ(pointer({{"band", "1,2,3"}}), "/band");
    EXPECT_EQ(pointer({{"band", "x,2"}}), "/band/0");
    EXPECT_EQ(pointer({{"band", "-1,2"}}), "/band/0");
    EXPECT_EQ(pointer({{"band", "0,0"}}), "/band/1");
    EXPECT_EQ(pointer({{"band", "0,1.5"}}), "/band/1");
    EXPECT_EQ(pointer({{"band", "0,2"}, {"band", "2,2"}}), "/band");
    EXPECT_EQ(pointer({{"split", "0"}}), "/split");
    EXPECT_EQ(pointer({{"split", "17"}}), "/split");
    EXPECT_EQ(pointer({{"split", "two"}}), "/split");
    EXPECT_EQ(pointer({{"split", "2"}, {"band", "0,4"}}), "/split");
    EXPECT_EQ(pointer({{"split", "2"}, {"accumulate", "true"}}), "/split");
    EXPECT_EQ(pointer({{"split", "9"}, {"height", "8"}}), "/split");
    EXPECT_EQ(pointer({{"split", "8"}, {"height", "8"}}), "(accepted)");
    auto refused = parse_render_query({{"split", "2"}, {"band", "0,4"}}, &split);
    ASSERT_FALSE(refused.has_value());
    EXPECT_THAT(refused.error().detail, ::testing::HasSubstr("band"));
    // A caller that cannot split (GET /v1/stream) does not know the member at all.
    auto unknown = parse_render_query({{"split", "2"}});
    ASSERT_FALSE(unknown.has_value());
    EXPECT_EQ(unknown.error().pointer, "/split");
    EXPECT_EQ(parse_render_body(Json::parse(R"({"band": {"y0": 1}})"), &split).error().pointer,
              "/band");
}

}  // namespace
}  // namespace strata::protocol
