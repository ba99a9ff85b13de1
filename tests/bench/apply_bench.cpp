// Cost of applying one large edit batch (Google Benchmark; never run by CTest): the scene's
// checks and bookkeeping for 100,000 edits, without any commit. Batches are built outside the
// timed region. `Reject*` batches fail at their last edit, so they pay every check plus undoing
// what the batch had applied. `Bulk*` apply the same adds and moves as one bulk edit
// (add_instances, update_instances). The argument of the accepted kinds is 1 when the apply also
// makes the batch's inverse, as the engine does for its undo history (inverse_batch.h), 0 when
// not.
//
//   build/tests/bench/strata_apply_bench --benchmark_repetitions=7 --benchmark_report_aggregates_only=true

#include <string>

#include <benchmark/benchmark.h>

#include "engine/scene/scene.h"
#include "engine/scene/shapes.h"

namespace strata {
namespace {

constexpr int EDITS = 100000;

std::string instance_id(int i) { return "instance-" + std::to_string(i); }

Affine place(int i, float lift) {
    return Affine::translation({float(i % 316) * 2.0f, lift, float(i / 316) * 2.0f});
}

/// One mesh, one material and `instances` instances of the mesh.
Scene populated(int instances) {
    Scene scene;
    EditBatch b;
    b.edits.emplace_back(add_mesh_edit("pebble", make_sphere(0.5f, 8)));
    b.edits.emplace_back(AddMaterial{"stone", Material{}});
    for (int i = 0; i < instances; ++i) {
        AddInstance e;
        e.id = instance_id(i);
        e.mesh = "pebble";
        e.transform = place(i, 0.0f);
        b.edits.emplace_back(std::move(e));
    }
    if (!scene.apply(std::move(b))) std::abort();
    return scene;
}

EditBatch adds(int first) {
    EditBatch b;
    for (int i = 0; i < EDITS; ++i) {
        AddInstance e;
        e.id = instance_id(first + i);
        e.mesh = "pebble";
        e.material = "stone";
        e.transform = place(i, 1.0f);
        b.edits.emplace_back(std::move(e));
    }
    return b;
}

EditBatch moves(int frame) {
    EditBatch b;
    for (int i = 0; i < EDITS; ++i)
        b.edits.emplace_back(SetTransform{instance_id(i), place(i, float(frame % 5))});
    return b;
}

EditBatch mixed(int frame) {
    EditBatch b;
    for (int i = 0; i < EDITS; ++i) {
        switch (i % 4) {
            case 0: b.edits.emplace_back(SetTransform{instance_id(i), place(i, float(frame % 5))}); break;
            case 1: {
                UpdateInstance u;
                u.instance = instance_id(i);
                u.visible = (frame + i) % 2 == 0;
                u.material = std::optional<std::string>("stone");
                b.edits.emplace_back(std::move(u));
                break;
            }
            case 2: {
                UpdateMaterial m;
                m.material = "stone";
                m.roughness = float(i % 10) / 10.0f;
                b.edits.emplace_back(std::move(m));
                break;
            }
            default: {
                UpdateMeshPositions p;
                p.mesh = "pebble";
                p.offset = uint32_t(i % 20);
                p.positions = {Vec3(0.0f, 0.5f + float(frame % 3) * 0.01f, 0.0f)};
                b.edits.emplace_back(std::move(p));
            }
        }
    }
    return b;
}

/// `b` with its last edit replaced by one that names an unknown instance.
EditBatch failing_at_the_end(EditBatch b) {
    b.edits.back() = SetTransform{"no-such-instance", Affine()};
    return b;
}

void apply_timed(benchmark::State& state, Scene& scene, EditBatch&& batch, bool expect_ok) {
    // The inverse, when made, is freed outside the timed region (the history frees it later).
    EditBatch inverse;
    auto r = scene.apply(std::move(batch), nullptr, state.range(0) ? &inverse : nullptr);
    if (bool(r) != expect_ok) state.SkipWithError("unexpected apply result");
    state.PauseTiming();
    inverse = {};
    state.ResumeTiming();
}

void BM_AddInstances(benchmark::State& state) {
    for (auto _ : state) {
        state.PauseTiming();
        Scene scene = populated(0);
        EditBatch b = adds(0);
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), true);
        state.PauseTiming();
        scene = Scene();  // not timed: freeing 100k instances
        state.ResumeTiming();
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_AddInstances)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_MoveInstances(benchmark::State& state) {
    Scene scene = populated(EDITS);
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        EditBatch b = moves(++frame);
        scene.clear_changes();
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), true);
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_MoveInstances)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_MixedEdits(benchmark::State& state) {
    Scene scene = populated(EDITS);
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        EditBatch b = mixed(++frame);
        scene.clear_changes();
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), true);
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_MixedEdits)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

/// The same 100,000 adds as adds(first), as one add_instances: a numbered range of ids, the
/// mesh and material once, the transforms packed.
EditBatch bulk_adds(int first) {
    AddInstances e;
    e.ids.prefix = "instance-";
    e.ids.first = uint64_t(first);
    e.ids.count = EDITS;
    e.meshes = {"pebble"};
    e.materials = {"stone"};
    for (int i = 0; i < EDITS; ++i) e.transforms.push_back(place(i, 1.0f));
    EditBatch b;
    b.edits.emplace_back(std::move(e));
    return b;
}

/// The same 100,000 moves as moves(frame), as one update_instances.
EditBatch bulk_moves(int frame) {
    UpdateInstances e;
    e.ids.prefix = "instance-";
    e.ids.count = EDITS;
    for (int i = 0; i < EDITS; ++i) e.transforms.push_back(place(i, float(frame % 5)));
    EditBatch b;
    b.edits.emplace_back(std::move(e));
    return b;
}

void BM_BulkAddInstances(benchmark::State& state) {
    for (auto _ : state) {
        state.PauseTiming();
        Scene scene = populated(0);
        EditBatch b = bulk_adds(0);
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), true);
        state.PauseTiming();
        scene = Scene();
        state.ResumeTiming();
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_BulkAddInstances)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_BulkMoveInstances(benchmark::State& state) {
    Scene scene = populated(EDITS);
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        EditBatch b = bulk_moves(++frame);
        scene.clear_changes();
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), true);
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_BulkMoveInstances)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_RejectAddInstances(benchmark::State& state) {
    Scene scene = populated(0);
    for (auto _ : state) {
        state.PauseTiming();
        EditBatch b = failing_at_the_end(adds(0));
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), false);
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_RejectAddInstances)->Arg(0)->Unit(benchmark::kMillisecond);

void BM_RejectMixedEdits(benchmark::State& state) {
    Scene scene = populated(EDITS);
    int frame = 0;
    for (auto _ : state) {
        state.PauseTiming();
        EditBatch b = failing_at_the_end(mixed(++frame));
        state.ResumeTiming();
        apply_timed(state, scene, std::move(b), false);
    }
    state.SetItemsProcessed(state.iterations() * EDITS);
}
BENCHMARK(BM_RejectMixedEdits)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace strata

BENCHMARK_MAIN();
