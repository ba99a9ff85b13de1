// Report JSON follows the contract of the issue: {"version", "tlas": {"action", "instances", "ms"},
// "blas_rebuilds", "blas_refits", "rebuilt": [{"mesh", "reason"}], "refit": [...],
// "primitives_built", "primitives_refit", "memory_bytes": {"blas", "tlas"}, "ms"}.

#include <gtest/gtest.h>

#include "protocol/report_json.h"

namespace strata::protocol {
namespace {

RebuildReport sample(bool planned) {
    RebuildReport r;
    r.version = 12;
    r.planned = planned;
    r.tlas_action = TlasAction::Update;
    r.tlas_instances = 3;
    r.rebuilt.push_back({"ball", BuildReason::TopologyChanged, "", 96, 1.5});
    r.refit.push_back({"flag", BuildReason::PositionsChanged, "", 32, 0.25});
    r.blas_rebuilds = 1;
    r.blas_refits = 1;
    r.primitives_built = 96;
    r.primitives_refit = 32;
    r.memory_blas_bytes = 1000;
    r.memory_tlas_bytes = 200;
    r.phases.total_ms = 2.0;
    r.phases.tlas_ms = 0.1;
    return r;
}

TEST(ReportJson, HasEveryContractMember) {
    const Json j = report_to_json(sample(false));
    EXPECT_EQ(j["version"], 12);
    EXPECT_EQ(j["tlas"]["action"], "update");
    EXPECT_EQ(j["tlas"]["instances"], 3);
    EXPECT_EQ(j["tlas"]["ms"], 0.1);
    EXPECT_EQ(j["blas_rebuilds"], 1);
    EXPECT_EQ(j["blas_refits"], 1);
    EXPECT_EQ(j["rebuilt"][0]["mesh"], "ball");
    EXPECT_EQ(j["rebuilt"][0]["reason"], "topology_changed");
    EXPECT_EQ(j["refit"][0]["mesh"], "flag");
    EXPECT_EQ(j["refit"][0]["reason"], "positions_changed");
    EXPECT_EQ(j["primitives_built"], 96);
    EXPECT_EQ(j["primitives_refit"], 32);
    EXPECT_EQ(j["memory_bytes"]["blas"], 1000);
    EXPECT_EQ(j["memory_bytes"]["tlas"], 200);
    EXPECT_EQ(j["ms"], 2.0);
}

TEST(ReportJson, AClusteredEntrySaysItsClustersAndAWholeOneDoesNot) {
    RebuildReport r = sample(false);
    MeshBuildEntry& e = r.refit[0];
    e.clusters = 553;
    e.clusters_refit = 16;
    e.clusters_rebuilt = 1;
    r.clusters_refit = 16;
    r.clusters_rebuilt = 1;
    const Json j = report_to_json(r);
    EXPECT_EQ(j["refit"][0]["clusters"], 553);
    EXPECT_EQ(j["refit"][0]["clusters_refit"], 16);
    EXPECT_EQ(j["refit"][0]["clusters_rebuilt"], 1);
    EXPECT_EQ(j["clusters_refit"], 16);
    EXPECT_EQ(j["clusters_rebuilt"], 1);
    EXPECT_FALSE(j["rebuilt"][0].contains("clusters"));
    EXPECT_FALSE(j["rebuilt"][0].contains("clusters_refit"));
}

TEST(ReportJson, TheTlasMemberShowsTheIncrementalTiersAndTheMerge) {
    RebuildReport r = sample(false);
    r.tlas.strategy = "incremental";
    r.tlas.static_instances = 1000;
    r.tlas.dynamic_instances = 3;
    r.tlas.stale_copies = 2;
    r.tlas.dynamic_array = true;
    r.tlas.merge_swapped = true;
    r.tlas.merge_build_ms = 42.5;
    r.tlas.merge_running = false;
    Json j = report_to_json(r)["tlas"];
    EXPECT_EQ(j["strategy"], "incremental");
    EXPECT_EQ(j["static_instances"], 1000);
    EXPECT_EQ(j["dynamic_instances"], 3);
    EXPECT_EQ(j["stale_copies"], 2);
    EXPECT_EQ(j["dynamic_array"], true);
    EXPECT_EQ(j["static_array"], false);
    EXPECT_EQ(j["merge"]["swapped"], true);
    EXPECT_EQ(j["merge"]["build_ms"], 42.5);
    EXPECT_EQ(j["merge"]["running"], false);
    EXPECT_FALSE(j["merge"].contains("cancelled"));
    EXPECT_FALSE(j.contains("static_rebuild"));

    r.tlas.merge_swapped = false;
    r.tlas.merge_cancelled = true;
    r.tlas.static_rebuild = "dynamic_tier_full";
    j = report_to_json(r)["tlas"];
    EXPECT_EQ(j["static_rebuild"], "dynamic_tier_full");
    EXPECT_FALSE(j["merge"].contains("build_ms"));
    EXPECT_EQ(j["merge"]["cancelled"], true);
}

TEST(ReportJson, ARebuildSaysItsBytesAndACompactedOneItsFullSizeToo) {
    RebuildReport r = sample(false);
    r.rebuilt[0].bytes = 800;
    r.rebuilt[0].uncompacted_bytes = 1200;
    r.compaction = {1, 1200, 800};
    Json j = report_to_json(r);
    EXPECT_EQ(j["rebuilt"][0]["bytes"], 800);
    EXPECT_EQ(j["rebuilt"][0]["uncompacted_bytes"], 1200);
    EXPECT_FALSE(j["refit"][0].contains("bytes"));
    EXPECT_EQ(j["memory_bytes"]["compaction"],
              Json({{"meshes", 1}, {"uncompacted_bytes", 1200}, {"bytes", 800},
                    {"saved_bytes", 400}}));
    r.rebuilt[0].uncompacted_bytes = 0;
    j = report_to_json(r);
    EXPECT_FALSE(j["rebuilt"][0].contains("uncompacted_bytes"));
    r.planned = true;
    EXPECT_FALSE(report_to_json(r)["rebuilt"][0].contains("bytes"));
}

TEST(ReportJson, APlanHasTheSameShapeWithoutTimes) {
    const Json plan = report_to_json(sample(true));
    const Json done = report_to_json(sample(false));
    EXPECT_TRUE(plan["planned"].get<bool>());
    EXPECT_FALSE(plan.contains("ms"));
    EXPECT_FALSE(plan["tlas"].contains("ms"));
    EXPECT_FALSE(plan["rebuilt"][0].contains("ms"));
    EXPECT_FALSE(plan.contains("phases"));
    for (const auto& [key, value] : plan.items()) EXPECT_TRUE(done.contains(key)) << key;
}

TEST(ReportJson, CountersUseTheEngineNames) {
    EngineCounters c;
    c.commits = 4;
    c.renders = 2;
    const Json j = counters_to_json(c);
    EXPECT_EQ(j["commits"], 4);
    EXPECT_EQ(j["renders"], 2);
    EXPECT_TRUE(j.contains("blas_rebuilds"));
}

}  // namespace
}  // namespace strata::protocol
