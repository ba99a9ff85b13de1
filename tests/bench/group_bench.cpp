// Moving a group: k instances below one group, in scenes of N instances (N from 10k to
// 1M, k fixed); and stepping the scene's time with k animated instances among N. Either must
// cost what the k instances cost, not what the scene holds. Never run by CTest.
//
//   build/tests/bench/strata_group_bench [--reps N] [--max-instances N] [--k K]
//
// Scene: N instances of one small sphere on a grid; the first k sit under group "moving", the rest
// under 100 other groups (the graph is not flat, and the other groups are never touched). Each
// repetition applies one set_transform on "moving" (Engine::apply: the rule, then the flattening
// of that subtree) and commits (one TLAS update over the k instances). The time rows give the
// first k instances an animation (two keyframes, 10 s apart) instead and apply one set_time per
// repetition (the animated instances evaluated, one TLAS update over them). 2 TBB threads
// (STRATA_BENCH_THREADS overrides), the incremental TLAS with its defaults. Medians of --reps
// (default 21) repetitions, after 3 unmeasured ones.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

std::unique_ptr<Engine> build_scene(int64_t n, int64_t k, bool animated) {
    auto engine = std::move(Engine::create().value());
    EditBatch b;
    b.edits.emplace_back(add_mesh_edit("pebble", make_sphere(0.45f, 16)));
    b.edits.emplace_back(AddGroup{"moving", std::nullopt, Affine::identity(), true});
    for (int g = 0; g < 100; ++g)
        b.edits.emplace_back(AddGroup{"still" + std::to_string(g), std::nullopt, Affine::identity(), true});
    const auto side = int64_t(std::ceil(std::sqrt(double(n))));
    for (int64_t i = 0; i < n; ++i) {
        AddInstance inst;
        inst.id = "i" + std::to_string(i);
        inst.mesh = "pebble";
        inst.transform = Affine::translation({float(i % side), 0.0f, float(i / side)});
        inst.parent = i < k ? std::string("moving") : "still" + std::to_string(i % 100);
        if (animated && i < k)
            inst.animation = {{0.0f, inst.transform},
                              {10.0f, Affine::translation({0, 5, 0}) * inst.transform}};
        b.edits.emplace_back(std::move(inst));
    }
    if (!engine->apply(std::move(b)) || !engine->commit()) std::abort();
    return engine;
}

struct Row {
    double apply_ms, commit_ms, tlas_ms;
    uint64_t world_transforms, instances_changed;
};

Row measure(Engine& engine, int reps, bool animated) {
    std::vector<double> apply_ms, commit_ms, tlas_ms;
    Row row{};
    for (int r = -3; r < reps; ++r) {
        const float x = float(r % 5) * 0.25f;
        EditBatch b;
        if (animated)
            b.edits.emplace_back(SetTime{float(r + 4) * 0.1f, std::nullopt});
        else
            b.edits.emplace_back(UpdateGroup{"moving", std::nullopt,
                                             Affine::translation({x, 1.0f, 0.0f}), std::nullopt});
        const auto t0 = Clock::now();
        if (!engine.apply(std::move(b))) std::abort();
        const double a = ms_since(t0);
        const auto t1 = Clock::now();
        auto report = engine.commit();
        const double c = ms_since(t1);
        if (!report) std::abort();
        if (r < 0) continue;
        apply_ms.push_back(a);
        commit_ms.push_back(c);
        tlas_ms.push_back(report->phases.tlas_ms);
        row.world_transforms = report->world_transforms;
        row.instances_changed = report->instances_changed;
    }
    row.apply_ms = median(apply_ms);
    row.commit_ms = median(commit_ms);
    row.tlas_ms = median(tlas_ms);
    return row;
}

}  // namespace
}  // namespace strata

int main(int argc, char** argv) {
    int reps = 21;
    int64_t max_instances = 1000000;
    std::vector<int64_t> ks = {100, 1000};
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!std::strcmp(argv[i], "--reps")) reps = std::atoi(argv[i + 1]);
        if (!std::strcmp(argv[i], "--max-instances")) max_instances = std::atoll(argv[i + 1]);
        if (!std::strcmp(argv[i], "--k")) ks = {std::atoll(argv[i + 1])};
    }
    const char* env = std::getenv("STRATA_BENCH_THREADS");
    const int threads = env ? std::atoi(env) : 2;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    std::printf("group move and time step, %d TBB threads, medians of %d\n", threads, reps);
    std::printf("| edit | N | k | apply (rule + flatten) ms | commit ms | TLAS phase ms | world "
                "transforms | instances to TLAS |\n");
    std::printf("|---|---|---|---|---|---|---|---|\n");
    for (const bool animated : {false, true}) {
        for (int64_t n : {int64_t(10000), int64_t(100000), int64_t(1000000)}) {
            if (n > max_instances) break;
            for (int64_t k : ks) {
                auto engine = strata::build_scene(n, k, animated);
                const strata::Row r = strata::measure(*engine, reps, animated);
                std::printf("| %s | %lld | %lld | %.3f | %.3f | %.3f | %llu | %llu |\n",
                            animated ? "set_time, k animated" : "move a group of k",
                            (long long)n, (long long)k, r.apply_ms, r.commit_ms, r.tlas_ms,
                            (unsigned long long)r.world_transforms,
                            (unsigned long long)r.instances_changed);
                std::fflush(stdout);
            }
        }
    }
    return 0;
}
