// The metric registry against what /metrics writes and what protocol/README.md documents. A stats
// field without a row does not compile (the static_asserts in server/metrics.cpp); here: every
// family the writer emits is a documented row of the registry, each row reads its own field, and
// a live server writes nothing the registry does not declare.
//
// After adding a metric, regenerate the README's table, then read the diff:
//   STRATA_UPDATE_DOCS=1 ctest --test-dir build -R MetricsRegistry

#include <regex>
#include <set>
#include <sstream>

#include <gmock/gmock.h>

#include "server/metrics.h"
#include "tests/generated_docs.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

const std::string README_PATH = STRATA_SOURCE_DIR "/protocol/README.md";

/// The families a Prometheus text declares (`# TYPE name type`).
std::set<std::string> declared_families(const std::string& text) {
    std::set<std::string> out;
    static const std::regex TYPE_LINE(R"(# TYPE (\S+) \S+)");
    for (std::sregex_iterator it(text.begin(), text.end(), TYPE_LINE), end; it != end; ++it)
        out.insert((*it)[1]);
    return out;
}

/// A snapshot in which every part of the server exists.
MetricsSnapshot full_snapshot(const FrontEndCounters& front_end) {
    MetricsSnapshot s;
    s.front_end = &front_end;
    s.durable = durable::DurableStats{};
    s.replica = replica::ReplicaStatus{};
    s.streams = StreamHubStats{};
    s.named_scenes = std::vector<NamedSceneMetrics>{{"city", 7, 3, 12, 4096}};
    s.commit_seconds = Histogram().counts();
    s.render_seconds = Histogram().counts();
    return s;
}

TEST(MetricsRegistry, TheReadmeTableIsTheOneTheRegistryGenerates) {
    const std::string readme = strata::test::read_text(README_PATH);
    const auto updated = strata::test::with_region(readme, "metrics", metrics_markdown_table());
    ASSERT_TRUE(updated) << "protocol/README.md lacks the metrics markers";
    if (strata::test::updating_docs()) {
        if (*updated != readme) strata::test::write_text(README_PATH, *updated);
        GTEST_SKIP() << "rewrote the metrics table of " << README_PATH;
    }
    EXPECT_TRUE(*updated == readme)
        << "protocol/README.md's metrics table is stale: run STRATA_UPDATE_DOCS=1 ctest "
           "--test-dir build -R MetricsRegistry";
}

TEST(MetricsRegistry, EveryFamilyIsWrittenOnceWithItsTypeAndHelp) {
    const FrontEndCounters front_end;
    const std::string text = prometheus_text(full_snapshot(front_end));
    std::set<std::string> names;
    for (const MetricFamily& f : metric_registry()) {
        EXPECT_TRUE(names.insert(f.name).second) << f.name << " is declared twice";
        EXPECT_THAT(f.name, ::testing::StartsWith("strata_"));
        EXPECT_FALSE(f.help.empty()) << f.name;
        EXPECT_NE(text.find("# HELP " + f.name + " "), std::string::npos) << f.name;
        if (f.type == MetricType::Counter) {
            EXPECT_THAT(f.name, ::testing::EndsWith("_total"));
        }
    }
    EXPECT_EQ(declared_families(text), names);
}

TEST(MetricsRegistry, FieldFamiliesReadTheirOwnField) {
    const FrontEndCounters front_end;
    MetricsSnapshot s = full_snapshot(front_end);
    // Distinct values in declaration order: a row reading another field would show another one.
    s.streams = StreamHubStats{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
    s.replica->applied_version = 41;
    s.replica->snapshot_version = 42;
    s.replica->entries_trimmed = 43;
    const std::string text = prometheus_text(s);
    for (const char* line :
         {"strata_stream_viewers 1\n", "strata_stream_event_clients 2\n", "strata_stream_views 3\n",
          "strata_stream_frames_sent_total 5\n", "strata_stream_commit_events_total 7\n",
          "strata_stream_renders_deferred_total 9\n", "strata_stream_frames_dropped_total 10\n",
          "strata_stream_held_bytes 12\n", "strata_replica_applied_version 41\n",
          "strata_replica_snapshot_version 42\n", "strata_replica_entries_trimmed_total 43\n",
          "strata_named_scenes 1\n", "strata_named_scene_version{scene=\"city\"} 7\n",
          "strata_named_scene_instances{scene=\"city\"} 3\n",
          "strata_named_scene_triangles{scene=\"city\"} 12\n",
          "strata_named_scene_blas_bytes{scene=\"city\"} 4096\n"})
        EXPECT_NE(text.find(line), std::string::npos) << line;
}

TEST(MetricsRegistry, PartsThatDoNotExistAreLeftOut) {
    const std::string text = prometheus_text(MetricsSnapshot{});
    EXPECT_NE(text.find("strata_batches_applied_total"), std::string::npos);
    EXPECT_NE(text.find("strata_http_responses_total{code=\"2xx\"} 0\n"), std::string::npos);
    for (const char* prefix :
         {"strata_http_connections", "strata_durable_", "strata_replica_", "strata_stream_",
          "strata_named_scene"})
        EXPECT_EQ(text.find(prefix), std::string::npos) << prefix;
}

TEST(MetricsRegistry, ALiveServerWritesOnlyDeclaredFamilies) {
    TestServer srv{ServerConfig{}, /*demo=*/true};
    const Reply r = srv.get("/metrics");
    ASSERT_EQ(r.status, 200);
    std::set<std::string> registry;
    for (const MetricFamily& f : metric_registry()) registry.insert(f.name);
    const std::set<std::string> written = declared_families(r.body);
    EXPECT_FALSE(written.empty());
    for (const std::string& name : written) EXPECT_TRUE(registry.count(name)) << name;
    // Every sample line belongs to a family declared before it.
    std::istringstream lines(r.body);
    std::string current;
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("# TYPE ", 0) == 0) current = line.substr(7, line.find(' ', 7) - 7);
        if (line.empty() || line[0] == '#') continue;
        EXPECT_EQ(line.rfind(current, 0), 0u) << line << " outside its family " << current;
    }
}

}  // namespace
}  // namespace strata::server::test
