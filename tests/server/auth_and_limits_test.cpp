// Bearer tokens, the loopback rule and request limits.

#include <cstdio>
#include <fstream>

#include <gmock/gmock.h>

#include "server/auth.h"
#include "server/cli.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

TEST(BearerToken, MatchesOnlyTheExactToken) {
    EXPECT_TRUE(bearer_token_matches("Bearer s3cret", "s3cret"));
    EXPECT_TRUE(bearer_token_matches("bearer s3cret", "s3cret"));
    EXPECT_FALSE(bearer_token_matches("Bearer s3cre", "s3cret"));
    EXPECT_FALSE(bearer_token_matches("Bearer s3cretx", "s3cret"));
    EXPECT_FALSE(bearer_token_matches("Basic s3cret", "s3cret"));
    EXPECT_FALSE(bearer_token_matches("", "s3cret"));
    EXPECT_FALSE(bearer_token_matches("Bearer ", ""));
}

TEST(TokenFile, IsTrimmedAndMustNotBeEmpty) {
    const std::string path = ::testing::TempDir() + "strata-token";
    std::ofstream(path) << "  abc123\n";
    EXPECT_EQ(read_token_file(path).value(), "abc123");
    std::ofstream(path) << " \n\t";
    EXPECT_FALSE(read_token_file(path).has_value());
    EXPECT_FALSE(read_token_file(path + "-missing").has_value());
    std::remove(path.c_str());
}

TEST(LoopbackRule, NonLoopbackNeedsATokenOrInsecure) {
    EXPECT_TRUE(is_loopback_host("127.0.0.1"));
    EXPECT_TRUE(is_loopback_host("127.1.2.3"));
    EXPECT_TRUE(is_loopback_host("::1"));
    EXPECT_TRUE(is_loopback_host("localhost"));
    EXPECT_FALSE(is_loopback_host("0.0.0.0"));
    EXPECT_FALSE(is_loopback_host("10.0.0.1"));
    EXPECT_FALSE(is_loopback_host("::"));

    CommandLine cl;
    cl.config.host = "0.0.0.0";
    EXPECT_THAT(finish_config(cl), ::testing::HasSubstr("--insecure"));
    cl.insecure = true;
    EXPECT_EQ(finish_config(cl), "");
}

class Auth : public ::testing::Test {
protected:
    static ServerConfig with_token() {
        ServerConfig c;
        c.token = "t0ken";
        return c;
    }
    TestServer srv{with_token()};
};

TEST_F(Auth, EveryEndpointButHealthNeedsTheToken) {
    for (const char* path :
         {"/v1/scene", "/v1/plan", "/v1/stats", "/metrics", "/v1/render?width=8&height=8",
          "/v1/scene/meshes/x", "/no-such-route"}) {
        const Reply r = srv.get(path);
        expect_problem(r, 401, "unauthorized");
        EXPECT_THAT(r.header("WWW-Authenticate"), ::testing::StartsWith("Bearer")) << path;
    }
    expect_problem(srv.edits({triangle_mesh("a")}), 401, "unauthorized");
    expect_problem(srv.post("/v1/commit", std::string()), 401, "unauthorized");
    expect_problem(srv.get("/v1/scene", {{"Authorization", "Bearer wrong"}}), 401, "unauthorized");
    EXPECT_EQ(srv.get("/livez").status, 200);
    EXPECT_EQ(srv.get("/readyz").status, 200);
    EXPECT_EQ(srv.engine().counters().batches_applied, 0u);
}

TEST_F(Auth, TheRightTokenIsLetThrough) {
    const httplib::Headers auth = {{"Authorization", "Bearer t0ken"}};
    EXPECT_EQ(srv.get("/v1/scene", auth).status, 200);
    EXPECT_EQ(srv.edits({triangle_mesh("a")}, auth).status, 200);
}

TEST(Limits, BodiesOverTheCapAre413) {
    ServerConfig c;
    c.max_body_bytes = 1024;
    TestServer srv(c);
    const std::string big = "{\"edits\": [], \"pad\": \"" + std::string(4096, 'x') + "\"}";
    expect_problem(srv.post("/v1/edits", big), 413, "too-large");
    // A body without Content-Length (chunked) is cut off at the cap too.
    auto client = srv.client();
    std::size_t sent = 0;
    auto r = client.Post(
        "/v1/edits",
        [&](size_t, httplib::DataSink& sink) {
            if (sent < 4096) {
                sink.write(big.data() + sent, 512);
                sent += 512;
            } else {
                sink.done();
            }
            return true;
        },
        "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 413);
    EXPECT_EQ(srv.edits({triangle_mesh("a")}).status, 200);
}

TEST(Limits, JsonDepthAndArrayLengthAreCapped) {
    ServerConfig c;
    c.max_json_depth = 8;
    c.max_array_elements = 100;
    TestServer srv(c);
    expect_problem(srv.post("/v1/edits", std::string(R"({"edits": [[[[[[[[[]]]]]]]]]})")), 400,
                   "nesting-too-deep");
    Json positions = Json::array();
    for (int i = 0; i < 300; ++i) positions.push_back(0);
    expect_problem(
        srv.edits(
            {{{"op", "add_mesh"}, {"id", "m"}, {"positions", positions}, {"indices", {0, 1, 2}}}}),
        413, "too-large");
}

}  // namespace
}  // namespace strata::server::test
