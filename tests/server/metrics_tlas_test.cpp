// The incremental TLAS's tiers in /metrics (strata_tlas_instances{tier}, strata_tlas_stale_copies,
// strata_tlas_merge_running) after moves, compared with known counts and with the rebuild report
// /v1/stats holds for the same commit.

#include <chrono>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

constexpr int INSTANCES = 2000;  // above TlasPolicy::min_instances: the dynamic tier is used

/// The value of the sample line `name` ("metric{labels}") in Prometheus text, if present.
std::optional<double> sample(const std::string& text, const std::string& name) {
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        if (line.size() > name.size() && line.compare(0, name.size(), name) == 0 &&
            line[name.size()] == ' ')
            return std::stod(line.substr(name.size() + 1));
    }
    return std::nullopt;
}

/// The TLAS gauges of one /metrics answer.
struct TlasGauges {
    double static_instances = -1, dynamic_instances = -1, stale_copies = -1, merge_running = -1;
};

class MetricsTlas : public ::testing::Test {
protected:
    static EngineConfig engine_config(bool merges) {
        EngineConfig c;
        c.accel.tlas = TlasKind::Incremental;
        c.accel.tlas_policy.background_merge = merges;
        return c;
    }

    void add_instances(TestServer& srv) {
        Json edits = Json::array();
        edits.push_back({{"op", "add_mesh"}, {"id", "box"}, {"shape", {{"type", "box"}}}});
        for (int i = 0; i < INSTANCES; ++i)
            edits.push_back(
                {{"op", "add_instance"},
                 {"id", "i" + std::to_string(i)},
                 {"mesh", "box"},
                 {"transform", {{"translate", {(i % 50) * 2.0, 0.0, (i / 50) * 2.0}}}}});
        ASSERT_EQ(srv.post("/v1/edits", Json{{"edits", edits}}).status, 200);
    }

    static void move(TestServer& srv, int first, int count, double y) {
        Json edits = Json::array();
        for (int i = first; i < first + count; ++i)
            edits.push_back({{"op", "set_transform"},
                             {"instance", "i" + std::to_string(i)},
                             {"transform", {{"translate", {0.0, y, double(i)}}}}});
        ASSERT_EQ(srv.post("/v1/edits", Json{{"edits", edits}}).status, 200);
    }

    static Json commit(TestServer& srv) {
        const Reply r = srv.post("/v1/commit", std::string());
        EXPECT_EQ(r.status, 200) << r.body;
        return r.json();
    }

    /// /metrics' gauges, checked against /v1/stats' last report (the same commit's).
    static TlasGauges gauges(TestServer& srv) {
        const Reply m = srv.get("/metrics");
        EXPECT_EQ(m.status, 200);
        TlasGauges g;
        auto read = [&](const char* name, double& out) {
            const auto v = sample(m.body, name);
            EXPECT_TRUE(v.has_value()) << "no " << name << " in\n" << m.body;
            out = v.value_or(-1);
        };
        read("strata_tlas_instances{tier=\"static\"}", g.static_instances);
        read("strata_tlas_instances{tier=\"dynamic\"}", g.dynamic_instances);
        read("strata_tlas_stale_copies", g.stale_copies);
        read("strata_tlas_merge_running", g.merge_running);
        const Json tlas = srv.get("/v1/stats").json()["last_report"]["tlas"];
        EXPECT_EQ(g.static_instances, tlas["static_instances"].get<double>());
        EXPECT_EQ(g.dynamic_instances, tlas["dynamic_instances"].get<double>());
        EXPECT_EQ(g.stale_copies, tlas["stale_copies"].get<double>());
        EXPECT_EQ(g.merge_running, tlas["merge"]["running"].get<bool>() ? 1.0 : 0.0);
        return g;
    }
};

TEST_F(MetricsTlas, GaugesFollowTheTiersAfterEveryCommit) {
    TestServer srv({}, false, engine_config(false));
    add_instances(srv);
    commit(srv);
    TlasGauges g = gauges(srv);
    EXPECT_EQ(g.static_instances, INSTANCES);
    EXPECT_EQ(g.dynamic_instances, 0);
    EXPECT_EQ(g.stale_copies, 0);
    EXPECT_EQ(g.merge_running, 0);

    move(srv, 0, 10, 1.0);
    commit(srv);
    g = gauges(srv);
    EXPECT_EQ(g.static_instances, INSTANCES);
    EXPECT_EQ(g.dynamic_instances, 10);
    EXPECT_EQ(g.stale_copies, 10);
    EXPECT_EQ(g.merge_running, 0) << "merges are off";

    // Five of the same instances again and five new ones: the tier holds each once.
    move(srv, 5, 10, 2.0);
    ASSERT_EQ(srv.post("/v1/render", Json{{"width", 8}, {"height", 8}}).status, 200);
    g = gauges(srv);  // the render's commit is the last one
    EXPECT_EQ(g.dynamic_instances, 15);
    EXPECT_EQ(g.stale_copies, 15);

    // A commit with nothing to do leaves the gauges where they were.
    commit(srv);
    g = gauges(srv);
    EXPECT_EQ(g.dynamic_instances, 15);
    EXPECT_EQ(g.static_instances, INSTANCES);
}

TEST_F(MetricsTlas, AMergeEmptiesTheDynamicTierAndTheGaugesSayIt) {
    TestServer srv({}, false, engine_config(true));
    add_instances(srv);
    commit(srv);
    move(srv, 100, 20, 1.0);
    commit(srv);  // starts a background merge
    TlasGauges g = gauges(srv);
    EXPECT_EQ(g.dynamic_instances, 20);
    EXPECT_EQ(g.stale_copies, 20);
    // The next commit after the merge finishes swaps it in (no scene change needed).
    bool swapped = false;
    for (int i = 0; i < 500 && !swapped; ++i) {
        const Json report = commit(srv);
        swapped = report["tlas"]["merge"]["swapped"].get<bool>();
        if (!swapped) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ASSERT_TRUE(swapped) << "no merge was swapped in within 5 s";
    g = gauges(srv);
    EXPECT_EQ(g.static_instances, INSTANCES);
    EXPECT_EQ(g.dynamic_instances, 0);
    EXPECT_EQ(g.stale_copies, 0);
    EXPECT_EQ(g.merge_running, 0);
    const Reply m = srv.get("/metrics");
    EXPECT_EQ(sample(m.body, "strata_tlas_merges_total"), 1.0);
}

}  // namespace
}  // namespace strata::server::test
