// BuildOptions::compact: every build is measured at full size, then rebuilt in Embree's compact
// layout. The report, the engine's compaction summary and the hits are checked against the same
// mesh built without compaction.

#include <gtest/gtest.h>

#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using test::instance_edit;
using test::mesh_edit;

const MeshBuildEntry& entry(const RebuildReport& r, const std::string& mesh) {
    for (const MeshBuildEntry& e : r.rebuilt)
        if (e.mesh == mesh) return e;
    ADD_FAILURE() << mesh << " was not rebuilt";
    static const MeshBuildEntry none;
    return none;
}

BuildOptions options(BuildPreference prefer, bool allow_refit, bool compact) {
    BuildOptions b;
    b.prefer = prefer;
    b.allow_refit = allow_refit;
    b.compact = compact;
    return b;
}

/// The three build setups of blas_store.h.
class CompactionSetups
    : public ::testing::TestWithParam<std::pair<BuildPreference, bool>> {
protected:
    BuildOptions with(bool compact) const {
        return options(GetParam().first, GetParam().second, compact);
    }
};

TEST_P(CompactionSetups, ACompactedBlasReportsItsFullSizeAndIsSmaller) {
    auto engine = test::make_engine();
    apply_ok(*engine, mesh_edit("full", make_sphere(1.0f, 160), with(false)),
             mesh_edit("small", make_sphere(1.0f, 160), with(true)),
             instance_edit("a", "full", {-1.5f, 0, 0}), instance_edit("b", "small", {1.5f, 0, 0}));
    const RebuildReport r = commit_ok(*engine);
    const MeshBuildEntry& full = entry(r, "full");
    const MeshBuildEntry& small = entry(r, "small");
    EXPECT_GT(full.bytes, 0);
    EXPECT_EQ(full.uncompacted_bytes, 0);
    // The first pass is the same build as the uncompacted mesh's (Embree's parallel builders
    // may allocate a little differently from run to run).
    EXPECT_NEAR(double(small.uncompacted_bytes), double(full.bytes), 0.1 * double(full.bytes));
    EXPECT_LT(double(small.bytes), 0.9 * double(small.uncompacted_bytes));
    EXPECT_GT(small.bytes, 0);

    EXPECT_EQ(r.compaction, (CompactionTotals{1, small.uncompacted_bytes, small.bytes}));
    const CompactionSummary summary = engine->compaction();
    ASSERT_EQ(summary.meshes.size(), 1u);
    EXPECT_EQ(summary.meshes[0].mesh, "small");
    EXPECT_EQ(summary.meshes[0].uncompacted_bytes, small.uncompacted_bytes);
    EXPECT_EQ(summary.meshes[0].bytes, small.bytes);
    EXPECT_EQ(summary.totals, r.compaction);
}

TEST_P(CompactionSetups, ACompactedBlasTracesTheSameHits) {
    auto plain = test::make_engine();
    auto compact = test::make_engine();
    for (auto [engine, on] : {std::pair{plain.get(), false}, std::pair{compact.get(), true}}) {
        MeshData sphere = make_sphere(1.0f, 48);
        // Off the pixel grid's symmetry, so no ray runs along an edge.
        for (Vec3& p : sphere.positions) p += Vec3(0.0031f * p.y, 0.0017f * p.z, 0.0023f * p.x);
        apply_ok(*engine, mesh_edit("m", std::move(sphere), with(on)),
                 mesh_edit("box", make_box(Vec3(1.0f)), with(on)),
                 instance_edit("a", "m", {-1.0f, 0.1f, 0}), instance_edit("b", "m", {1.2f, 0, 0.3f}),
                 instance_edit("c", "box", {0.1f, -1.3f, 0.2f}));
    }
    const test::HitFrame a = test::render(*plain, 0xFFFFFFFFu, nullptr, 96, 64);
    const test::HitFrame b = test::render(*compact, 0xFFFFFFFFu, nullptr, 96, 64);
    EXPECT_EQ(test::compare(a, b), "");
}

INSTANTIATE_TEST_SUITE_P(Builds, CompactionSetups,
                         ::testing::Values(std::pair{BuildPreference::FastTrace, true},
                                           std::pair{BuildPreference::FastTrace, false},
                                           std::pair{BuildPreference::FastBuild, false}),
                         [](const auto& p) {
                             return std::string(p.param.second ? "refit" : "no_refit_") +
                                    (p.param.second
                                         ? ""
                                         : build_preference_name(p.param.first));
                         });

TEST(Compaction, MovedVerticesRefitTheCompactedBlasInPlace) {
    auto engine = test::make_engine();
    const BuildOptions compact = options(BuildPreference::FastTrace, true, true);
    apply_ok(*engine, mesh_edit("m", make_sphere(1.0f, 64), compact), instance_edit("a", "m"));
    const RebuildReport built = commit_ok(*engine);

    MeshData moved = make_sphere(1.0f, 64);
    for (Vec3& p : moved.positions) p *= Vec3(1.2f, 0.9f, 1.0f);
    apply_ok(*engine, UpdateMeshPositions{"m", 0, moved.positions});
    const RebuildReport refit = commit_ok(*engine);
    EXPECT_EQ(refit.blas_rebuilds, 0u);
    EXPECT_EQ(refit.blas_refits, 1u);
    // Still the compact BVH: a refit neither grows it back nor measures it again.
    EXPECT_EQ(refit.compaction.uncompacted_bytes, built.compaction.uncompacted_bytes);
    EXPECT_LE(refit.compaction.bytes, built.compaction.bytes);

    // Its hits are a fresh compacted build's of the moved mesh.
    auto fresh = test::make_engine();
    apply_ok(*fresh, mesh_edit("m", std::move(moved), compact), instance_edit("a", "m"));
    EXPECT_EQ(test::compare(test::render(*engine, ~0u), test::render(*fresh, ~0u)), "");
}

TEST(Compaction, ARebuildMeasuresAgainAndARemovedMeshLeavesTheSummary) {
    auto engine = test::make_engine();
    const BuildOptions compact = options(BuildPreference::FastTrace, false, true);
    apply_ok(*engine, mesh_edit("m", make_sphere(1.0f, 32), compact),
             mesh_edit("n", make_sphere(1.0f, 32), compact), instance_edit("a", "m"));
    const RebuildReport first = commit_ok(*engine);
    EXPECT_EQ(first.compaction.meshes, 2u);

    // New topology, four times the triangles: both sizes are measured again and grow.
    ReplaceMeshTopology bigger;
    bigger.mesh = "m";
    MeshData data = make_sphere(1.0f, 64);
    bigger.positions = std::move(data.positions);
    bigger.triangles = std::move(data.triangles);
    apply_ok(*engine, bigger);
    const RebuildReport rebuilt = commit_ok(*engine);
    const MeshBuildEntry& m = entry(rebuilt, "m");
    EXPECT_GT(m.uncompacted_bytes, entry(first, "m").uncompacted_bytes * 2);
    EXPECT_GT(m.bytes, entry(first, "m").bytes * 2);
    EXPECT_LT(m.bytes, m.uncompacted_bytes);
    EXPECT_EQ(rebuilt.compaction.meshes, 2u);
    EXPECT_EQ(rebuilt.compaction.bytes, m.bytes + entry(first, "n").bytes);

    apply_ok(*engine, RemoveMesh{"n"});
    const RebuildReport removed = commit_ok(*engine);
    EXPECT_EQ(removed.compaction, (CompactionTotals{1, m.uncompacted_bytes, m.bytes}));
    ASSERT_EQ(engine->compaction().meshes.size(), 1u);
    EXPECT_EQ(engine->compaction().meshes[0].mesh, "m");

    // An instance move touches no BLAS: the summary is the same.
    UpdateInstance move;
    move.instance = "a";
    move.transform = Affine::translation({0, 1, 0});
    apply_ok(*engine, move);
    EXPECT_EQ(commit_ok(*engine).compaction, removed.compaction);
}

TEST(Compaction, ABigCompactedMeshIsBuiltWholeNeverAsClusters) {
    EngineConfig config;
    config.accel.clusters.min_triangles = 1000;
    auto created = test::create_engine(config);
    ASSERT_TRUE(created.has_value());
    Engine& engine = *created.value();
    const BuildOptions compact = options(BuildPreference::FastTrace, true, true);
    MeshData sphere = make_sphere(1.0f, 64);
    const std::size_t vertices = sphere.positions.size();
    apply_ok(engine, mesh_edit("m", std::move(sphere), compact),
             mesh_edit("c", make_sphere(1.0f, 64)), instance_edit("a", "m"));
    commit_ok(engine);
    // A local edit on each: the plain mesh is rebuilt as clusters, the compacted one refit.
    const Vec3 p = engine.read([](const Scene& s) { return s.mesh(s.find_mesh("m")).value()->positions[0]; });
    apply_ok(engine, UpdateMeshVertices{"m", {0}, {p * 1.01f}},
             UpdateMeshVertices{"c", {0}, {p * 1.01f}});
    const RebuildReport r = commit_ok(engine);
    ASSERT_EQ(r.rebuilt.size(), 1u);
    EXPECT_EQ(r.rebuilt[0].mesh, "c");
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Clustered);
    ASSERT_EQ(r.refit.size(), 1u);
    EXPECT_EQ(r.refit[0].mesh, "m");
    EXPECT_EQ(r.refit[0].clusters, 0u);
    EXPECT_GT(vertices, 1000u);
}

}  // namespace
}  // namespace strata
