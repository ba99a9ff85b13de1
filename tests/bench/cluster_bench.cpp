// Clustered against whole-mesh BLASes on one 1M-triangle terrain (a plain program; NOTES.md,
// "Clustered BLAS", has the results). Two engines hold the same mesh, one with clustering off;
// every measurement alternates between them, so both see the same machine noise.
//
//   build/tests/bench/strata_cluster_bench [runs] [threads] [size_factor]
//
// Rows: the commit after a square patch holding 1%, 10% or all of the vertices moved (the patch
// is written as one update_mesh per grid row, as a client sculpting it would send), the commit
// after a patch of 1% or 10% of the triangles was re-cut (one replace_triangles per grid row:
// the whole BLAS is rebuilt, the clustered one rebuilds the clusters that held them), BLAS
// memory, and primary rays per second on a fresh BLAS and after 1000 small local edits. Commit
// times are wall time around Engine::commit (the apply before it is not timed), medians over
// `runs`.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <initializer_list>
#include <memory>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "tests/bench/bench_clock.h"

namespace strata {
namespace {

constexpr uint32_t NX = 1000, NZ = 500;  // 1,000,000 triangles
constexpr uint32_t ROW = NX + 1;

using bench::median;
using bench::now_ms;

struct Terrain {
    std::unique_ptr<Engine> engine;
    std::vector<Vec3> positions;
    double build_ms = 0.0;
    double clustering_ms = 0.0;  ///< the first local edit's commit (the rebuild as clusters)
    uint32_t clusters = 0;
};

double g_size_factor = ClusterPolicy{}.size_factor;

Terrain make_terrain(bool clustered) {
    EngineConfig config;
    config.accel.clusters.size_factor = g_size_factor;
    if (!clustered) config.accel.clusters.min_triangles = 0;
    Terrain t;
    t.engine = std::move(Engine::create(config).value());
    MeshData m = make_plane(Vec3(100.0f, 0.0f, 50.0f), NX, NZ);
    for (Vec3& p : m.positions) p.y = 2.0f * std::sin(p.x * 0.21f) * std::cos(p.z * 0.17f);
    t.positions = m.positions;
    EditBatch b;
    b.edits.emplace_back(add_mesh_edit("terrain", std::move(m)));
    AddInstance inst;
    inst.id = "terrain";
    inst.mesh = "terrain";
    b.edits.emplace_back(std::move(inst));
    b.edits.emplace_back(SetCamera{Vec3(0.0f, 40.0f, 45.0f), Vec3(0.0f), Vec3(0, 1, 0), 55.0f});
    (void)t.engine->apply(std::move(b));
    const double start = now_ms();
    (void)t.engine->commit();
    t.build_ms = now_ms() - start;
    // The first local edit turns a big mesh clustered (whole meshes never get one).
    if (clustered) {
        UpdateMeshPositions u;
        u.mesh = "terrain";
        u.positions = {t.positions[0]};
        EditBatch e;
        e.edits.emplace_back(std::move(u));
        (void)t.engine->apply(std::move(e));
        const double first = now_ms();
        const RebuildReport c = t.engine->commit().value();
        t.clustering_ms = now_ms() - first;
        t.clusters = c.rebuilt.empty() ? 0 : c.rebuilt[0].clusters;
    }
    return t;
}

/// Moves a square patch of about `fraction` of the vertices, centred at (cx, cz) in grid units,
/// up or down by `lift`: one update_mesh per grid row.
EditBatch patch(Terrain& t, double fraction, uint32_t cx, uint32_t cz, float lift) {
    EditBatch b;
    if (fraction >= 1.0) {
        UpdateMeshPositions u;
        u.mesh = "terrain";
        for (Vec3& p : t.positions) p.y += lift;
        u.positions = t.positions;
        b.edits.emplace_back(std::move(u));
        return b;
    }
    const auto side = uint32_t(std::sqrt(fraction * double(t.positions.size())));
    const uint32_t x0 = std::min(cx - std::min(cx, side / 2), ROW - side);
    const uint32_t z0 = std::min(cz - std::min(cz, side / 2), NZ + 1 - side);
    for (uint32_t z = z0; z < z0 + side; ++z) {
        UpdateMeshPositions u;
        u.mesh = "terrain";
        u.offset = z * ROW + x0;
        for (uint32_t x = 0; x < side; ++x) {
            Vec3& p = t.positions[u.offset + x];
            p.y += lift;
            u.positions.push_back(p);
        }
        b.edits.emplace_back(std::move(u));
    }
    return b;
}

/// Re-cuts a square patch of about `fraction` of the quads, centred at (cx, cz), along the
/// other diagonal (`flip`) or back: one replace_triangles per grid row (each row of the patch is
/// one run of triangles), the triangle count unchanged.
EditBatch recut(double fraction, uint32_t cx, uint32_t cz, bool flip) {
    EditBatch b;
    const auto side = uint32_t(std::sqrt(fraction * double(NX) * double(NZ)));
    const uint32_t x0 = std::min(cx - std::min(cx, side / 2), NX - side);
    const uint32_t z0 = std::min(cz - std::min(cz, side / 2), NZ - side);
    for (uint32_t z = z0; z < z0 + side; ++z) {
        ReplaceMeshTriangles e{"terrain", 2 * (z * NX + x0), 2 * side, {}};
        for (uint32_t x = x0; x < x0 + side; ++x) {
            const uint32_t a = z * ROW + x, bb = a + 1, c = a + ROW, d = c + 1;
            if (flip) {
                e.triangles.push_back({a, c, d});
                e.triangles.push_back({a, d, bb});
            } else {  // make_plane's own cut
                e.triangles.push_back({a, c, bb});
                e.triangles.push_back({bb, c, d});
            }
        }
        b.edits.emplace_back(std::move(e));
    }
    return b;
}

/// Applies `batch` (untimed), then times the commit.
double timed_commit(Terrain& t, EditBatch batch, RebuildReport* report = nullptr) {
    if (auto r = t.engine->apply(std::move(batch)); !r) {
        std::fprintf(stderr, "apply: %s\n", r.error().describe().c_str());
        std::exit(1);
    }
    const double start = now_ms();
    auto r = t.engine->commit();
    const double ms = now_ms() - start;
    if (report && r) *report = r.value();
    return ms;
}

/// Median primary-frame times of the two engines, measured alternately.
std::pair<double, double> trace_ms(Terrain& a, Terrain& b, int runs) {
    PrimarySettings s;
    s.width = 1280;
    s.height = 720;
    Frame fa, fb;
    (void)a.engine->render_primary(s, fa);  // warm
    (void)b.engine->render_primary(s, fb);
    std::vector<double> va, vb;
    for (int i = 0; i < runs; ++i) {
        double start = now_ms();
        (void)a.engine->render_primary(s, fa);
        va.push_back(now_ms() - start);
        start = now_ms();
        (void)b.engine->render_primary(s, fb);
        vb.push_back(now_ms() - start);
    }
    return {median(va), median(vb)};
}

/// One table row per fraction: the whole engine's commit against the clustered one's after
/// `edit(terrain, fraction, i)` (the i-th run), with the clustered commit's phases and the
/// clusters `count(entry)` names.
template <class Edit, class Count>
void rows(Terrain& whole, Terrain& clustered, int runs, std::initializer_list<double> fractions,
          const char* what, Edit&& edit, Count&& count) {
    for (double fraction : fractions) {
        std::vector<double> a, b, plan, blas, tlas, sync;
        RebuildReport report;
        for (int i = 0; i < runs; ++i) {
            a.push_back(timed_commit(whole, edit(whole, fraction, i)));
            b.push_back(timed_commit(clustered, edit(clustered, fraction, i), &report));
            plan.push_back(report.phases.plan_ms);
            blas.push_back(report.phases.blas_ms);
            tlas.push_back(report.phases.tlas_ms);
            sync.push_back(report.phases.sync_ms);
        }
        const uint32_t clusters = report.refit.empty() ? 0 : count(report.refit[0]);
        std::printf("| %g%% of the %s (one patch) | %.3f ms | %.3f ms | %u of %u | %.1fx | "
                    "%.3f / %.3f / %.3f / %.3f ms |\n",
                    fraction * 100.0, what, median(a), median(b), clusters, clustered.clusters,
                    median(a) / median(b), median(plan), median(blas), median(tlas),
                    median(sync));
    }
}

void run(int runs) {
    Terrain whole = make_terrain(false), clustered = make_terrain(true);
    std::printf("first build %.1f ms; first local edit (rebuilt as %u clusters) %.1f ms\n\n",
                whole.build_ms, clustered.clusters, clustered.clustering_ms);
    std::printf("| commit after moving | whole BLAS (refit) | clustered | clusters refit | "
                "speed-up | clustered phases: plan / blas / tlas / sync |\n");
    std::printf("|---|---|---|---|---|---|\n");
    rows(
        whole, clustered, runs, {0.01, 0.10, 1.0}, "vertices",
        [](Terrain& t, double fraction, int i) {
            const float lift = i % 2 ? -0.05f : 0.05f;  // back and forth: no drift
            return patch(t, fraction, ROW / 2, NZ / 2, lift);
        },
        [](const MeshBuildEntry& e) { return e.clusters_refit; });

    std::printf("\n| commit after replacing the triangles of | whole BLAS (rebuild) | clustered | "
                "clusters rebuilt | speed-up | clustered phases: plan / blas / tlas / sync |\n");
    std::printf("|---|---|---|---|---|---|\n");
    rows(
        whole, clustered, runs, {0.01, 0.10}, "triangles",
        [](Terrain&, double fraction, int i) {
            return recut(fraction, NX / 2, NZ / 2, i % 2 == 0);  // re-cut, then cut back
        },
        [](const MeshBuildEntry& e) { return e.clusters_rebuilt; });
    const auto mb = [](Terrain& t) {
        return double(t.engine->memory_bytes(MemoryCategory::Blas)) / (1024.0 * 1024.0);
    };
    std::printf("\nBLAS memory: whole %.1f MiB, clustered %.1f MiB (%.2fx)\n", mb(whole),
                mb(clustered), mb(clustered) / mb(whole));

    std::printf("\n| primary rays, 1280x720 | whole | clustered | clustered / whole speed |\n");
    std::printf("|---|---|---|---|\n");
    auto [ta, tb] = trace_ms(whole, clustered, runs);
    std::printf("| fresh BLAS | %.1f ms | %.1f ms | %.3f |\n", ta, tb, ta / tb);
    std::mt19937 rng(1);
    for (int i = 0; i < 1000; ++i) {
        const uint32_t cx = rng() % ROW, cz = rng() % (NZ + 1);
        const float lift = std::uniform_real_distribution<float>(-0.3f, 0.3f)(rng);
        timed_commit(whole, patch(whole, 0.0005, cx, cz, lift));
        timed_commit(clustered, patch(clustered, 0.0005, cx, cz, lift));
    }
    std::tie(ta, tb) = trace_ms(whole, clustered, runs);
    std::printf("| after 1000 local edits | %.1f ms | %.1f ms | %.3f |\n", ta, tb, ta / tb);
}

}  // namespace
}  // namespace strata

int main(int argc, char** argv) {
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 15;
    const int threads = argc > 2 ? std::max(0, std::atoi(argv[2])) : 0;
    if (argc > 3) strata::g_size_factor = std::atof(argv[3]);
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0)
        limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                      std::size_t(threads));
    std::printf("strata_cluster_bench: %d runs, %s threads, cluster size %.2f sqrt(triangles)\n\n",
                runs, threads > 0 ? std::to_string(threads).c_str() : "all",
                strata::g_size_factor);
    strata::run(runs);
    return 0;
}
