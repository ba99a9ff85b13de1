// TLAS strategies against plain Embree, in one run. Never run by CTest.
//
//   build/tests/bench/strata_tlas_bench [--reps N] [--max-instances N] [--verbose 1]
//       [--rows move,batch,addremove,trace,memory,arrays] [--dynamic-medium-max N]
//
// Scene: n instances of one ~200-triangle sphere (make_sphere(0.45, 16): 224 triangles) on a
// square grid, 2 TBB threads (STRATA_BENCH_THREADS overrides). Engine side: an Engine with the
// incremental TLAS (its defaults: background merges on, 10% dynamic-tier limit), edited through
// Engine::apply and timed through Engine::commit; the table shows the commit's TLAS phase
// (report.phases.tlas_ms) and the whole commit. Baseline: a plain Embree instance scene at
// RTC_BUILD_QUALITY_MEDIUM (RTC_SCENE_FLAG_DYNAMIC, robust, as EmbreeTlas) over a plain BLAS
// (quality HIGH), where an edit is rtcSetGeometryTransform / attach / detach, then
// rtcCommitScene. Every row is the median of --reps repetitions (default 21). Trace rows time
// 640x360 primary rays in 4x4 packets, the engine's TLAS and the plain scene alternately, and
// report the median of per-pair speed ratios. The arrays rows trace fresh builds whose static
// tier is Embree instance geometries, then an instance array (TlasPolicy::array_min_instances),
// at sizes around the policy's threshold and above.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <embree3/rtcore.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include "engine/engine.h"
#include "engine/render/camera_rays.h"
#include "engine/scene/shapes.h"

namespace strata {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

constexpr float SPACING = 1.2f;
constexpr uint32_t SEGMENTS = 16;
constexpr uint32_t WIDTH = 640;
constexpr uint32_t HEIGHT = 360;

int side_of(int64_t n) {
    return int(std::ceil(std::sqrt(double(n))));
}

Affine place(int64_t cell, int64_t n, float dy = 0.0f) {
    const int side = side_of(n);
    return Affine::translation({float(cell % side) * SPACING, dy, float(cell / side) * SPACING});
}

Camera camera_for(int64_t n) {
    const float extent = float(side_of(n)) * SPACING;
    Camera c;
    c.eye = Vec3(0.5f * extent, 0.35f * extent + 3.0f, -0.15f * extent - 2.0f);
    c.target = Vec3(0.5f * extent, 0.0f, 0.45f * extent);
    c.up = Vec3(0.0f, 1.0f, 0.0f);
    c.fov_y_deg = 55.0f;
    return c;
}

/// The whole grid from beyond its far edge: most rays pass many distant instances' boxes.
Camera overview_for(int64_t n) {
    const float extent = float(side_of(n)) * SPACING;
    Camera c;
    c.eye = Vec3(0.5f * extent, 0.25f * extent, 1.1f * extent);
    c.target = Vec3(0.5f * extent, 0.0f, 0.55f * extent);
    c.up = Vec3(0.0f, 1.0f, 0.0f);
    c.fov_y_deg = 45.0f;
    return c;
}

// ---- plain Embree baseline -------------------------------------------------------------------

struct PlainMemory {
    std::atomic<int64_t> bytes{0};
};

bool on_memory(void* p, ssize_t bytes, bool) {
    static_cast<PlainMemory*>(p)->bytes.fetch_add(bytes);
    return true;
}

class PlainEmbree {
public:
    explicit PlainEmbree(const MeshData& mesh) {
        m_device = rtcNewDevice(nullptr);
        rtcSetDeviceMemoryMonitorFunction(m_device, on_memory, &m_memory);
        m_blas = rtcNewScene(m_device);
        rtcSetSceneBuildQuality(m_blas, RTC_BUILD_QUALITY_HIGH);
        rtcSetSceneFlags(m_blas, RTC_SCENE_FLAG_ROBUST);
        RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
        auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, mesh.positions.size()));
        std::memcpy(v, mesh.positions.data(), mesh.positions.size() * 12);
        auto* t = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, mesh.triangles.size()));
        std::memcpy(t, mesh.triangles.data(), mesh.triangles.size() * 12);
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(m_blas, g, 0);
        rtcReleaseGeometry(g);
        rtcCommitScene(m_blas);
        m_blas_bytes = m_memory.bytes.load();
    }
    ~PlainEmbree() {
        clear();
        rtcReleaseScene(m_blas);
        rtcReleaseDevice(m_device);
    }

    /// A fresh TLAS over `transforms` (one instance each, attached by index).
    void build(const std::vector<Affine>& transforms) {
        clear();
        m_tlas = rtcNewScene(m_device);
        rtcSetSceneBuildQuality(m_tlas, RTC_BUILD_QUALITY_MEDIUM);
        rtcSetSceneFlags(m_tlas, RTCSceneFlags(RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST));
        m_geoms.resize(transforms.size());
        for (std::size_t i = 0; i < transforms.size(); ++i) m_geoms[i] = make(transforms[i]);
        for (std::size_t i = 0; i < transforms.size(); ++i)
            rtcAttachGeometryByID(m_tlas, m_geoms[i], uint32_t(i));
        rtcCommitScene(m_tlas);
    }
    void move(uint32_t i, const Affine& a) {
        rtcSetGeometryTransform(m_geoms[i], 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, a.m.data());
        rtcCommitGeometry(m_geoms[i]);
    }
    void add(const Affine& a) {
        m_geoms.push_back(make(a));
        rtcAttachGeometryByID(m_tlas, m_geoms.back(), uint32_t(m_geoms.size() - 1));
    }
    void remove_last() {
        rtcDetachGeometry(m_tlas, uint32_t(m_geoms.size() - 1));
        rtcReleaseGeometry(m_geoms.back());
        m_geoms.pop_back();
    }
    void commit() { rtcCommitScene(m_tlas); }
    RTCScene tlas() const { return m_tlas; }
    int64_t tlas_bytes() const { return m_memory.bytes.load() - m_blas_bytes; }

private:
    RTCGeometry make(const Affine& a) {
        RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_INSTANCE);
        rtcSetGeometryInstancedScene(g, m_blas);
        rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, a.m.data());
        rtcCommitGeometry(g);
        return g;
    }
    void clear() {
        for (RTCGeometry g : m_geoms) rtcReleaseGeometry(g);
        m_geoms.clear();
        if (m_tlas) rtcReleaseScene(m_tlas);
        m_tlas = nullptr;
    }

    PlainMemory m_memory;
    RTCDevice m_device = nullptr;
    RTCScene m_blas = nullptr;
    RTCScene m_tlas = nullptr;
    std::vector<RTCGeometry> m_geoms;
    int64_t m_blas_bytes = 0;
};

// ---- engine side -----------------------------------------------------------------------------

struct EngineScene {
    std::unique_ptr<Engine> engine;
    std::vector<Affine> transforms;  ///< by instance index "i<k>"
    int64_t n = 0;
    double first_build_tlas_ms = 0.0;  ///< the first commit's TLAS phase
};

EngineScene engine_scene(int64_t n, const MeshData& mesh, const TlasPolicy& policy) {
    EngineConfig config;
    config.accel.tlas = TlasKind::Incremental;
    config.accel.tlas_policy = policy;
    config.budget.max_triangles = uint64_t(1) << 32;
    EngineScene s;
    s.engine = std::move(Engine::create(config).value());
    s.n = n;
    EditBatch b;
    BuildOptions build;
    build.allow_refit = false;  // HIGH quality, as the plain BLAS
    b.edits.emplace_back(add_mesh_edit("ball", mesh, build));
    s.transforms.reserve(std::size_t(n));
    for (int64_t i = 0; i < n; ++i) {
        AddInstance inst;
        inst.id = "i" + std::to_string(i);
        inst.mesh = "ball";
        inst.transform = place(i, n);
        s.transforms.push_back(inst.transform);
        b.edits.emplace_back(std::move(inst));
    }
    const Camera c = camera_for(n);
    SetCamera sc;
    sc.eye = c.eye;
    sc.target = c.target;
    sc.fov_y_deg = c.fov_y_deg;
    b.edits.emplace_back(sc);
    auto applied = s.engine->apply(std::move(b));
    if (!applied) {
        std::fprintf(stderr, "apply: %s\n", applied.error().describe().c_str());
        std::exit(1);
    }
    auto first = s.engine->commit();
    if (first) s.first_build_tlas_ms = first->phases.tlas_ms;
    return s;
}

struct CommitCost {
    double tlas_ms = 0.0;
    double total_ms = 0.0;
};

bool g_verbose = false;

CommitCost commit(Engine& e) {
    auto r = e.commit();
    if (!r) {
        std::fprintf(stderr, "commit: %s\n", r.error().describe().c_str());
        std::exit(1);
    }
    if (g_verbose) {
        std::printf(
            "  commit tlas %.3f ms: static %llu dynamic %llu stale %llu swapped %d "
            "(built in %.1f ms) running %d static_rebuild '%s'\n",
            r->phases.tlas_ms, static_cast<unsigned long long>(r->tlas.static_instances),
            static_cast<unsigned long long>(r->tlas.dynamic_instances),
            static_cast<unsigned long long>(r->tlas.stale_copies), r->tlas.merge_swapped,
            r->tlas.merge_build_ms, r->tlas.merge_running, r->tlas.static_rebuild);
    }
    return {r->phases.tlas_ms, r->phases.total_ms};
}

// ---- primary-ray tracing -----------------------------------------------------------------

/// 4x4-pixel packets of camera rays over the frame, traced by `trace(valid, packet)`.
template <class Trace>
void trace_frame(const Camera& camera, Trace&& trace) {
    const CameraRays rays(camera, WIDTH, HEIGHT);
    const uint32_t bx = WIDTH / 4, by = HEIGHT / 4;
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, bx * by, 64), [&](auto range) {
        RayHit16 packet;
        ValidMask16 valid;
        for (uint32_t b = range.begin(); b != range.end(); ++b) {
            const uint32_t x0 = (b % bx) * 4, y0 = (b / bx) * 4;
            float px[16], py[16];
            for (uint32_t i = 0; i < 16; ++i) {
                px[i] = float(x0 + i % 4) + 0.5f;
                py[i] = float(y0 + i / 4) + 0.5f;
            }
            rays.directions(px, py, 16, packet.dir_x, packet.dir_y, packet.dir_z);
            for (uint32_t i = 0; i < 16; ++i) {
                packet.org_x[i] = rays.eye().x;
                packet.org_y[i] = rays.eye().y;
                packet.org_z[i] = rays.eye().z;
                packet.tnear[i] = 0.0f;
                packet.tfar[i] = std::numeric_limits<float>::infinity();
                packet.time[i] = 0.0f;
                packet.mask[i] = 0xFFFFFFFFu;
                packet.flags[i] = 0;
                packet.geom_id[i] = packet.inst_id[i] = INVALID_ID;
                valid.lanes[i] = -1;
            }
            trace(valid, packet);
        }
    });
}

double engine_frame_ms(Engine& e, const Camera& camera) {
    const auto t = Clock::now();
    (void)e.launch([&](const FrameState&, const TlasStrategy& tlas, const RebuildReport&) {
        trace_frame(camera,
                    [&](const ValidMask16& v, RayHit16& p) { tlas.intersect16(v, p, true); });
        return true;
    });
    return ms_since(t);
}

double plain_frame_ms(RTCScene scene, const Camera& camera) {
    const auto t = Clock::now();
    trace_frame(camera, [&](const ValidMask16& v, RayHit16& p) {
        for (uint32_t i = 0; i < 16; ++i) {
            if (!v.lanes[i]) {
                p.tnear[i] = 1.0f;
                p.tfar[i] = 0.0f;
            }
        }
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        rtcIntersect16(v.lanes, scene, &ctx, reinterpret_cast<RTCRayHit16*>(&p));
    });
    return ms_since(t);
}

/// Median over `reps` pairs of (plain frame time / engine frame time): > 1 means the engine is
/// faster. The order alternates so both see the same load.
double speed_ratio(Engine& e, RTCScene plain, const Camera& camera, int reps) {
    engine_frame_ms(e, camera);  // warm-up
    plain_frame_ms(plain, camera);
    std::vector<double> ratios;
    for (int r = 0; r < reps; ++r) {
        double a, b;
        if (r % 2) {
            a = engine_frame_ms(e, camera);
            b = plain_frame_ms(plain, camera);
        } else {
            b = plain_frame_ms(plain, camera);
            a = engine_frame_ms(e, camera);
        }
        ratios.push_back(b / a);
    }
    return median(ratios);
}

// ---- rows --------------------------------------------------------------------------------

struct Options {
    int reps = 21;
    int64_t max_instances = 1000000;
    std::string rows = "move,batch,addremove,trace,memory";
    TlasPolicy policy;  ///< the engine side's (--dynamic-medium-max sets one field)
};

void print_row(const char* work, double engine_tlas, double engine_total, double plain,
               const char* target) {
    std::printf("| %-34s | %10.3f | %10.3f | %10.3f | %8.1fx | %-14s |\n", work, engine_tlas,
                engine_total, plain, plain / engine_tlas, target);
    std::fflush(stdout);
}

/// Move one random instance per repetition, each its own commit.
void move_rows(const Options& o, const MeshData& mesh) {
    std::mt19937 rng(1);
    std::vector<double> medians;
    for (int64_t n : {int64_t(10000), int64_t(100000), int64_t(1000000)}) {
        if (n > o.max_instances) continue;
        EngineScene s = engine_scene(n, mesh, o.policy);
        PlainEmbree plain(mesh);
        plain.build(s.transforms);
        std::vector<double> tlas, total, base;
        std::uniform_int_distribution<int64_t> pick(0, n - 1);
        for (int r = 0; r < o.reps; ++r) {
            const int64_t i = pick(rng);
            const Affine a = place(i, n, 0.1f * float(r % 5 + 1));
            (void)s.engine->apply(EditBatch{{SetTransform{"i" + std::to_string(i), a}}});
            const CommitCost c = commit(*s.engine);
            tlas.push_back(c.tlas_ms);
            total.push_back(c.total_ms);
            const auto t = Clock::now();
            plain.move(uint32_t(i), a);
            plain.commit();
            base.push_back(ms_since(t));
        }
        char label[64];
        std::snprintf(label, sizeof label, "move 1 of %lld", static_cast<long long>(n));
        print_row(label, median(tlas), median(total), median(base),
                  n == 1000000  ? ">=100x"
                  : n == 100000 ? ">=20x"
                                : "");
        medians.push_back(median(tlas));
    }
    if (medians.size() == 3)
        std::printf("| cost growth 10k -> 1M (move 1)     | %9.2fx | (target < 3x)\n",
                    medians[2] / medians[0]);
}

/// Move 1% of 100k instances in one batch.
void batch_row(const Options& o, const MeshData& mesh) {
    const int64_t n = std::min<int64_t>(100000, o.max_instances);
    EngineScene s = engine_scene(n, mesh, o.policy);
    PlainEmbree plain(mesh);
    plain.build(s.transforms);
    std::mt19937 rng(2);
    std::uniform_int_distribution<int64_t> pick(0, n - 1);
    std::vector<double> tlas, total, base;
    for (int r = 0; r < o.reps; ++r) {
        EditBatch b;
        std::vector<std::pair<int64_t, Affine>> moved;
        for (int64_t k = 0; k < n / 100; ++k) {
            const int64_t i = pick(rng);
            const Affine a = place(i, n, 0.1f * float(r % 5 + 1));
            b.edits.emplace_back(SetTransform{"i" + std::to_string(i), a});
            moved.emplace_back(i, a);
        }
        (void)s.engine->apply(std::move(b));
        const CommitCost c = commit(*s.engine);
        tlas.push_back(c.tlas_ms);
        total.push_back(c.total_ms);
        const auto t = Clock::now();
        for (const auto& [i, a] : moved) plain.move(uint32_t(i), a);
        plain.commit();
        base.push_back(ms_since(t));
    }
    print_row("move 1% of 100k in one batch", median(tlas), median(total), median(base), ">=5x");
}

/// Add one instance, then remove it, each its own commit.
void add_remove_rows(const Options& o, const MeshData& mesh) {
    const int64_t n = std::min<int64_t>(100000, o.max_instances);
    EngineScene s = engine_scene(n, mesh, o.policy);
    PlainEmbree plain(mesh);
    plain.build(s.transforms);
    std::vector<double> add_tlas, add_total, add_base, rm_tlas, rm_total, rm_base;
    for (int r = 0; r < o.reps; ++r) {
        const Affine a = place(r * 7919 % n, n, 1.0f);
        AddInstance inst;
        inst.id = "extra";
        inst.mesh = "ball";
        inst.transform = a;
        (void)s.engine->apply(EditBatch{{inst}});
        CommitCost c = commit(*s.engine);
        add_tlas.push_back(c.tlas_ms);
        add_total.push_back(c.total_ms);
        auto t = Clock::now();
        plain.add(a);
        plain.commit();
        add_base.push_back(ms_since(t));

        (void)s.engine->apply(EditBatch{{RemoveInstance{"extra"}}});
        c = commit(*s.engine);
        rm_tlas.push_back(c.tlas_ms);
        rm_total.push_back(c.total_ms);
        t = Clock::now();
        plain.remove_last();
        plain.commit();
        rm_base.push_back(ms_since(t));
    }
    print_row("add 1 of 100k", median(add_tlas), median(add_total), median(add_base), ">=20x");
    print_row("remove 1 of 100k", median(rm_tlas), median(rm_total), median(rm_base), ">=20x");
}

/// Trace speed right after a fresh build, and after 1000 frames of random single moves.
void trace_rows(const Options& o, const MeshData& mesh) {
    const int64_t n = std::min<int64_t>(100000, o.max_instances);
    const Camera camera = camera_for(n);
    const int reps = std::max(o.reps, 15);
    for (bool merges : {true, false}) {
        TlasPolicy policy = o.policy;
        policy.background_merge = merges;
        EngineScene s = engine_scene(n, mesh, policy);
        PlainEmbree plain(mesh);
        if (merges) {
            plain.build(s.transforms);
            std::printf(
                "| trace, fresh build (%lldk)          | speed %.3fx plain Embree "
                "(target >= 0.97x)\n",
                static_cast<long long>(n / 1000),
                speed_ratio(*s.engine, plain.tlas(), camera, reps));
        }
        std::mt19937 rng(3);
        std::uniform_int_distribution<int64_t> pick(0, n - 1);
        std::vector<double> tlas;
        RebuildReport last;
        for (int frame = 0; frame < 1000; ++frame) {
            const int64_t i = pick(rng);
            const Affine a = place(i, n, 0.2f + 0.1f * float(frame % 7));
            s.transforms[std::size_t(i)] = a;
            (void)s.engine->apply(EditBatch{{SetTransform{"i" + std::to_string(i), a}}});
            auto r = s.engine->commit();
            tlas.push_back(r->phases.tlas_ms);
            last = *r;
        }
        // The TLAS the 1000th commit left: a merge still building finishes first so it does
        // not compete for the cores, but it is not swapped in (that takes another commit).
        s.engine->wait_for_background();
        plain.build(s.transforms);
        const double ratio = speed_ratio(*s.engine, plain.tlas(), camera, reps);
        std::printf(
            "| trace after 1000 single moves (%s) | speed %.3fx a fresh Embree TLAS "
            "(target >= 0.90x); tiers static %llu dynamic %llu stale %llu; "
            "commit tlas_ms median %.3f; memory tlas %.1f MB vs plain %.1f MB (%.2fx)\n",
            merges ? "merges on " : "merges off", ratio,
            static_cast<unsigned long long>(last.tlas.static_instances),
            static_cast<unsigned long long>(last.tlas.dynamic_instances),
            static_cast<unsigned long long>(last.tlas.stale_copies), median(tlas),
            double(last.memory_tlas_bytes) / 1e6, double(plain.tlas_bytes()) / 1e6,
            double(last.memory_tlas_bytes) / double(plain.tlas_bytes()));
        std::fflush(stdout);
    }
}

/// Trace speed of a fresh static tier of each kind against plain Embree, from the trace rows'
/// camera and from overview_for's, and the commit that built it (its TLAS phase).
void array_rows(const Options& o, const MeshData& mesh) {
    const int reps = std::max(o.reps, 15);
    for (const int64_t n : {10000, 20000, 40000, 100000, 1000000}) {
        if (n > o.max_instances) continue;
        PlainEmbree plain(mesh);
        double near[2] = {}, far[2] = {}, build_ms[2] = {};
        for (const bool array : {false, true}) {
            TlasPolicy policy = o.policy;
            policy.array_min_instances = array ? 0 : std::numeric_limits<uint32_t>::max();
            EngineScene s = engine_scene(n, mesh, policy);
            build_ms[array] = s.first_build_tlas_ms;
            if (!array) plain.build(s.transforms);
            near[array] = speed_ratio(*s.engine, plain.tlas(), camera_for(n), reps);
            far[array] = speed_ratio(*s.engine, plain.tlas(), overview_for(n), reps);
        }
        std::printf(
            "| trace, fresh build (%lldk) | speed vs plain Embree, geometries / instance array: "
            "near %.3fx / %.3fx, overview %.3fx / %.3fx; first build tlas_ms %.1f / %.1f\n",
            static_cast<long long>(n / 1000), near[0], near[1], far[0], far[1], build_ms[0],
            build_ms[1]);
        std::fflush(stdout);
    }
}

/// TLAS memory after a fresh build and at its peak while a merge holds a second static tier.
void memory_rows(const Options& o, const MeshData& mesh) {
    for (int64_t n : {int64_t(100000), int64_t(1000000)}) {
        if (n > o.max_instances) continue;
        EngineScene s = engine_scene(n, mesh, o.policy);
        const int64_t fresh = s.engine->memory_bytes(MemoryCategory::Tlas);
        (void)s.engine->apply(EditBatch{{SetTransform{"i1", place(1, n, 0.5f)}}});
        commit(*s.engine);
        s.engine->wait_for_background();
        const int64_t peak = s.engine->memory_bytes(MemoryCategory::Tlas);  // both static tiers
        commit(*s.engine);                                                  // swap
        s.engine->wait_for_background();  // the old static tier is released off the commit
        const int64_t after = s.engine->memory_bytes(MemoryCategory::Tlas);
        PlainEmbree plain(mesh);
        plain.build(s.transforms);
        const double p = double(plain.tlas_bytes());
        std::printf(
            "| memory %lldk: plain %.1f MB; incremental fresh %.1f MB (%.2fx), during a "
            "merge %.1f MB (%.2fx), after the swap and release %.1f MB (%.2fx); "
            "target <= 2.5x\n",
            static_cast<long long>(n / 1000), p / 1e6, double(fresh) / 1e6, double(fresh) / p,
            double(peak) / 1e6, double(peak) / p, double(after) / 1e6, double(after) / p);
        std::fflush(stdout);
    }
}

}  // namespace
}  // namespace strata

int main(int argc, char** argv) {
    using namespace strata;
    Options o;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string flag = argv[i];
        if (flag == "--reps") o.reps = std::max(1, std::atoi(argv[i + 1]));
        if (flag == "--max-instances") o.max_instances = std::atoll(argv[i + 1]);
        if (flag == "--rows") o.rows = argv[i + 1];
        if (flag == "--verbose") g_verbose = std::atoi(argv[i + 1]) != 0;
        if (flag == "--dynamic-medium-max")
            o.policy.dynamic_medium_max = uint32_t(std::strtoul(argv[i + 1], nullptr, 10));
    }
    const char* env = std::getenv("STRATA_BENCH_THREADS");
    const int threads = env ? std::max(1, std::atoi(env)) : 2;
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    const MeshData mesh = make_sphere(0.45f, SEGMENTS);
    std::printf("tlas_bench: %d threads, %d repetitions (medians), sphere of %zu triangles\n\n",
                threads, o.reps, mesh.triangles.size());
    std::printf("| %-34s | %10s | %10s | %10s | %9s | %-14s |\n", "work", "tlas ms", "commit ms",
                "embree ms", "speed-up", "target");
    std::printf("|%s|%s|%s|%s|%s|%s|\n", std::string(36, '-').c_str(), std::string(12, '-').c_str(),
                std::string(12, '-').c_str(), std::string(12, '-').c_str(),
                std::string(11, '-').c_str(), std::string(16, '-').c_str());
    auto wants = [&](const std::string& row) {
        return ("," + o.rows + ",").find("," + row + ",") != std::string::npos;
    };
    if (wants("move")) move_rows(o, mesh);
    if (wants("batch")) batch_row(o, mesh);
    if (wants("addremove")) add_remove_rows(o, mesh);
    if (wants("trace")) trace_rows(o, mesh);
    if (wants("memory")) memory_rows(o, mesh);
    if (wants("arrays")) array_rows(o, mesh);
    return 0;
}
