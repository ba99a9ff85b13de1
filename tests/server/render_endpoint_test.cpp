// POST and GET /v1/render: image bytes, ETag, X-Strata-Rebuild, options and errors.

#include <gmock/gmock.h>

#include "engine/image/exr.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

bool is_png(const std::string& bytes) {
    return bytes.size() > 8 && bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}

uint32_t png_width(const std::string& b) {
    return uint32_t(uint8_t(b[16])) << 24 | uint32_t(uint8_t(b[17])) << 16 |
           uint32_t(uint8_t(b[18])) << 8 | uint8_t(b[19]);
}

class Render : public ::testing::Test {
protected:
    TestServer srv{ServerConfig{}, /*demo=*/true};
};

TEST_F(Render, PostAnswersAPngWithTheVersionAndTheCommitSummary) {
    const Reply r = srv.post("/v1/render", Json{{"width", 64}, {"height", 32}, {"format", "png"}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.header("Content-Type"), "image/png");
    EXPECT_TRUE(is_png(r.body));
    EXPECT_EQ(png_width(r.body), 64u);
    EXPECT_EQ(r.header("ETag"), "\"1\"");
    EXPECT_THAT(r.header("X-Strata-Rebuild"),
                ::testing::MatchesRegex("v1 tlas=update\\(18\\) rebuilds=5 refits=0 .*ms=.*"));
    // Nothing changed since: the next frame's commit does nothing.
    const Reply again = srv.post("/v1/render", Json{{"width", 64}, {"height", 32}});
    EXPECT_THAT(again.header("X-Strata-Rebuild"),
                ::testing::StartsWith("v1 tlas=none(18) rebuilds=0 refits=0"));
}

TEST_F(Render, AReportTooLongForAHeaderKeepsItsCountsAndFitsEveryClient) {
    // Two hundred rebuilt meshes would make a 20 KiB header line: cpp-httplib, this test's own
    // client, refuses lines over 8 KiB (the answer would be lost), nginx header blocks over 4 KiB.
    Json edits = Json::array();
    for (int i = 0; i < 200; ++i) {
        edits.push_back({{"op", "add_mesh"},
                         {"id", "a-mesh-with-a-longish-name-" + std::to_string(i)},
                         {"shape", {{"type", "box"}}}});
    }
    ASSERT_EQ(srv.edits(edits).status, 200);
    const Reply r = srv.get("/v1/render?width=16&height=16");
    ASSERT_EQ(r.status, 200) << r.body;
    const std::string header = r.header("X-Strata-Report");
    EXPECT_LE(header.size(), 3u * 1024);
    const Json report = Json::parse(header);
    EXPECT_EQ(report["blas_rebuilds"], 205);  // the demo's five and these
    EXPECT_EQ(report["entries_truncated"], true);
    EXPECT_GT(report["rebuilt"].size(), 0u);
    EXPECT_LT(report["rebuilt"].size(), 205u);
    // A short report is whole.
    const Json again =
        Json::parse(srv.get("/v1/render?width=16&height=16").header("X-Strata-Report"));
    EXPECT_FALSE(again.contains("entries_truncated"));
}

TEST_F(Render, GetUsesTheQueryString) {
    const Reply r = srv.get("/v1/render?width=40&height=30&format=png&spp=1&exposure=0.5");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_TRUE(is_png(r.body));
    EXPECT_EQ(png_width(r.body), 40u);
    EXPECT_EQ(r.header("ETag"), "\"1\"");
}

TEST_F(Render, ACameraOverrideChangesTheFrameNotTheScene) {
    const Reply plain = srv.post("/v1/render", Json{{"width", 48}, {"height", 48}});
    const Reply moved = srv.post(
        "/v1/render", Json{{"width", 48}, {"height", 48}, {"camera", {{"eye", {0, 30, 0.1}}}}});
    ASSERT_EQ(moved.status, 200) << moved.body;
    EXPECT_NE(plain.body, moved.body);
    EXPECT_EQ(srv.get("/v1/scene").json()["camera"]["eye"], (Json{0, 4, 11}));
}

TEST_F(Render, EachFrameShowsTheVersionItsETagNames) {
    ASSERT_EQ(srv.edits({{{"op", "set_transform"},
                          {"instance", "crate-a"},
                          {"transform", {{"translate", {2, 0.5, 2}}}}}})
                  .status,
              200);
    const Reply r = srv.post("/v1/render", Json{{"width", 32}, {"height", 32}});
    EXPECT_EQ(r.header("ETag"), "\"2\"");
    EXPECT_THAT(r.header("X-Strata-Rebuild"), ::testing::StartsWith("v2 tlas=update"));
}

TEST_F(Render, BadOptionsAreProblems) {
    expect_problem(srv.post("/v1/render", Json{{"width", 0}}), 400, "invalid-request", "/width");
    expect_problem(srv.post("/v1/render", Json{{"format", "gif"}}), 400, "invalid-request",
                   "/format");
    expect_problem(srv.post("/v1/render", Json{{"aovs", {"depth", "depth"}}}), 422, "invalid-value",
                   "/aovs/0");
    expect_problem(srv.post("/v1/render", Json{{"camera", {{"up", {0, 0, 0}}}}}), 422,
                   "invalid-value", "/camera/up");
    expect_problem(srv.post("/v1/render", Json{{"exposure", 100}}), 422, "invalid-value",
                   "/exposure");
    expect_problem(srv.get("/v1/render?width=abc"), 400, "invalid-request", "/width");
    expect_problem(srv.get("/v1/render?zoom=2"), 400, "invalid-request", "/zoom");
    expect_problem(srv.post("/v1/render", std::string("{")), 400, "malformed-json");
}

TEST_F(Render, FramesOverThePixelCapAre413) {
    expect_problem(srv.post("/v1/render", Json{{"width", 8192}, {"height", 8192}}), 413,
                   "too-large", "/width");
}

DecodedExr decode(const Reply& r) {
    auto exr = decode_exr(reinterpret_cast<const uint8_t*>(r.body.data()), r.body.size());
    EXPECT_TRUE(exr.has_value()) << (exr.has_value() ? "" : exr.error().describe());
    return exr.has_value() ? std::move(exr.value()) : DecodedExr{};
}

TEST_F(Render, ExrFromThePostCarriesEveryRequestedAovWithOpenExrNames) {
    const Reply r = srv.post("/v1/render", Json{{"width", 40},
                                                {"height", 24},
                                                {"format", "exr"},
                                                {"compression", "piz"},
                                                {"aovs",
                                                 {"albedo", "normal", "depth", "position",
                                                  "instance_id", "primitive_id", "mesh_id"}}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.header("Content-Type"), "image/x-exr");
    EXPECT_EQ(r.header("X-Strata-Samples"), "1");
    const DecodedExr exr = decode(r);
    EXPECT_EQ(exr.width, 40u);
    EXPECT_EQ(exr.height, 24u);
    EXPECT_EQ(exr.compression, ExrCompression::Piz);
    const std::vector<std::pair<std::string, ExrPixel>> expected = {
        {"A", ExrPixel::Half},           {"B", ExrPixel::Half},
        {"G", ExrPixel::Half},           {"N.X", ExrPixel::Half},
        {"N.Y", ExrPixel::Half},         {"N.Z", ExrPixel::Half},
        {"P.X", ExrPixel::Float},        {"P.Y", ExrPixel::Float},
        {"P.Z", ExrPixel::Float},        {"R", ExrPixel::Half},
        {"Z", ExrPixel::Float},          {"albedo.B", ExrPixel::Half},
        {"albedo.G", ExrPixel::Half},    {"albedo.R", ExrPixel::Half},
        {"instance_id", ExrPixel::Uint}, {"mesh_id", ExrPixel::Uint},
        {"primitive_id", ExrPixel::Uint}};
    ASSERT_EQ(exr.channels.size(), expected.size());
    for (const auto& [name, type] : expected) {
        const DecodedExrChannel* c = exr.find(name);
        ASSERT_NE(c, nullptr) << name;
        EXPECT_EQ(c->type, type) << name;
        const std::size_t n = type == ExrPixel::Uint ? c->u32.size() : c->f32.size();
        EXPECT_EQ(n, 40u * 24u) << name;
    }
}

TEST_F(Render, ExrFromTheGetFormUsesTheQueryOptions) {
    const Reply r = srv.get(
        "/v1/render?width=32&height=16&format=exr&aovs=depth,instance_id"
        "&compression=none&spp=2");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.header("X-Strata-Samples"), "2");
    const DecodedExr exr = decode(r);
    EXPECT_EQ(exr.compression, ExrCompression::None);
    std::vector<std::string> names;
    for (const auto& c : exr.channels) names.push_back(c.name);
    EXPECT_EQ(names, (std::vector<std::string>{"A", "B", "G", "R", "Z", "instance_id"}));
}

TEST_F(Render, TheInstanceIdAovNamesTheIndexTheSceneApiReports) {
    // Look straight down at the big ball: the centre pixel shows it.
    const Reply r =
        srv.post("/v1/render", Json{{"width", 9},
                                    {"height", 9},
                                    {"format", "exr"},
                                    {"aovs", {"instance_id", "mesh_id"}},
                                    {"camera", {{"eye", {0, 12, 0.01}}, {"target", {0, 0, 0}}}}});
    ASSERT_EQ(r.status, 200) << r.body;
    const DecodedExr exr = decode(r);
    const Json ball = srv.get("/v1/scene/instances/ball").json();
    const Json ball_mesh = srv.get("/v1/scene/meshes/ball").json();
    ASSERT_TRUE(ball.contains("index") && ball_mesh.contains("index"));
    const std::size_t centre = 4 * 9 + 4;
    EXPECT_EQ(exr.find("instance_id")->u32.at(centre), ball["index"].get<uint32_t>());
    EXPECT_EQ(exr.find("mesh_id")->u32.at(centre), ball_mesh["index"].get<uint32_t>());
}

TEST_F(Render, AccumulatedFramesReportTheirGrowingSampleCount) {
    const Json body = {{"width", 16}, {"height", 16}, {"spp", 2}, {"accumulate", true}};
    EXPECT_EQ(srv.post("/v1/render", body).header("X-Strata-Samples"), "2");
    EXPECT_EQ(srv.post("/v1/render", body).header("X-Strata-Samples"), "4");
    // Any edit restarts the accumulation.
    ASSERT_EQ(srv.edits({{{"op", "set_lighting"}, {"sky_intensity", 0.3}}}).status, 200);
    EXPECT_EQ(srv.post("/v1/render", body).header("X-Strata-Samples"), "2");
}

TEST_F(Render, AovsOtherThanColorNeedExr) {
    expect_problem(srv.post("/v1/render", Json{{"format", "png"}, {"aovs", {"depth"}}}), 422,
                   "invalid-value", "/aovs/0");
}

}  // namespace
}  // namespace strata::server::test
