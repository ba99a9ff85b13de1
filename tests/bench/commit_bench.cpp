// Cost of a commit by kind of edit (Google Benchmark; never run by CTest). Each benchmark edits,
// then times only the commit that follows, so the numbers are the acceleration-structure work
// the least-work rules leave.
//
//   build/tests/bench/strata_commit_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true

#include <algorithm>
#include <cmath>
#include <vector>
#include <string>

#include <benchmark/benchmark.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"

namespace strata {
namespace {

std::unique_ptr<Engine> make_engine() { return std::move(Engine::create().value()); }

Affine grid_transform(int64_t i, int64_t n, float jitter) {
    const auto side = int64_t(std::ceil(std::sqrt(double(n))));
    return Affine::translation({float(i % side) * 2.0f + jitter, 0.0f, float(i / side) * 2.0f});
}

/// A field of `n` instances of one small sphere, committed.
std::unique_ptr<Engine> instance_field(int64_t n) {
    auto engine = make_engine();
    EditBatch b;
    b.edits.emplace_back(add_mesh_edit("pebble", make_sphere(0.5f, 12)));
    for (int64_t i = 0; i < n; ++i) {
        AddInstance inst;
        inst.id = "i" + std::to_string(i);
        inst.mesh = "pebble";
        inst.transform = grid_transform(i, n, 0.0f);
        b.edits.emplace_back(std::move(inst));
    }
    (void)engine->apply(std::move(b));
    (void)engine->commit();
    return engine;
}

/// An engine holding `mesh` and one instance of it (named as the mesh), committed.
std::unique_ptr<Engine> one_instance_of(AddMesh mesh) {
    auto engine = make_engine();
    EditBatch b;
    AddInstance inst;
    inst.id = inst.mesh = mesh.id;
    b.edits.emplace_back(std::move(mesh));
    b.edits.emplace_back(std::move(inst));
    (void)engine->apply(std::move(b));
    (void)engine->commit();
    return engine;
}

void commit_timed(benchmark::State& state, Engine& engine) {
    auto report = engine.commit();
    if (!report) state.SkipWithError(report.error().describe().c_str());
    benchmark::DoNotOptimize(report);
}

void BM_NothingChanged(benchmark::State& state) {
    auto engine = instance_field(state.range(0));
    for (auto _ : state) commit_timed(state, *engine);
}
BENCHMARK(BM_NothingChanged)->Arg(10000)->Unit(benchmark::kMicrosecond);

void BM_CameraOnly(benchmark::State& state) {
    auto engine = instance_field(state.range(0));
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        SetCamera c;
        c.eye = Vec3(float(++frame % 7), 5.0f, 20.0f);
        (void)engine->apply(EditBatch{{c}});
        state.ResumeTiming();
        commit_timed(state, *engine);
    }
}
BENCHMARK(BM_CameraOnly)->Arg(10000)->Unit(benchmark::kMicrosecond);

/// Each iteration moves one instance of the field of `n` (untimed), then times the commit.
void time_single_moves(benchmark::State& state, Engine& engine, int64_t n, float step) {
    int64_t frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        const int64_t i = (frame * 7919) % n;
        const float lift = float(++frame % 3) * step;
        (void)engine.apply(EditBatch{{SetTransform{"i" + std::to_string(i),
                                                   grid_transform(i, n, lift)}}});
        state.ResumeTiming();
        commit_timed(state, engine);
    }
}

void BM_MoveOneInstance(benchmark::State& state) {
    const int64_t n = state.range(0);
    auto engine = instance_field(n);
    time_single_moves(state, *engine, n, 0.1f);
    state.counters["instances"] = double(n);
}
BENCHMARK(BM_MoveOneInstance)->Arg(1000)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

/// Moving one instance after a batch that moved 8% of them (under the dynamic tier's 10% limit)
/// was merged into the static tier: the dynamic tier is small again, and so should the commit be
/// (the dynamic tier's Embree scene must not keep walking the slots the batch used).
void BM_MoveOneAfterADrainedBatch(benchmark::State& state) {
    const int64_t n = state.range(0);
    auto engine = instance_field(n);
    EditBatch batch;
    for (int64_t i = 0; i < n * 8 / 100; ++i)
        batch.edits.emplace_back(SetTransform{"i" + std::to_string(i), grid_transform(i, n, 0.1f)});
    (void)engine->apply(std::move(batch));
    (void)engine->commit();  // the dynamic tier takes the batch; a merge starts
    engine->wait_for_background();
    (void)engine->commit();  // the merge is swapped in: the dynamic tier drains
    time_single_moves(state, *engine, n, 0.2f);
}
BENCHMARK(BM_MoveOneAfterADrainedBatch)
    ->Arg(100000)
    ->Arg(1000000)
    ->Unit(benchmark::kMillisecond);

void BM_TlasRebuild(benchmark::State& state) {
    auto engine = instance_field(state.range(0));
    for (auto _ : state) {
        state.PauseTiming();
        (void)engine->apply(EditBatch{{MarkDirty{std::nullopt, DirtyAction::Rebuild}}});
        state.ResumeTiming();
        commit_timed(state, *engine);
    }
}
BENCHMARK(BM_TlasRebuild)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

/// The first commit of `n` instances added in one bulk edit (issue 24): every instance's Embree
/// geometry made and the static TLAS tier built. The apply before it is untimed.
void BM_FirstBuild(benchmark::State& state) {
    const int64_t n = state.range(0);
    AddInstances bulk;
    bulk.ids.prefix = "i";
    bulk.ids.count = uint64_t(n);
    bulk.meshes = {"pebble"};
    for (int64_t i = 0; i < n; ++i) bulk.transforms.push_back(grid_transform(i, n, 0.0f));
    std::vector<CommitPhases> phases;
    for (auto _ : state) {
        state.PauseTiming();
        auto engine = make_engine();
        (void)engine->apply(EditBatch{{add_mesh_edit("pebble", make_sphere(0.5f, 12)), bulk}});
        state.ResumeTiming();
        auto report = engine->commit();
        state.PauseTiming();
        if (!report) state.SkipWithError(report.error().describe().c_str());
        phases.push_back(report->phases);
        engine.reset();
        state.ResumeTiming();
    }
    // Medians of the commit's phases: where the first build goes.
    auto median_of = [&](double CommitPhases::*field) {
        std::vector<double> v;
        for (const CommitPhases& p : phases) v.push_back(p.*field);
        std::sort(v.begin(), v.end());
        return v.empty() ? 0.0 : v[v.size() / 2];
    };
    state.counters["plan_ms"] = median_of(&CommitPhases::plan_ms);
    state.counters["tlas_ms"] = median_of(&CommitPhases::tlas_ms);
    state.counters["sync_ms"] = median_of(&CommitPhases::sync_ms);
}
BENCHMARK(BM_FirstBuild)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond)->Iterations(3);

/// One instanced mesh of about 1M triangles whose vertices wobble each frame; `keyed`: it has a
/// second vertex key (deformation blur), and each frame gives both keys.
void deform_big_mesh(benchmark::State& state, BuildOptions options, bool force_rebuild,
                     bool keyed = false) {
    MeshData sphere = make_sphere(1.0f, 1000);
    const std::vector<Vec3> base = sphere.positions;
    AddMesh add = add_mesh_edit("big", std::move(sphere), options);
    if (keyed) add.motion_positions = base;
    auto engine = one_instance_of(std::move(add));
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        UpdateMeshPositions u;
        u.mesh = "big";
        u.positions = base;
        const float phase = 0.1f * float(++frame);
        for (Vec3& p : u.positions) p *= 1.0f + 0.01f * std::sin(7.0f * p.x + phase);
        if (keyed) {
            u.motion_positions = u.positions;
            for (Vec3& p : *u.motion_positions) p *= 1.02f;
        }
        EditBatch edits;
        edits.edits.emplace_back(std::move(u));
        if (force_rebuild) edits.edits.emplace_back(MarkDirty{std::string("big"), DirtyAction::Rebuild});
        (void)engine->apply(std::move(edits));
        state.ResumeTiming();
        commit_timed(state, *engine);
    }
    state.counters["triangles"] = double(sphere_triangle_count(1000));
}

void BM_Deform1MTriangles_Refit(benchmark::State& state) { deform_big_mesh(state, {}, false); }
void BM_Deform1MTriangles_RebuildRefitQuality(benchmark::State& state) { deform_big_mesh(state, {}, true); }
void BM_Deform1MTriangles_RebuildFastTrace(benchmark::State& state) {
    deform_big_mesh(state, {BuildPreference::FastTrace, false}, false);
}
void BM_Deform1MTriangles_RebuildFastBuild(benchmark::State& state) {
    deform_big_mesh(state, {BuildPreference::FastBuild, false}, false);
}
/// The same mesh with two vertex keys (deformation blur), both given each frame: a rebuild, as
/// Embree 3 has no refit for motion-blur BVHs.
void BM_Deform1MTriangles_Keyed(benchmark::State& state) {
    deform_big_mesh(state, {}, false, true);
}
BENCHMARK(BM_Deform1MTriangles_Refit)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform1MTriangles_Keyed)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform1MTriangles_RebuildRefitQuality)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform1MTriangles_RebuildFastTrace)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Deform1MTriangles_RebuildFastBuild)->Unit(benchmark::kMillisecond);

/// 1M points (kind points) or 250,000 four-vertex B-spline strands (250,000 segments) on a
/// sphere, one instance: the commit after one vertex moved. Embree has no refit for spheres
/// and curves, so this is a rebuild of the mesh; a 1M-triangle refit is the row above.
void move_one_vertex(benchmark::State& state, MeshKind kind) {
    AddMesh m;
    m.id = "cloud";
    m.kind = kind;
    const int n = 1000000;
    for (int k = 0; k < n; ++k) {
        const float z = 1.0f - 2.0f * (float(k) + 0.5f) / float(n), r = std::sqrt(1.0f - z * z);
        const float a = 2.39996323f * float(k);
        const float grow = kind == MeshKind::Curves ? 1.0f + 0.02f * float(k % 4) : 1.0f;
        m.positions.emplace_back(grow * r * std::cos(a), grow * z, grow * r * std::sin(a));
        m.radii.push_back(0.001f);
    }
    if (kind == MeshKind::Curves) {
        m.basis = CurveBasis::BSpline;
        m.strands.assign(n / 4, 4);
    }
    auto engine = one_instance_of(std::move(m));
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        EditBatch edits;
        edits.edits.emplace_back(
            UpdateMeshPositions{"cloud", 4, {Vec3(0.0f, 0.001f * float(++frame % 7), 1.0f)}});
        (void)engine->apply(std::move(edits));
        state.ResumeTiming();
        commit_timed(state, *engine);
    }
}
void BM_MoveOneOf1MPoints(benchmark::State& state) { move_one_vertex(state, MeshKind::Points); }
void BM_MoveOneVertexOf250kCurveSegments(benchmark::State& state) {
    move_one_vertex(state, MeshKind::Curves);
}
BENCHMARK(BM_MoveOneOf1MPoints)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_MoveOneVertexOf250kCurveSegments)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace strata

BENCHMARK_MAIN();
