// BLAS compaction (BuildOptions::compact) against the same mesh built without it, for each of
// the three build setups (a plain program; NOTES.md, "Compaction", has the results). Two engines
// hold the same ~1M-triangle sphere seen from the same camera, one compacted; every measurement
// alternates between them, so both see the same machine noise.
//
//   build/tests/bench/strata_compaction_bench [runs] [threads]
//
// Rows: BLAS memory (the compacted mesh's own report gives both sizes), the commit that builds
// the BLAS (a compacted build is two passes), and primary rays per second (1280x720, one ray per
// pixel). Times are medians over `runs`.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "engine/engine.h"
#include "engine/scene/shapes.h"
#include "tests/bench/bench_clock.h"

namespace strata {
namespace {

constexpr uint32_t SEGMENTS = 1000;  // ~1M triangles

using bench::median;
using bench::now_ms;

std::unique_ptr<Engine> make_engine() {
    auto created = Engine::create();
    if (!created) {
        std::fprintf(stderr, "%s\n", created.error().describe().c_str());
        std::exit(1);
    }
    return std::move(created.value());
}

/// Adds the sphere with `build` (its id and instance change each call, so the commit builds it
/// anew) and returns that commit's report and wall time.
std::pair<RebuildReport, double> add_and_commit(Engine& engine, const MeshData& sphere,
                                                BuildOptions build, int round) {
    const std::string id = "sphere" + std::to_string(round);
    EditBatch batch;
    if (round > 0) {
        batch.edits.emplace_back(RemoveInstance{"sphere" + std::to_string(round - 1)});
        batch.edits.emplace_back(RemoveMesh{"sphere" + std::to_string(round - 1)});
    }
    batch.edits.emplace_back(add_mesh_edit(id, sphere, build));
    AddInstance inst;
    inst.id = id;
    inst.mesh = id;
    batch.edits.emplace_back(inst);
    SetCamera camera;
    camera.eye = Vec3(0.0f, 0.4f, 2.6f);
    camera.target = Vec3(0.0f);
    batch.edits.emplace_back(camera);
    if (auto applied = engine.apply(std::move(batch)); !applied) {
        std::fprintf(stderr, "%s\n", applied.error().describe().c_str());
        std::exit(1);
    }
    const double start = now_ms();
    auto r = engine.commit();
    const double ms = now_ms() - start;
    if (!r) {
        std::fprintf(stderr, "%s\n", r.error().describe().c_str());
        std::exit(1);
    }
    return {r.value(), ms};
}

double trace_ms(Engine& engine, Frame& frame) {
    PrimarySettings s;
    s.width = 1280;
    s.height = 720;
    const double start = now_ms();
    (void)engine.render_primary(s, frame);
    return now_ms() - start;
}

void run(int runs) {
    const MeshData sphere = make_sphere(1.0f, SEGMENTS);
    struct Setup {
        const char* name;
        BuildOptions build;
    };
    BuildOptions refit, fast_trace, fast_build;
    fast_trace.allow_refit = fast_build.allow_refit = false;
    fast_build.prefer = BuildPreference::FastBuild;
    const Setup setups[] = {{"allow_refit (LOW, DYNAMIC / REFIT)", refit},
                            {"fast_trace (HIGH / HIGH)", fast_trace},
                            {"fast_build (LOW, DYNAMIC / LOW)", fast_build}};

    std::printf("%zu triangles, %d runs\n\n", sphere.triangles.size(), runs);
    std::printf("| build setup | BLAS bytes full / compacted | saved | commit full / compacted | "
                "primary rays full / compacted |\n|---|---|---|---|---|\n");
    for (const Setup& setup : setups) {
        auto full = make_engine();
        auto compact = make_engine();
        BuildOptions compacted = setup.build;
        compacted.compact = true;
        std::vector<double> build_full, build_compact, trace_full, trace_compact;
        RebuildReport report;
        for (int i = 0; i < runs; ++i) {
            build_full.push_back(add_and_commit(*full, sphere, setup.build, i).second);
            auto [r, ms] = add_and_commit(*compact, sphere, compacted, i);
            build_compact.push_back(ms);
            report = r;
        }
        Frame fa, fb;
        trace_ms(*full, fa);  // warm
        trace_ms(*compact, fb);
        for (int i = 0; i < runs; ++i) {
            trace_full.push_back(trace_ms(*full, fa));
            trace_compact.push_back(trace_ms(*compact, fb));
        }
        const MeshBuildEntry& e = report.rebuilt.at(0);
        const double pixels = 1280.0 * 720.0;
        std::printf("| %s | %.1f / %.1f MB | %.0f%% | %.0f / %.0f ms | %.1f / %.1f Mrays/s |\n",
                    setup.name, double(e.uncompacted_bytes) / 1e6, double(e.bytes) / 1e6,
                    100.0 * double(e.uncompacted_bytes - e.bytes) / double(e.uncompacted_bytes),
                    median(build_full), median(build_compact),
                    pixels / median(trace_full) / 1e3, pixels / median(trace_compact) / 1e3);
        std::fflush(stdout);
    }
}

}  // namespace
}  // namespace strata

int main(int argc, char** argv) {
    const int runs = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
    const int threads = argc > 2 ? std::max(1, std::atoi(argv[2])) : 0;
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0)
        limit = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    strata::run(runs);
    return 0;
}
