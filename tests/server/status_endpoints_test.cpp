// /v1/commit, /v1/plan, /v1/scene, /v1/stats, /metrics, /livez, /readyz and the 404 and 405
// answers.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <sstream>
#include <thread>

#include <gmock/gmock.h>

#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

class Status : public ::testing::Test {
protected:
    TestServer srv{ServerConfig{}, /*demo=*/true};
};

void expect_report_shape(const Json& r, bool planned) {
    for (const char* k : {"version", "tlas", "blas_rebuilds", "blas_refits", "rebuilt", "refit",
                          "primitives_built", "primitives_refit", "memory_bytes"})
        EXPECT_TRUE(r.contains(k)) << k << " in " << r.dump();
    EXPECT_TRUE(r["tlas"].contains("action"));
    EXPECT_TRUE(r["tlas"].contains("instances"));
    EXPECT_TRUE(r["memory_bytes"].contains("blas"));
    EXPECT_TRUE(r["memory_bytes"].contains("tlas"));
    EXPECT_EQ(r.contains("ms"), !planned);
    EXPECT_EQ(r["tlas"].contains("ms"), !planned);
}

TEST_F(Status, PlanShowsTheNextCommitAndCommitDoesIt) {
    const Reply plan = srv.get("/v1/plan");
    ASSERT_EQ(plan.status, 200);
    EXPECT_EQ(plan.header("ETag"), "\"1\"");
    expect_report_shape(plan.json(), true);
    EXPECT_EQ(plan.json()["blas_rebuilds"], 5);
    EXPECT_EQ(plan.json()["rebuilt"][0]["reason"], "added");

    const Reply commit = srv.post("/v1/commit", std::string());
    ASSERT_EQ(commit.status, 200) << commit.body;
    EXPECT_EQ(commit.header("ETag"), "\"1\"");
    const Json c = commit.json();
    expect_report_shape(c, false);
    EXPECT_EQ(c["tlas"]["action"], "update");
    EXPECT_EQ(c["tlas"]["instances"], 18);
    EXPECT_EQ(c["rebuilt"].size(), 5u);
    EXPECT_GT(c["memory_bytes"]["blas"].get<int64_t>(), 0);
    for (std::size_t i = 0; i < 5; ++i)
        EXPECT_EQ(c["rebuilt"][i]["mesh"], plan.json()["rebuilt"][i]["mesh"]);

    ASSERT_EQ(srv.edits({{{"op", "set_transform"},
                          {"instance", "crate-a"},
                          {"transform", {{"translate", {1, 0.5, 1}}}}}})
                  .status,
              200);
    EXPECT_EQ(srv.get("/v1/plan").json()["tlas"]["action"], "update");
    const Json second = srv.post("/v1/commit", std::string()).json();
    EXPECT_EQ(second["blas_rebuilds"], 0);
    EXPECT_EQ(second["tlas"]["action"], "update");
    EXPECT_EQ(srv.get("/v1/plan").json()["tlas"]["action"], "none");
}

/// Sends raw HTTP and returns the status line, for requests httplib's client would not send.
std::string raw_request(int port, const std::string& request) {
    std::string reply;
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(uint16_t(port));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0) {
        (void)::send(fd, request.data(), request.size(), 0);
        char buf[4096];
        const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
        if (n > 0) reply.assign(buf, std::size_t(n));
    }
    ::close(fd);
    return reply.substr(0, reply.find("\r\n"));
}

TEST_F(Status, APostWithoutContentLengthHasNoBodyAndDoesNotStall) {
    // What `curl -X POST` sends: no Content-Length, no Transfer-Encoding.
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(raw_request(srv.port(), "POST /v1/commit HTTP/1.1\r\nHost: x\r\n\r\n"),
              "HTTP/1.1 200 OK");
    EXPECT_EQ(raw_request(srv.port(), "POST /v1/render HTTP/1.1\r\nHost: x\r\n\r\n"),
              "HTTP/1.1 200 OK");
    EXPECT_EQ(raw_request(srv.port(), "POST /v1/scene HTTP/1.1\r\nHost: x\r\n\r\n"),
              "HTTP/1.1 405 Method Not Allowed");
    EXPECT_EQ(raw_request(srv.port(), "POST /nowhere HTTP/1.1\r\nHost: x\r\n\r\n"),
              "HTTP/1.1 404 Not Found");
    EXPECT_EQ(raw_request(srv.port(), "DELETE /nowhere HTTP/1.1\r\nHost: x\r\n\r\n"),
              "HTTP/1.1 404 Not Found");
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
    // An edit batch still needs its body.
    expect_problem(to_reply(srv.client().Post("/v1/edits")), 400, "malformed-json");
}

TEST_F(Status, SceneShowsCountsBoundsAndCamera) {
    const Reply r = srv.get("/v1/scene");
    ASSERT_EQ(r.status, 200);
    EXPECT_EQ(r.header("ETag"), "\"1\"");
    const Json j = r.json();
    EXPECT_EQ(j["version"], 1);
    for (const char* k : {"meshes", "instances", "materials", "triangles", "instanced_triangles"})
        EXPECT_TRUE(j["counts"].contains(k)) << k;
    EXPECT_EQ(j["counts"]["instances"], 18);
    EXPECT_EQ(j["bounds"]["min"].size(), 3u);
    EXPECT_EQ(j["camera"]["eye"].size(), 3u);
}

TEST_F(Status, UnknownObjectsAre404Problems) {
    expect_problem(srv.get("/v1/scene/meshes/nope"), 404, "not-found");
    expect_problem(srv.get("/v1/scene/instances/nope"), 404, "not-found");
    expect_problem(srv.get("/v1/scene/materials/nope"), 404, "not-found");
    EXPECT_EQ(srv.get("/v1/scene/meshes/ball").status, 200);
}

TEST_F(Status, StatsCarryCountersAndTheLastReport) {
    EXPECT_EQ(srv.get("/v1/stats").json()["last_report"], nullptr);
    srv.post("/v1/commit", std::string());
    const Reply r = srv.get("/v1/stats");
    ASSERT_EQ(r.status, 200);
    const Json j = r.json();
    EXPECT_EQ(j["counters"]["commits"], 1);
    EXPECT_EQ(j["counters"]["batches_applied"], 1);
    expect_report_shape(j["last_report"], false);
    EXPECT_EQ(r.header("ETag"), "\"1\"");
}

TEST_F(Status, ACompactedMeshShowsBothSizesInItsReportTheStatsAndItsDocument) {
    const Json sphere = {{"type", "sphere"}, {"radius", 1}, {"segments", 64}};
    ASSERT_EQ(srv.edits({{{"op", "add_mesh"},
                          {"id", "small"},
                          {"shape", sphere},
                          {"build", {{"compact", true}}}},
                         {{"op", "add_mesh"}, {"id", "full"}, {"shape", sphere}}})
                  .status,
              200);
    const Json c = srv.post("/v1/commit", std::string()).json();
    Json small, full;
    for (const Json& e : c["rebuilt"]) (e["mesh"] == "small" ? small : full) = e;
    ASSERT_TRUE(small.is_object() && full.is_object()) << c.dump();
    EXPECT_GT(full["bytes"].get<int64_t>(), 0);
    EXPECT_FALSE(full.contains("uncompacted_bytes"));
    const int64_t before = small["uncompacted_bytes"].get<int64_t>();
    const int64_t after = small["bytes"].get<int64_t>();
    EXPECT_LT(after, before);
    const Json totals = {{"meshes", 1},
                         {"uncompacted_bytes", before},
                         {"bytes", after},
                         {"saved_bytes", before - after}};
    EXPECT_EQ(c["memory_bytes"]["compaction"], totals);

    Json stats = srv.get("/v1/stats").json()["memory_bytes"]["compaction"];
    const Json per_mesh = stats["per_mesh"];
    stats.erase("per_mesh");
    EXPECT_EQ(stats, totals);
    EXPECT_EQ(per_mesh, Json::array({{{"mesh", "small"},
                                      {"uncompacted_bytes", before},
                                      {"bytes", after}}}));
    EXPECT_EQ(srv.get("/v1/scene/meshes/small").json()["build"]["compact"], true);
    EXPECT_EQ(srv.get("/v1/scene/meshes/full").json()["build"]["compact"], false);
    // The plan shows what is held now.
    EXPECT_EQ(srv.get("/v1/plan").json()["memory_bytes"]["compaction"], totals);

    ASSERT_EQ(srv.edits({{{"op", "remove_mesh"}, {"mesh", "small"}}}).status, 200);
    srv.post("/v1/commit", std::string());
    stats = srv.get("/v1/stats").json()["memory_bytes"]["compaction"];
    EXPECT_EQ(stats["meshes"], 0);
    EXPECT_EQ(stats["per_mesh"], Json::array());
}

TEST_F(Status, AGroupHasItsSubtreesBoundsAndARenderCanFrameIt) {
    ASSERT_EQ(srv.edits({{{"op", "add_group"}, {"id", "spot"}},
                         {{"op", "add_instance"},
                          {"id", "spot-ball"},
                          {"mesh", "ball"},
                          {"parent", "spot"},
                          {"transform", {{"translate", {30, 0, 0}}}}}})
                  .status,
              200);
    const Json spot = srv.get("/v1/scene/groups/spot").json();
    ASSERT_TRUE(spot["bounds"].is_object()) << spot.dump();
    const Json listed = srv.get("/v1/scene/groups").json();
    for (const Json& g : listed["items"]) EXPECT_FALSE(g.contains("bounds")) << g.dump();

    EXPECT_EQ(srv.get("/v1/render?width=16&height=16&frame_group=spot").status, 200);
    EXPECT_EQ(srv.get("/v1/render?width=16&height=16&frame_instance=spot-ball").status, 200);
    const Reply unknown = srv.get("/v1/render?width=16&height=16&frame_group=nope");
    EXPECT_EQ(unknown.status, 422);
    EXPECT_EQ(unknown.json()["pointer"], "/frame/group");
    const Reply both = srv.get("/v1/render?width=16&height=16&frame_group=spot&eye=1,2,3");
    EXPECT_EQ(both.status, 400);
    EXPECT_EQ(both.json()["pointer"], "/camera");
    // The stream renders no framed frames: an unknown parameter there.
    EXPECT_EQ(srv.get("/v1/stream?frame_group=spot").status, 400);
}

TEST_F(Status, MetricsArePrometheusText) {
    srv.post("/v1/render", Json{{"width", 16}, {"height", 16}});
    srv.get("/nothing-here");
    // The access-log hook counts a response after sending it: give it a moment.
    Reply r;
    for (int i = 0; i < 100; ++i) {
        r = srv.get("/metrics");
        if (r.body.find("strata_http_responses_total{code=\"4xx\"} 1\n") != std::string::npos)
            break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_EQ(r.status, 200);
    EXPECT_THAT(r.header("Content-Type"), ::testing::StartsWith("text/plain; version=0.0.4"));
    EXPECT_THAT(r.body, ::testing::HasSubstr(
                            "# TYPE strata_commits_total counter\nstrata_commits_total 1\n"));
    EXPECT_THAT(r.body, ::testing::HasSubstr("strata_renders_total 1\n"));
    EXPECT_THAT(r.body, ::testing::HasSubstr("# TYPE strata_commit_duration_seconds histogram"));
    EXPECT_THAT(r.body, ::testing::HasSubstr("strata_render_duration_seconds_count 1\n"));
    EXPECT_THAT(r.body,
                ::testing::HasSubstr("strata_render_duration_seconds_bucket{le=\"+Inf\"} 1\n"));
    EXPECT_THAT(r.body, ::testing::HasSubstr("strata_http_responses_total{code=\"4xx\"} 1\n"));
    // Every sample line is "name{labels} value" or "name value".
    std::istringstream lines(r.body);
    for (std::string line; std::getline(lines, line);) {
        if (line.empty() || line[0] == '#') continue;
        EXPECT_THAT(line,
                    ::testing::MatchesRegex("strata_[a-z_]+(\\{[a-z]+=\"[^\"]+\"\\})? [-+0-9.e]+"))
            << line;
    }
}

TEST_F(Status, HealthEndpointsAnswer) {
    EXPECT_EQ(srv.get("/livez").status, 200);
    EXPECT_EQ(srv.get("/readyz").status, 200);
}

TEST_F(Status, UnknownRoutesAre404AndWrongMethods405WithAllow) {
    expect_problem(srv.get("/v2/scene"), 404, "not-found");
    const Reply r = srv.get("/v1/edits");
    expect_problem(r, 405, "method-not-allowed");
    EXPECT_EQ(r.header("Allow"), "POST");
    auto c = srv.client();
    const Reply del = to_reply(c.Delete("/v1/scene"));
    expect_problem(del, 405, "method-not-allowed");
    EXPECT_EQ(del.header("Allow"), "GET, HEAD");
    const Reply put = to_reply(c.Put("/v1/render", "{}", "application/json"));
    EXPECT_EQ(put.header("Allow"), "GET, POST, HEAD");
}

}  // namespace
}  // namespace strata::server::test
