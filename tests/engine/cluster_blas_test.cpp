// Clustered BLASes (engine/accel/cluster_layout.h, clustered_blas.h): the layout's bookkeeping,
// the dirty vertex ranges it reads, what a commit reports, and a differential test against a
// fresh monolithic build of the same meshes.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "engine/accel/cluster_layout.h"
#include "engine/scene/vertex_ranges.h"
#include "tests/engine/cluster_fixtures.h"
#include "tests/engine/hit_frames.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using Range = VertexRanges::Range;
using test::batch_of;
using test::bumpy_grid;
using test::clustered_config;
using test::committed_grid;
using test::make;

std::vector<Range> ranges_of(const VertexRanges& r) { return {r.ranges().begin(), r.ranges().end()}; }

TEST(VertexRanges, MergesOverlappingAndTouchingRanges) {
    VertexRanges r;
    r.add(10, 20);
    r.add(30, 40);
    r.add(5, 5);  // empty: nothing
    EXPECT_EQ(ranges_of(r), (std::vector<Range>{{10, 20}, {30, 40}}));
    r.add(20, 25);  // touches the first
    EXPECT_EQ(ranges_of(r), (std::vector<Range>{{10, 25}, {30, 40}}));
    r.add(24, 31);  // bridges both
    EXPECT_EQ(ranges_of(r), (std::vector<Range>{{10, 40}}));
    r.add(0, 3);
    r.add(50, 60);
    EXPECT_EQ(ranges_of(r), (std::vector<Range>{{0, 3}, {10, 40}, {50, 60}}));
    EXPECT_EQ(r.count(), 3u + 30u + 10u);
    EXPECT_EQ(r.begin(), 0u);
    EXPECT_EQ(r.end(), 60u);
}

TEST(VertexRanges, StaysShortByMergingTheClosestRangesAndNeverLosesAVertex) {
    VertexRanges r;
    std::set<uint32_t> written;
    std::mt19937 rng(7);
    for (int i = 0; i < 500; ++i) {
        const uint32_t begin = rng() % 100000, end = begin + 1 + rng() % 20;
        r.add(begin, end);
        for (uint32_t v = begin; v < end; ++v) written.insert(v);
        ASSERT_LE(r.ranges().size(), VertexRanges::MAX_RANGES);
    }
    for (std::size_t i = 0; i + 1 < r.ranges().size(); ++i)
        EXPECT_LT(r.ranges()[i].end, r.ranges()[i + 1].begin) << "sorted, disjoint, apart";
    for (uint32_t v : written) {
        const bool covered = std::any_of(r.ranges().begin(), r.ranges().end(),
                                         [&](const Range& x) { return x.begin <= v && v < x.end; });
        ASSERT_TRUE(covered) << "vertex " << v;
    }
}

TEST(ClusterLayout, EveryTriangleInOneClusterAndEveryVertexMapsToTheClustersUsingIt) {
    const MeshData m = bumpy_grid(40, 30, 1);
    const ClusterLayout layout(m.positions, m.triangles, 64);
    ASSERT_GE(layout.cluster_count(), (m.triangles.size() + 63) / 64);
    ASSERT_LE(layout.cluster_count(), 4 * ((m.triangles.size() + 63) / 64)) << "pieces merged";
    for (uint32_t c = 0; c < layout.cluster_count(); ++c) ASSERT_LE(layout.size(c), 64u);
    std::vector<uint32_t> seen(m.triangles.size(), 0);
    std::vector<std::set<uint32_t>> users(m.positions.size());
    for (uint32_t c = 0; c < layout.cluster_count(); ++c) {
        for (uint32_t prim = 0; prim < layout.size(c); ++prim) {
            const uint32_t t = layout.mesh_triangle(c, prim);
            ++seen[t];
            for (int k = 0; k < 3; ++k) users[m.triangles[t][k]].insert(c);
        }
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](uint32_t n) { return n == 1; }));
    for (uint32_t v = 0; v < m.positions.size(); ++v) {
        std::vector<uint32_t> got;
        layout.for_each_cluster_of(v, [&](uint32_t c) { got.push_back(c); });
        EXPECT_EQ(std::set<uint32_t>(got.begin(), got.end()), users[v]) << "vertex " << v;
        EXPECT_TRUE(std::is_sorted(got.begin(), got.end()));
        EXPECT_EQ(got.size(), users[v].size()) << "each cluster once";
    }
    // touched(): exactly the union over the vertices in the ranges.
    VertexRanges r;
    r.add(100, 140);
    r.add(700, 705);
    std::set<uint32_t> expect;
    for (uint32_t v : {100u, 700u})
        for (uint32_t w = v; w < v + (v == 100 ? 40u : 5u); ++w) expect.insert(users[w].begin(), users[w].end());
    const std::vector<uint32_t> touched = layout.touched(r);
    EXPECT_EQ(std::set<uint32_t>(touched.begin(), touched.end()), expect);
    EXPECT_LT(touched.size(), layout.cluster_count() / 2) << "a local edit touches few clusters";
}

TEST(ClusterLayout, ClustersAreCompactPatches) {
    // Morton order: the clusters' boxes together cover little more than the mesh, where
    // clusters of the shuffled client order would each span nearly the whole grid.
    const MeshData m = bumpy_grid(64, 64, 2);
    const ClusterLayout layout(m.positions, m.triangles, 128);
    std::vector<Triangle> sorted(m.triangles.size());
    layout.write_sorted(m.triangles, sorted.data());
    double sorted_area = 0.0, naive_area = 0.0;
    for (uint32_t c = 0; c < layout.cluster_count(); ++c) {
        sorted_area += double(ClusterLayout::measure(m.positions, sorted.data() + layout.first(c),
                                                     layout.size(c))
                                  .bounds.surface_area());
        Bounds3 naive;
        for (uint32_t k = layout.first(c); k < layout.first(c) + layout.size(c); ++k)
            for (int i = 0; i < 3; ++i) naive.extend(m.positions[m.triangles[k][i]]);
        naive_area += double(naive.surface_area());
    }
    EXPECT_LT(sorted_area * 10.0, naive_area);
}

// ---- the engine with clustered BLASes ----

TEST(UpdateMeshVertices, MovesTheListedVerticesAndIsAtomicAndUndoable) {
    auto engine = make(clustered_config(1024));
    MeshData grid = bumpy_grid(10, 10, 8);
    const std::vector<Vec3> before = grid.positions;
    test::apply_ok(*engine, test::mesh_edit("g", std::move(grid)));
    auto positions = [&] {
        return engine->read([](const Scene& s) {
            return std::vector<Vec3>(s.mesh(s.find_mesh("g")).value()->positions.begin(),
                                     s.mesh(s.find_mesh("g")).value()->positions.end());
        });
    };
    // Listed twice: the last position wins.
    test::apply_ok(*engine, UpdateMeshVertices{"g", {7, 3, 7}, {{0, 1, 0}, {0, 2, 0}, {0, 3, 0}}});
    std::vector<Vec3> expect = before;
    expect[3] = {0, 2, 0};
    expect[7] = {0, 3, 0};
    EXPECT_EQ(positions(), expect);

    // A vertex outside the mesh: refused with the index named, nothing changed.
    EditBatch bad;
    bad.edits.emplace_back(UpdateMeshVertices{"g", {5, 9}, {{9, 9, 9}, {9, 9, 9}}});
    bad.edits.emplace_back(UpdateMeshVertices{"g", {1, 121}, {{9, 9, 9}, {9, 9, 9}}});
    auto r = engine->apply(std::move(bad));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::OutOfRange);
    EXPECT_EQ(r.error().edit_index, 1u);
    EXPECT_EQ(r.error().field, "vertices/1");
    EXPECT_EQ(positions(), expect) << "the batch's first edit was rolled back (in reverse order)";

    // Counts that differ, no vertices, a NaN.
    r = engine->apply(batch_of({UpdateMeshVertices{"g", {1, 2}, {{0, 0, 0}}}}));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().field, "positions");
    r = engine->apply(batch_of({UpdateMeshVertices{"g", {}, {}}}));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().field, "vertices");
    r = engine->apply(batch_of({UpdateMeshVertices{"g", {1}, {{0, std::nanf(""), 0}}}}));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::NotFinite);
    EXPECT_EQ(positions(), expect);
}

TEST(UpdateMeshVertices, ABrushStrokeRefitsOnlyTheClustersAlongIt) {
    auto [engine, positions, added] = committed_grid(9);
    // A diagonal stroke of 30 vertices: 30 ranges, in one edit.
    UpdateMeshVertices stroke;
    stroke.mesh = "g";
    for (uint32_t k = 30; k < 60; ++k) {
        const uint32_t v = k * 101 + k;
        positions[v].y += 0.05f;
        stroke.vertices.push_back(v);
        stroke.positions.push_back(positions[v]);
    }
    ASSERT_TRUE(engine->apply(batch_of({stroke})).has_value());
    RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Clustered);
    const uint32_t clusters = r.rebuilt[0].clusters;
    stroke.positions[0].y += 0.05f;
    ASSERT_TRUE(engine->apply(batch_of({stroke})).has_value());
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_GE(r.refit[0].clusters_refit, 2u);
    EXPECT_LE(r.refit[0].clusters_refit, clusters / 3) << "a stroke across a third of the grid";
}

/// A dent in a 101x101-vertex grid: `rows` rows of ten vertices from (40, 40), one edit per row.
EditBatch dent(std::vector<Vec3>& positions, uint32_t rows, float depth) {
    std::vector<Edit> edits;
    for (uint32_t row = 40; row < 40 + rows; ++row) {
        UpdateMeshPositions e;
        e.mesh = "g";
        e.offset = row * 101 + 40;
        for (uint32_t v = e.offset; v < e.offset + 10; ++v) {
            positions[v].y -= depth;
            e.positions.push_back(positions[v]);
        }
        edits.emplace_back(std::move(e));
    }
    return batch_of(std::move(edits));
}

TEST(ClusteredBlas, TheFirstLocalEditClustersABigMeshAndLaterOnesRefitOnlyWhatTheyTouch) {
    auto [engine, positions, added] = committed_grid(3);  // clusters of at most 282 triangles
    ASSERT_EQ(added.rebuilt.size(), 1u);
    EXPECT_EQ(added.rebuilt[0].clusters, 0u) << "built whole until edited locally";

    // The first dent: rebuilt as clusters.
    ASSERT_TRUE(engine->apply(dent(positions, 5, 0.1f)).has_value());
    const RebuildReport first = test::commit_ok(*engine);
    ASSERT_EQ(first.rebuilt.size(), 1u) << first.summary();
    EXPECT_EQ(first.rebuilt[0].reason, BuildReason::Clustered);
    EXPECT_NE(first.rebuilt[0].detail.find("50 of 10201 vertices in edited ranges"), std::string::npos)
        << first.rebuilt[0].detail;
    const uint32_t clusters = first.rebuilt[0].clusters;
    EXPECT_GE(clusters, (20000u + 281u) / 282u);
    EXPECT_LE(clusters, 4 * (20000u + 281u) / 282u);
    EXPECT_EQ(first.rebuilt[0].clusters_rebuilt, clusters);
    EXPECT_EQ(first.clusters_rebuilt, clusters);

    // The next dent (five rows: five ranges in one batch) refits a few clusters.
    ASSERT_TRUE(engine->apply(dent(positions, 5, 0.1f)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u);
    const MeshBuildEntry& e = r.refit[0];
    EXPECT_EQ(e.reason, BuildReason::PositionsChanged);
    EXPECT_EQ(e.clusters, clusters);
    EXPECT_GE(e.clusters_refit, 1u);
    EXPECT_LE(e.clusters_refit, 8u) << "a 5x10 patch touches a few clusters, not " << clusters;
    EXPECT_EQ(e.clusters_rebuilt, 0u);
    EXPECT_EQ(r.clusters_refit, e.clusters_refit);
    EXPECT_LT(r.primitives_refit, 8u * 282u);
    EXPECT_EQ(engine->counters().clusters_refit, e.clusters_refit);
    EXPECT_EQ(engine->counters().clusters_rebuilt, clusters);
}

TEST(ClusteredBlas, AMeshMovedWholeStaysWhole) {
    auto [engine, positions, added] = committed_grid(3);
    UpdateMeshPositions all;
    all.mesh = "g";
    all.positions = positions;
    for (Vec3& p : all.positions) p.y += 0.01f;
    ASSERT_TRUE(engine->apply(batch_of({all})).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_EQ(r.refit[0].clusters, 0u);
    EXPECT_EQ(r.refit[0].primitives, 20000u);
}

TEST(ClusteredBlas, AStretchedClusterIsRebuiltAndAnExplodedMeshReclustered) {
    auto [engine, positions, added] = committed_grid(4);
    ASSERT_TRUE(engine->apply(dent(positions, 1, 0.01f)).has_value());
    ASSERT_EQ(test::commit_ok(*engine).clusters_rebuilt > 0, true) << "clustered";

    // One vertex pulled far out: its clusters' triangles stretch past the policy's limit.
    UpdateMeshPositions pull;
    pull.mesh = "g";
    pull.offset = 5050;
    pull.positions = {positions[5050] + Vec3(0.0f, 6.0f, 0.0f)};
    ASSERT_TRUE(engine->apply(batch_of({pull})).has_value());
    RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size(), 1u) << r.summary();
    EXPECT_GE(r.refit[0].clusters_rebuilt, 1u);
    EXPECT_EQ(r.refit[0].clusters_refit, 0u);
    EXPECT_NE(r.refit[0].detail.find("clusters rebuilt"), std::string::npos) << r.refit[0].detail;

    // Everything scaled up: the clusters' boxes together grow past the limit: a new layout.
    UpdateMeshPositions all;
    all.mesh = "g";
    all.positions = positions;
    for (Vec3& p : all.positions) p *= 3.0f;
    ASSERT_TRUE(engine->apply(batch_of({all})).has_value());
    r = test::commit_ok(*engine);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::BoundsGrowth);
    EXPECT_NE(r.rebuilt[0].detail.find("clusters'"), std::string::npos) << r.rebuilt[0].detail;
}

TEST(ClusteredBlas, SmallMeshesAndMeshesThatForbidRefitStayWhole) {
    auto engine = make(clustered_config(1024));
    BuildOptions no_refit;
    no_refit.allow_refit = false;
    test::apply_ok(*engine, test::mesh_edit("small", bumpy_grid(10, 10, 5)),
                   test::mesh_edit("rigid", bumpy_grid(100, 100, 6), no_refit),
                   test::instance_edit("a", "small"), test::instance_edit("b", "rigid"));
    test::commit_ok(*engine);
    UpdateMeshPositions small, rigid;
    small.mesh = "small";
    small.positions = {Vec3(0.0f)};
    rigid.mesh = "rigid";
    rigid.offset = 500;
    rigid.positions = {Vec3(0.0f)};
    ASSERT_TRUE(engine->apply(batch_of({small, rigid})).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    ASSERT_EQ(r.refit.size() + r.rebuilt.size(), 2u) << r.summary();
    for (const MeshBuildEntry& e : r.refit) EXPECT_EQ(e.clusters, 0u) << e.mesh;
    for (const MeshBuildEntry& e : r.rebuilt) {
        EXPECT_EQ(e.clusters, 0u) << e.mesh;
        EXPECT_EQ(e.reason, BuildReason::RefitNotAllowed) << e.mesh;
    }
    EXPECT_EQ(r.clusters_rebuilt + r.clusters_refit, 0u);
}

// ---- differential: clustered against a fresh monolithic build ----

/// Random edits on a few bumpy grids and spheres of many sizes: local vertex patches (several
/// ranges per batch), whole-mesh deformations, refit and rebuild requests, local topology edits
/// (runs of triangles replaced) and whole topology changes.
class ClusterEdits {
public:
    explicit ClusterEdits(uint64_t seed) : m_rng(seed) {}

    EditBatch initial() {
        EditBatch b;
        const uint32_t sizes[] = {12, 23, 40, 64, 90};
        for (uint32_t i = 0; i < 5; ++i) {
            const std::string id = "m" + std::to_string(i);
            MeshData m = i == 4 ? make_sphere(2.5f, 60) : bumpy_grid(sizes[i], sizes[i] + 3, m_rng());
            m_meshes.push_back({id, m.positions, m.triangles, i == 4 ? 0u : sizes[i] + 1});
            b.edits.emplace_back(test::mesh_edit(id, std::move(m)));
            b.edits.emplace_back(test::instance_edit("i" + std::to_string(i), id,
                                                     Vec3(float(i % 3) * 9.0f - 9.0f, float(i) * 0.4f,
                                                          float(i / 3) * 9.0f - 4.0f)));
        }
        b.edits.emplace_back(camera());
        return b;
    }

    EditBatch next() {
        EditBatch b;
        const int edits = 1 + int(m_rng() % 3);
        for (int k = 0; k < edits; ++k) {
            Mesh& m = m_meshes[m_rng() % m_meshes.size()];
            const uint32_t kind = m_rng() % 10;
            if (kind < 4) {
                local_patch(m, b);
            } else if (kind < 5) {
                deform_all(m, b);
            } else if (kind < 6) {
                b.edits.emplace_back(MarkDirty{m.id, m_rng() % 2 ? DirtyAction::Refit : DirtyAction::Rebuild});
            } else if (kind < 8) {
                splice(m, b);
            } else if (kind < 9 && m_rng() % 2) {
                retopologize(m, b);
            } else {
                b.edits.emplace_back(camera());
            }
        }
        return b;
    }

private:
    struct Mesh {
        std::string id;
        std::vector<Vec3> positions;
        std::vector<Triangle> triangles;
        uint32_t row = 0;  ///< vertices per grid row (0: not a grid)
    };

    float uniform(float a, float b) { return std::uniform_real_distribution<float>(a, b)(m_rng); }

    SetCamera camera() {
        SetCamera c;
        c.eye = Vec3(uniform(-12, 12), uniform(4, 14), uniform(-14, 14));
        c.target = Vec3(uniform(-4, 4), 0.0f, uniform(-4, 4));
        c.up = Vec3(0, 1, 0);
        c.fov_y_deg = uniform(30, 80);
        return c;
    }

    /// A rectangular patch (or, on a sphere, a run of vertices) moved up or down; now and then
    /// far enough to stretch its clusters past the refit policy.
    void local_patch(Mesh& m, EditBatch& b) {
        const uint32_t n = uint32_t(m.positions.size());
        const float lift = m_rng() % 6 == 0 ? uniform(-3.0f, 3.0f) : uniform(-0.2f, 0.2f);
        const uint32_t rows = m.row ? 1 + m_rng() % 6 : 1;
        const uint32_t width = 1 + m_rng() % (m.row ? std::min(m.row, 12u) : 200u);
        const uint32_t start = m_rng() % n;
        // Half the time one edit listing the patch's vertices (update_mesh with vertices),
        // backwards so the list is not sorted; else one ranged edit per row.
        const bool listed = m_rng() % 2 == 0;
        UpdateMeshVertices list;
        list.mesh = m.id;
        for (uint32_t r = 0; r < rows; ++r) {
            const uint32_t offset = start + r * m.row;
            if (offset >= n) break;
            UpdateMeshPositions e;
            e.mesh = m.id;
            e.offset = offset;
            const uint32_t end = std::min(n, offset + width);
            for (uint32_t v = offset; v < end; ++v) {
                m.positions[v].y += lift;
                e.positions.push_back(m.positions[v]);
                list.vertices.insert(list.vertices.begin(), v);
                list.positions.insert(list.positions.begin(), m.positions[v]);
            }
            if (!listed) b.edits.emplace_back(std::move(e));
        }
        if (listed) b.edits.emplace_back(std::move(list));
    }

    void deform_all(Mesh& m, EditBatch& b) {
        const float phase = uniform(0.0f, 6.0f), amp = uniform(0.0f, 0.4f);
        for (Vec3& p : m.positions) p.y += amp * std::sin(p.x + phase);
        UpdateMeshPositions e;
        e.mesh = m.id;
        e.positions = m.positions;
        b.edits.emplace_back(std::move(e));
    }

    /// A run of triangles replaced (a local topology edit): some kept, some re-wound, some cut
    /// out, some joined by a new triangle over nearby vertices; or, with none replaced, new
    /// triangles inserted.
    void splice(Mesh& m, EditBatch& b) {
        const auto n = uint32_t(m.triangles.size());
        const auto vertices = uint32_t(m.positions.size());
        const uint32_t count = std::min(n - 1, uint32_t(m_rng() % 41));
        const uint32_t first = uint32_t(m_rng() % (n - count + 1));
        const uint32_t step = m.row ? m.row : 61;
        std::vector<Triangle> out;
        auto near = [&](const Triangle& t) {
            return Triangle(t.x, t.y, std::min(vertices - 1, t.x + step + 1));
        };
        for (uint32_t i = first; i < first + count; ++i) {
            const Triangle t = m.triangles[i];
            switch (m_rng() % 4) {
                case 0: break;
                case 1: out.push_back(Triangle(t.x, t.z, t.y)); break;
                case 2:
                    out.push_back(t);
                    out.push_back(near(t));
                    break;
                default: out.push_back(t);
            }
        }
        if (count == 0) {
            for (uint32_t k = 0; k < 1 + m_rng() % 8; ++k)
                out.push_back(near(m.triangles[m_rng() % n]));
        }
        m.triangles.erase(m.triangles.begin() + first, m.triangles.begin() + first + count);
        m.triangles.insert(m.triangles.begin() + first, out.begin(), out.end());
        b.edits.emplace_back(ReplaceMeshTriangles{m.id, first, count, std::move(out)});
    }

    /// New triangles in a new order (some dropped): a topology change and a new numbering.
    void retopologize(Mesh& m, EditBatch& b) {
        std::shuffle(m.triangles.begin(), m.triangles.end(), m_rng);
        if (m.triangles.size() > 64) m.triangles.resize(m.triangles.size() - m_rng() % 32);
        ReplaceMeshTopology e;
        e.mesh = m.id;
        e.triangles = m.triangles;
        b.edits.emplace_back(std::move(e));
    }

    std::mt19937_64 m_rng;
    std::vector<Mesh> m_meshes;
};

/// Normals of two frames agree pixel by pixel (the same triangle gives the same normal).
std::string compare_normals(const test::HitFrame& a, const test::HitFrame& b) {
    for (std::size_t p = 0; p < a.hits.normal.size(); ++p) {
        if (glm::length(a.hits.normal[p] - b.hits.normal[p]) > 1e-5f) {
            std::ostringstream out;
            out << "pixel " << p << ": normal differs";
            return out.str();
        }
    }
    return "";
}

TEST(ClusteredBlas, HitsMatchAFreshMonolithicBuildAfterRandomEdits) {
    constexpr int SEQUENCES = 12;
    constexpr int BATCHES = 25;
    uint64_t clusters_refit = 0, clusters_rebuilt = 0, hits = 0, launches = 0, spliced = 0;
    for (int seq = 0; seq < SEQUENCES; ++seq) {
        ClusterEdits edits(0xC1u + uint64_t(seq));
        auto engine = make(clustered_config(256));
        for (int batch = 0; batch < BATCHES; ++batch) {
            auto applied = engine->apply(batch == 0 ? edits.initial() : edits.next());
            ASSERT_TRUE(applied.has_value()) << applied.error().describe();
            RebuildReport report;
            const test::HitFrame clustered = test::render(*engine, 0xFFFFFFFFu, &report, 96, 64);
            clusters_refit += report.clusters_refit;
            clusters_rebuilt += report.clusters_rebuilt;
            for (const MeshBuildEntry& e : report.refit)
                spliced += e.reason == BuildReason::TrianglesReplaced;

            auto whole = make(clustered_config(0));
            ASSERT_TRUE(whole->apply(engine->read([](const Scene& s) { return s.to_batch(); }))
                            .has_value());
            const test::HitFrame fresh = test::render(*whole, 0xFFFFFFFFu, nullptr, 96, 64);
            const std::string diff = test::compare(clustered, fresh);
            ASSERT_TRUE(diff.empty()) << "sequence " << seq << " batch " << batch << ":\n" << diff;
            const std::string normals = compare_normals(clustered, fresh);
            ASSERT_TRUE(normals.empty()) << "sequence " << seq << " batch " << batch << ": " << normals;
            ++launches;
            for (const auto& id : clustered.instance_ids) hits += !id.empty();
        }
    }
    // Not vacuous: clusters were refit and rebuilt, and the frames show geometry.
    EXPECT_GT(clusters_refit, 100u);
    EXPECT_GT(clusters_rebuilt, 100u);
    EXPECT_GT(spliced, 20u) << "local topology edits re-made clusters";
    EXPECT_GT(double(hits) / double(launches * 96 * 64), 0.2);
}

// Renders race local edits: an editor thread applies dents while launches commit and trace. Each
// frame must show exactly the version its commit reported (the same hits as a fresh whole build
// of that version), with cluster refits running between the launches. Run under TSan too, with
// one rendering thread: launches are serialised anyway, and TSan cannot see TBB's (uninstrumented)
// joins, so two rendering threads make it flag a worker's read of one launch's stack against the
// next launch's writes.
TEST(ClusteredBlas, RendersDuringLocalEditsTraceExactlyOneVersion) {
    constexpr int BATCHES = 120;
    MeshData grid = bumpy_grid(100, 100, 11);
    std::vector<Vec3> positions = grid.positions;
    EditBatch initial;
    initial.edits.emplace_back(test::mesh_edit("g", std::move(grid)));
    initial.edits.emplace_back(test::instance_edit("i", "g"));
    initial.edits.emplace_back(SetCamera{Vec3(0, 9, 9), Vec3(0), Vec3(0, 1, 0), 60.0f});
    std::vector<EditBatch> batches;
    // The mesh's positions after each number of batches: a fresh build of any version needs them.
    std::vector<std::vector<Vec3>> versions{positions};
    std::mt19937 rng(5);
    for (int i = 0; i < BATCHES; ++i) {
        EditBatch b;
        const uint32_t row = rng() % 90, col = rng() % 90, rows = 1 + rng() % 8;
        const float lift = std::uniform_real_distribution<float>(-0.3f, 0.3f)(rng);
        for (uint32_t r = row; r < row + rows; ++r) {
            UpdateMeshPositions e;
            e.mesh = "g";
            e.offset = r * 101 + col;
            for (uint32_t v = e.offset; v < e.offset + 10; ++v) {
                positions[v].y += lift;
                e.positions.push_back(positions[v]);
            }
            b.edits.emplace_back(std::move(e));
        }
        batches.push_back(std::move(b));
        versions.push_back(positions);
    }

    // The first batch clusters the mesh before the race starts: every later commit refits.
    auto engine = make(clustered_config(1024));
    ASSERT_TRUE(engine->apply(EditBatch(initial)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(EditBatch(batches[0])).has_value());
    ASSERT_EQ(test::commit_ok(*engine).rebuilt.at(0).reason, BuildReason::Clustered);
    const uint64_t base = engine->read([](const Scene& s) { return s.version(); }) - 1;

    std::atomic<int> next{1};
    std::atomic<bool> stop{false};
    std::thread editor([&] {
        while (!stop.load() && next.load() < BATCHES) {
            if (!engine->apply(EditBatch(batches[std::size_t(next.load())])).has_value()) break;
            next.fetch_add(1);
            std::this_thread::sleep_for(std::chrono::microseconds(500));
        }
    });
    using Shown = std::vector<std::pair<uint64_t, test::HitFrame>>;
    // Frames until the editor is done (at least 5, at most 30), each checked below.
    Shown a;
    while (a.size() < 5 || (a.size() < 30 && next.load() < BATCHES)) {
        RebuildReport report;
        test::HitFrame frame = test::render(*engine, 0xFFFFFFFFu, &report, 96, 64);
        a.emplace_back(report.version, std::move(frame));
    }
    stop.store(true);
    editor.join();

    const uint64_t clusters_refit = engine->counters().clusters_refit;
    EXPECT_GT(clusters_refit, 0u) << "local edits were committed as cluster refits";
    for (const auto& [version, frame] : a) {
        ASSERT_GE(version, base);
        const uint64_t applied = version - base;
        ASSERT_LE(applied, uint64_t(BATCHES));
        EditBatch whole = initial;
        std::get<AddMesh>(whole.edits.front()).positions = versions[applied];
        auto fresh_engine = make(clustered_config(0));
        ASSERT_TRUE(fresh_engine->apply(std::move(whole)).has_value());
        const test::HitFrame fresh = test::render(*fresh_engine, 0xFFFFFFFFu, nullptr, 96, 64);
        const std::string diff = test::compare(frame, fresh);
        EXPECT_TRUE(diff.empty()) << "frame of version " << version << " differs:\n" << diff;
    }
}

}  // namespace
}  // namespace strata
