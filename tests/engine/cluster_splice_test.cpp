// Local topology edits (ReplaceMeshTriangles): the dirty hull that maps the old numbering to the
// new, the scene rule, and what a commit rebuilds on a clustered BLAS (only the clusters that held
// the replaced triangles), checked against a fresh whole build of the same scene.

#include <algorithm>
#include <numeric>
#include <optional>
#include <random>

#include <gtest/gtest.h>

#include "tests/engine/cluster_fixtures.h"
#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::batch_of;
using test::clustered_config;
using test::make;

/// Checks `splices` against `now`, the triangles after the edits labelled by their number at the
/// last commit (-1: new): every triangle outside the runs is an old one, renumbered as
/// TriangleRenumbering says, every new one is inside a run, and the runs replaced exactly the old
/// triangles that are gone (and maybe some unchanged ones, which are inside a run too).
void expect_maps(const TriangleSplices& splices, const std::vector<int64_t>& now,
                 uint32_t committed) {
    ASSERT_LE(splices.runs().size(), TriangleSplices::MAX_RUNS);
    ASSERT_EQ(int64_t(committed) - int64_t(splices.old_count()) + int64_t(splices.new_count()),
              int64_t(now.size()));
    const TriangleRenumbering renumber(splices);
    std::vector<uint8_t> in_run(now.size(), 0);
    const std::vector<uint32_t> starts = splices.starts();
    for (std::size_t k = 0; k < starts.size(); ++k) {
        if (k > 0) ASSERT_LE(splices.runs()[k - 1].old_end, splices.runs()[k].old_first);
        for (uint32_t i = starts[k]; i < starts[k] + splices.runs()[k].count; ++i) in_run[i] = 1;
    }
    std::vector<uint8_t> kept(committed, 0);
    for (uint32_t i = 0; i < now.size(); ++i) {
        if (in_run[i]) continue;
        ASSERT_GE(now[i], 0) << "a new triangle outside the runs, at " << i;
        ASSERT_EQ(renumber(uint32_t(now[i])), std::optional<uint32_t>(i));
        kept[std::size_t(now[i])] = 1;
    }
    for (uint32_t old = 0; old < committed; ++old)
        ASSERT_EQ(renumber.replaced(old), !kept[old]) << old;
}

TEST(TriangleSplices, RunsMapTheTrianglesOfTheLastCommitToTheirNumbersNow) {
    std::mt19937 rng(3);
    for (int round = 0; round < 400; ++round) {
        std::vector<int64_t> now(50 + rng() % 400);
        std::iota(now.begin(), now.end(), 0);
        const auto committed = static_cast<uint32_t>(now.size());
        TriangleSplices splices;
        for (int e = 0, edits = 1 + int(rng() % 6); e < edits; ++e) {
            const auto n = uint32_t(now.size());
            const uint32_t removed = rng() % std::min<uint32_t>(n, 6);
            const uint32_t at = rng() % (n - removed + 1), inserted = rng() % 6;
            now.erase(now.begin() + at, now.begin() + at + removed);
            now.insert(now.begin() + at, inserted, -1);
            splices.add(at, removed, inserted);
        }
        SCOPED_TRACE("round " + std::to_string(round));
        expect_maps(splices, now, committed);
    }
}

TEST(TriangleSplices, PastTheRunCapTheClosestRunsMergeAndStillMapEveryTriangle) {
    // 2,000 single triangles cut out about 20 apart: more runs than the cap.
    std::vector<int64_t> now(50000);
    std::iota(now.begin(), now.end(), 0);
    TriangleSplices splices;
    for (uint32_t k = 0; k < 2000; ++k) {
        const uint32_t at = 20 * k + (k % 7);
        now.erase(now.begin() + at);
        splices.add(at, 1, 0);
    }
    EXPECT_EQ(splices.runs().size(), TriangleSplices::MAX_RUNS);
    EXPECT_EQ(splices.old_count() - splices.new_count(), 2000u);
    expect_maps(splices, now, 50000);
}

TEST(TriangleSplices, EditsThatOverlapOrTouchARunMergeIntoItAndUndoneInsertionsVanish) {
    TriangleSplices s;
    s.add(10, 2, 3);  // [10, 12) -> 3 new: numbers from 12 on move up by 1
    s.add(40, 0, 1);  // an insertion far away: its own run (39 at the last commit)
    ASSERT_EQ(s.runs().size(), 2u);
    EXPECT_EQ(s.runs()[1], (TriangleSplices::Run{39, 39, 1}));
    s.add(13, 1, 0);  // touches the first run's new triangles (10..12): merged
    ASSERT_EQ(s.runs().size(), 2u);
    EXPECT_EQ(s.runs()[0], (TriangleSplices::Run{10, 13, 3}));
    s.add(39, 1, 0);  // the far insertion removed again
    ASSERT_EQ(s.runs().size(), 1u);
}

/// A 100x100-quad grid whose triangles are numbered row by row (quad (x, z) holds triangles
/// 2 (100 z + x) and the next), so a run of triangles is a strip of rows.
MeshData row_grid() {
    MeshData m = make_plane(Vec3(8.0f, 0.0f, 8.0f), 100, 100);
    for (Vec3& p : m.positions) p.y = 0.3f * std::sin(p.x * 1.7f) * std::cos(p.z * 1.3f);
    return m;
}

/// Rows [z0, z1) of row_grid() with each quad cut along its other diagonal.
ReplaceMeshTriangles other_diagonal(uint32_t z0, uint32_t z1) {
    ReplaceMeshTriangles e{"g", 200 * z0, 200 * (z1 - z0), {}};
    for (uint32_t z = z0; z < z1; ++z) {
        for (uint32_t x = 0; x < 100; ++x) {
            const uint32_t a = z * 101 + x, b = a + 1, c = a + 101, d = c + 1;
            e.triangles.push_back({a, c, d});
            e.triangles.push_back({a, d, b});
        }
    }
    return e;
}

/// Hits of `engine` against a fresh whole build of its scene; empty when they agree.
std::string against_fresh(Engine& engine) {
    const test::HitFrame frame = test::render(engine, 0xFFFFFFFFu, nullptr, 96, 64);
    auto whole = make(clustered_config(0));
    EXPECT_TRUE(whole->apply(engine.read([](const Scene& s) { return s.to_batch(); })).has_value());
    return test::compare(frame, test::render(*whole, 0xFFFFFFFFu, nullptr, 96, 64));
}

std::unique_ptr<Engine> grid_engine() {
    auto engine = make(clustered_config(1024));
    test::apply_ok(*engine, test::mesh_edit("g", row_grid()), test::instance_edit("i", "g"),
                   SetCamera{Vec3(0, 7, 6), Vec3(0), Vec3(0, 1, 0), 60.0f});
    test::commit_ok(*engine);
    return engine;
}

TEST(ClusterSplice, TheFirstLocalTopologyEditClustersABigMeshAndLaterOnesRemakeOnlyTheirClusters) {
    auto engine = grid_engine();
    // The first: a whole BLAS has no part to rebuild, so the mesh is rebuilt as clusters.
    test::apply_ok(*engine, other_diagonal(40, 42));
    RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Clustered);
    EXPECT_NE(r.rebuilt[0].detail.find("400 triangles replaced by 400"), std::string::npos)
        << r.rebuilt[0].detail;
    const uint32_t clusters = r.rebuilt[0].clusters;
    ASSERT_GT(clusters, 40u);
    EXPECT_EQ(against_fresh(*engine), "");

    // The next: the clusters that held rows 60 and 61 are re-made, nothing else.
    test::apply_ok(*engine, other_diagonal(60, 62));
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    ASSERT_TRUE(r.rebuilt.empty());
    const MeshBuildEntry& e = r.refit[0];
    EXPECT_EQ(e.reason, BuildReason::TrianglesReplaced);
    EXPECT_EQ(e.clusters, clusters);
    EXPECT_GE(e.clusters_rebuilt, 1u);
    EXPECT_LE(e.clusters_rebuilt, clusters / 4) << "two rows of a hundred";
    EXPECT_EQ(e.clusters_refit, 0u);
    EXPECT_NE(e.detail.find("400 triangles replaced by 400"), std::string::npos) << e.detail;
    EXPECT_LT(e.primitives, 20000u / 4) << "the re-made clusters' triangles only";
    EXPECT_EQ(r.blas_rebuilds, 0u);
    EXPECT_EQ(against_fresh(*engine), "");
}

TEST(ClusterSplice, HolesAndInsertionsRenumberTheTrianglesAfterThemAndHitsStayExact) {
    auto engine = grid_engine();
    test::apply_ok(*engine, other_diagonal(10, 11));
    ASSERT_EQ(test::commit_ok(*engine).rebuilt.at(0).reason, BuildReason::Clustered);

    // A hole: rows 50 and 51 cut out. Every triangle after them moves down by 400.
    test::apply_ok(*engine, ReplaceMeshTriangles{"g", 10000, 400, {}});
    RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_EQ(r.refit[0].reason, BuildReason::TrianglesReplaced);
    EXPECT_EQ(against_fresh(*engine), "");
    EXPECT_EQ(engine->read([](const Scene& s) { return s.mesh_totals().triangles; }), 19600u);

    // An insertion in front of everything (count 0): all numbers move up; one at the end in the
    // same batch is a run of its own, so the two re-make a few clusters, not the mesh.
    ReplaceMeshTriangles front{"g", 0, 0, {{0, 101, 1}, {5, 106, 6}}};
    ReplaceMeshTriangles back{"g", 19602, 0, {{7, 108, 8}}};
    test::apply_ok(*engine, front, back);
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_EQ(r.refit[0].reason, BuildReason::TrianglesReplaced);
    EXPECT_LE(r.refit[0].clusters_rebuilt, 4u) << r.refit[0].detail;
    EXPECT_EQ(against_fresh(*engine), "");

    // A hole filled again and several edits in one batch, some far apart (one hull).
    ReplaceMeshTriangles fill = other_diagonal(50, 52);
    fill.first = 10002;
    fill.count = 0;
    test::apply_ok(*engine, fill, ReplaceMeshTriangles{"g", 30, 4, {{1, 102, 2}}},
                   ReplaceMeshTriangles{"g", 19000, 2, {}});
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_NE(r.refit[0].detail.find("6 triangles replaced by 401"), std::string::npos)
        << r.refit[0].detail;
    EXPECT_EQ(against_fresh(*engine), "");
}

TEST(ClusterSplice, AnEditOfMostOfTheMeshOrOneThatOverfillsAClusterReclustersIt) {
    auto engine = grid_engine();
    test::apply_ok(*engine, other_diagonal(10, 11));
    test::commit_ok(*engine);

    test::apply_ok(*engine, other_diagonal(0, 60));  // 12,000 of 20,000 triangles
    RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::TopologyChanged);
    EXPECT_NE(r.rebuilt[0].detail.find("not a local edit"), std::string::npos)
        << r.rebuilt[0].detail;
    EXPECT_GT(r.rebuilt[0].clusters, 0u) << "still clustered";
    EXPECT_EQ(against_fresh(*engine), "");

    // 3,000 copies of one small triangle: one cluster would take them all.
    ReplaceMeshTriangles pile{"g", 0, 0, std::vector<Triangle>(3000, Triangle(0, 101, 1))};
    test::apply_ok(*engine, pile);
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::TopologyChanged);
    EXPECT_NE(r.rebuilt[0].detail.find("would hold"), std::string::npos) << r.rebuilt[0].detail;
    EXPECT_EQ(against_fresh(*engine), "");
}

TEST(ClusterSplice, VertexEditsInTheSameBatchRefitTheOtherClustersAndReachTheNewTriangles) {
    auto engine = grid_engine();
    test::apply_ok(*engine, other_diagonal(10, 11));
    test::commit_ok(*engine);
    // New triangles (rows 30-31 re-cut) and their vertices lifted, with a dent elsewhere.
    UpdateMeshVertices lift{"g", {}, {}};
    const MeshData grid = row_grid();
    for (uint32_t v = 30 * 101; v < 32 * 101; ++v) {
        lift.vertices.push_back(v);
        lift.positions.push_back(grid.positions[v] + Vec3(0.0f, 0.2f, 0.0f));
    }
    for (uint32_t v = 70 * 101 + 20; v < 70 * 101 + 30; ++v) {
        lift.vertices.push_back(v);
        lift.positions.push_back(grid.positions[v] - Vec3(0.0f, 0.1f, 0.0f));
    }
    test::apply_ok(*engine, other_diagonal(30, 32), lift);
    RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_EQ(r.refit[0].reason, BuildReason::TrianglesReplaced);
    EXPECT_GE(r.refit[0].clusters_refit, 1u) << "the dent's clusters";
    EXPECT_EQ(against_fresh(*engine), "");

    // Later vertex edits find the new triangles' clusters (the vertex map learnt them).
    for (Vec3& p : lift.positions) p.y += 0.3f;
    test::apply_ok(*engine, lift);
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_EQ(r.refit[0].reason, BuildReason::PositionsChanged);
    EXPECT_EQ(against_fresh(*engine), "");
}

TEST(ReplaceMeshTriangles, RefusesBadRangesAndIndicesAndChangesNothing) {
    auto engine = make(clustered_config(1024));
    test::apply_ok(*engine, test::mesh_edit("m", make_box(Vec3(1.0f))),
                   test::instance_edit("i", "m"));
    test::commit_ok(*engine);
    const uint64_t version = engine->version();
    auto refused = [&](ReplaceMeshTriangles e, ErrorCode code, const std::string& field,
                       const std::string& words) {
        // Second in its batch, after a valid edit: the batch is atomic.
        auto r = engine->apply(batch_of({ReplaceMeshTriangles{"m", 0, 1, {{0, 1, 2}}}, e}));
        ASSERT_FALSE(r.has_value()) << words;
        EXPECT_EQ(r.error().code, code) << r.error().describe();
        EXPECT_EQ(r.error().field, field) << r.error().describe();
        EXPECT_EQ(r.error().edit_index, 1u);
        EXPECT_NE(r.error().message.find(words), std::string::npos) << r.error().message;
    };
    refused({"nope", 0, 0, {}}, ErrorCode::UnknownId, "mesh", "nope");
    refused({"m", 13, 0, {}}, ErrorCode::OutOfRange, "first", "past the end");
    refused({"m", 10, 3, {}}, ErrorCode::OutOfRange, "count", "10 to 12");
    refused({"m", 0, 1, {{0, 1, 2}, {0, 1, 8}}}, ErrorCode::OutOfRange, "indices/5",
            "uses vertex 8");
    refused({"m", 0, 12, {}}, ErrorCode::EmptyMesh, "indices", "no triangles");
    EXPECT_EQ(engine->version(), version);
    EXPECT_EQ(engine->read([](const Scene& s) { return s.mesh_totals().triangles; }), 12u);
}

TEST(ReplaceMeshTriangles, UndoPutsTheTrianglesBackAndTheHitsWithThem) {
    auto engine = grid_engine();
    const test::HitFrame original = test::render(*engine, 0xFFFFFFFFu, nullptr, 96, 64);
    test::apply_ok(*engine, ReplaceMeshTriangles{"g", 8000, 600, {{0, 101, 1}}});
    test::commit_ok(*engine);
    EXPECT_NE(test::compare(original, test::render(*engine, 0xFFFFFFFFu, nullptr, 96, 64)), "");
    auto undo = engine->undo_batch(engine->version());
    ASSERT_TRUE(undo.has_value()) << undo.error().describe();
    ASSERT_EQ(undo.value().edits.size(), 1u);
    const auto& back = std::get<ReplaceMeshTriangles>(undo.value().edits[0]);
    EXPECT_EQ(back.first, 8000u);
    EXPECT_EQ(back.count, 1u);
    EXPECT_EQ(back.triangles.size(), 600u) << "only the replaced triangles, not the mesh";
    ASSERT_TRUE(engine->apply(std::move(undo.value()), engine->version()).has_value());
    EXPECT_EQ(test::compare(original, test::render(*engine, 0xFFFFFFFFu, nullptr, 96, 64)), "");
}

}  // namespace
}  // namespace strata
