// The pieces of a split render that need no second process: --peers parsing and the band query a
// coordinator sends (it must read back as exactly the band request, camera floats included).
// tests/server/test_replicas.py splits frames across real replicas.

#include <gtest/gtest.h>

#include "engine/render/band_assembly.h"
#include "protocol/render_parser.h"
#include "server/split_render.h"

namespace strata::server {
namespace {

/// "k=v&k=v" into the multimap the router hands protocol::parse_render_query.
std::multimap<std::string, std::string> query_params(const std::string& query) {
    std::multimap<std::string, std::string> out;
    std::size_t start = 0;
    while (start < query.size()) {
        const std::size_t amp = std::min(query.find('&', start), query.size());
        const std::string item = query.substr(start, amp - start);
        const std::size_t eq = item.find('=');
        out.emplace(item.substr(0, eq), eq == std::string::npos ? "" : item.substr(eq + 1));
        start = amp + 1;
    }
    return out;
}

TEST(SplitRender, PeersAreCommaSeparatedHttpHostPorts) {
    auto peers = parse_peers("http://127.0.0.1:7071, 10.0.0.3:80,http://[::1]:7073/");
    ASSERT_TRUE(peers.has_value()) << peers.error().message;
    ASSERT_EQ(peers->size(), 3u);
    EXPECT_EQ((*peers)[0].host, "127.0.0.1");
    EXPECT_EQ((*peers)[0].port, 7071);
    EXPECT_EQ((*peers)[0].url, "http://127.0.0.1:7071");
    EXPECT_EQ((*peers)[1].url, "http://10.0.0.3:80");
    EXPECT_EQ((*peers)[2].host, "::1");
    EXPECT_TRUE(parse_peers("").value().empty());
    for (const char* bad :
         {"https://a:1", "a", "a:0", "a:99999", "a:1,,b:2", "http://a:1/v1", ":80", "a:x"}) {
        auto r = parse_peers(bad);
        ASSERT_FALSE(r.has_value()) << bad;
        EXPECT_EQ(r.error().field, "peers") << bad;
        EXPECT_NE(r.error().message.find("--peers"), std::string::npos) << bad;
    }
}

TEST(SplitRender, TheBandQueryReadsBackAsTheBandRequestBitForBit) {
    RenderRequest r;
    r.width = 333;
    r.height = 201;
    r.spp = 7;
    r.format = ImageFormat::Png;
    r.exposure = 1.25f;
    r.filter = true;
    r.aovs = {Aov::Color};
    r.camera = SetCamera{};
    r.camera->eye = Vec3(0.1f, -1e-7f, 12345.678f);
    r.camera->target = Vec3(1.0f / 3.0f, 2.0f / 7.0f, -0.3f);
    r.camera->fov_y_deg = 33.3f;
    r.camera->shutter_open = 0.125f;
    r.camera->shutter_close = 2.0f / 3.0f;
    r.time = 1.0f / 7.0f;
    const RowBand band{64, 70};
    auto parsed = protocol::parse_render_query(query_params(band_query(r, band)));
    ASSERT_TRUE(parsed.has_value()) << parsed.error().detail;
    const RenderRequest want = band_request(r, band);
    const RenderRequest& got = parsed.value();
    EXPECT_EQ(got.width, want.width);
    EXPECT_EQ(got.height, want.height);
    EXPECT_EQ(got.spp, want.spp);
    EXPECT_EQ(got.format, ImageFormat::Exr);
    EXPECT_EQ(got.compression, ExrCompression::None);
    EXPECT_EQ(got.aovs, want.aovs);  // color and the filter's guides
    EXPECT_FALSE(got.filter);
    ASSERT_TRUE(got.band.has_value());
    EXPECT_EQ(*got.band, band);
    ASSERT_TRUE(got.camera.has_value());
    EXPECT_EQ(got.camera->eye, r.camera->eye);
    EXPECT_EQ(got.camera->target, r.camera->target);
    EXPECT_FALSE(got.camera->up.has_value());
    EXPECT_EQ(got.camera->fov_y_deg, r.camera->fov_y_deg);
    EXPECT_EQ(got.camera->shutter_open, r.camera->shutter_open);
    EXPECT_EQ(got.camera->shutter_close, r.camera->shutter_close);
    EXPECT_EQ(got.time, r.time);  // the peers show the animated instances where this one does
}

}  // namespace
}  // namespace strata::server
