// Renderer benchmarks (never run by CTest; results and method in tests/bench/NOTES.md).
//
// Primary rays at 1280x720 through the engine (Engine::render_primary: commit check, launch,
// packets, hit buffers) against plain Embree loops (rtcIntersect1 and rtcIntersect16) over an
// equivalent Embree scene built here: the same meshes with the same build qualities the engine's
// BlasStore and EmbreeTlas choose, the same instance transforms, the same rays (CameraRays over
// the same fixed tile grid) and the same coherent context flag. BM_PrimaryRatio times them frame
// by frame in rotation and reports the engine's relative speed: the headline number, steady even
// on a busy machine. Full frames (BM_EngineRender) and the encoders are measured too.
//
//   strata_render_bench --benchmark_repetitions=15 --benchmark_enable_random_interleaving=true
//       --benchmark_report_aggregates_only=true [STRATA_BENCH_THREADS=N in the environment]

#include <optional>
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>
#include <embree3/rtcore.h>
#include <tbb/global_control.h>

#include "engine/engine.h"
#include "engine/image/exr.h"
#include "engine/image/highlight.h"
#include "engine/image/jpeg_encode.h"
#include "engine/image/png.h"
#include "engine/image/tonemap.h"
#include "engine/render/camera_rays.h"
#include "engine/render/frame_encode.h"
#include "engine/render/tiles.h"
#include "engine/scene/demo_scene.h"
#include "engine/scene/shapes.h"

namespace strata {
namespace {

constexpr uint32_t WIDTH = 1280, HEIGHT = 720;
/// Build options of the benchmark meshes; PlainScene mirrors what BlasStore does with them.
constexpr BuildOptions BUILD{BuildPreference::FastTrace, false};

struct InstanceDesc {
    uint32_t mesh;
    Affine transform;
};

/// A scene description both the engine and the plain Embree loops are built from.
struct SceneDesc {
    std::vector<MeshData> meshes;
    std::vector<InstanceDesc> instances;
    Camera camera;
};

/// (a) one sphere of about a million triangles filling most of the frame.
SceneDesc mesh_1m() {
    SceneDesc d;
    d.meshes.push_back(make_sphere(1.0f, 1000));
    d.instances.push_back({0, Affine::identity()});
    d.camera.eye = Vec3(0.0f, 0.3f, 2.6f);
    d.camera.target = Vec3(0.0f);
    return d;
}

/// (b) 100 x 100 instances of a 224-triangle sphere on a grid, seen at an angle.
SceneDesc instances_10k() {
    SceneDesc d;
    d.meshes.push_back(make_sphere(0.45f, 16));
    for (int z = 0; z < 100; ++z) {
        for (int x = 0; x < 100; ++x)
            d.instances.push_back(
                {0, Affine::translation({float(x) - 49.5f, 0.0f, float(z) - 49.5f})});
    }
    d.camera.eye = Vec3(0.0f, 25.0f, 60.0f);
    d.camera.target = Vec3(0.0f, 0.0f, 5.0f);
    return d;
}

/// The scene as an engine; `material`, when given, is every mesh's default material.
std::unique_ptr<Engine> make_engine(const SceneDesc& d,
                                    const std::optional<Material>& material = std::nullopt) {
    auto engine = std::move(Engine::create().value());
    EditBatch b;
    if (material) b.edits.emplace_back(AddMaterial{"material", *material});
    for (std::size_t m = 0; m < d.meshes.size(); ++m) {
        AddMesh e;
        e.id = "m" + std::to_string(m);
        e.positions = d.meshes[m].positions;
        e.triangles = d.meshes[m].triangles;
        e.build = BUILD;
        if (material) e.material = "material";
        b.edits.emplace_back(std::move(e));
    }
    for (std::size_t i = 0; i < d.instances.size(); ++i) {
        AddInstance e;
        e.id = "i" + std::to_string(i);
        e.mesh = "m" + std::to_string(d.instances[i].mesh);
        e.transform = d.instances[i].transform;
        b.edits.emplace_back(std::move(e));
    }
    SetCamera c;
    c.eye = d.camera.eye;
    c.target = d.camera.target;
    c.up = d.camera.up;
    c.fov_y_deg = d.camera.fov_y_deg;
    b.edits.emplace_back(c);
    STRATA_CHECK(engine->apply(std::move(b)).has_value());
    STRATA_CHECK(engine->commit().has_value());
    return engine;
}

/// The same scene in plain Embree: BLAS scenes with BlasStore's qualities for BUILD (HIGH scene
/// and geometry quality, ROBUST as the engine's default watertight mode), a top-level scene with
/// EmbreeTlas's settings (MEDIUM, DYNAMIC, ROBUST) holding one instance geometry per instance,
/// attached by index.
class PlainScene {
public:
    explicit PlainScene(const SceneDesc& d) {
        m_device = rtcNewDevice(nullptr);
        for (const MeshData& mesh : d.meshes) {
            RTCScene s = rtcNewScene(m_device);
            rtcSetSceneBuildQuality(s, RTC_BUILD_QUALITY_HIGH);
            rtcSetSceneFlags(s, RTC_SCENE_FLAG_ROBUST);
            RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_TRIANGLE);
            rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_HIGH);
            auto* v = static_cast<Vec3*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                                 RTC_FORMAT_FLOAT3, sizeof(Vec3),
                                                                 mesh.positions.size()));
            std::copy(mesh.positions.begin(), mesh.positions.end(), v);
            auto* t = static_cast<Triangle*>(
                rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                        sizeof(Triangle), mesh.triangles.size()));
            std::copy(mesh.triangles.begin(), mesh.triangles.end(), t);
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(s, g, 0);
            rtcReleaseGeometry(g);
            rtcCommitScene(s);
            m_blas.push_back(s);
        }
        m_top = rtcNewScene(m_device);
        rtcSetSceneBuildQuality(m_top, RTC_BUILD_QUALITY_MEDIUM);
        rtcSetSceneFlags(m_top, RTCSceneFlags(RTC_SCENE_FLAG_DYNAMIC | RTC_SCENE_FLAG_ROBUST));
        for (std::size_t i = 0; i < d.instances.size(); ++i) {
            RTCGeometry g = rtcNewGeometry(m_device, RTC_GEOMETRY_TYPE_INSTANCE);
            rtcSetGeometryInstancedScene(g, m_blas[d.instances[i].mesh]);
            rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR,
                                    d.instances[i].transform.m.data());
            rtcCommitGeometry(g);
            rtcAttachGeometryByID(m_top, g, unsigned(i));
            rtcReleaseGeometry(g);
        }
        rtcCommitScene(m_top);
        STRATA_CHECK(rtcGetDeviceError(m_device) == RTC_ERROR_NONE);
    }
    ~PlainScene() {
        rtcReleaseScene(m_top);
        for (RTCScene s : m_blas) rtcReleaseScene(s);
        rtcReleaseDevice(m_device);
    }
    PlainScene(const PlainScene&) = delete;
    PlainScene& operator=(const PlainScene&) = delete;

    RTCScene scene() const { return m_top; }

private:
    RTCDevice m_device = nullptr;
    std::vector<RTCScene> m_blas;
    RTCScene m_top = nullptr;
};

/// Both versions of one benchmark scene, built once.
struct Fixture {
    SceneDesc desc;
    std::unique_ptr<Engine> engine;
    std::unique_ptr<PlainScene> plain;
};

const Fixture& fixture(int which) {
    static std::unique_ptr<Fixture> fixtures[2];
    if (!fixtures[which]) {
        auto f = std::make_unique<Fixture>();
        f->desc = which == 0 ? mesh_1m() : instances_10k();
        f->engine = make_engine(f->desc);
        f->plain = std::make_unique<PlainScene>(f->desc);
        fixtures[which] = std::move(f);
    }
    return *fixtures[which];
}

/// The fixture a benchmark's first argument names, with its name as the benchmark's label.
const Fixture& fixture_of(benchmark::State& state) {
    const int which = int(state.range(0));
    state.SetLabel(which == 0 ? "mesh_1m" : "instances_10k");
    return fixture(which);
}

/// The plain loops' output: what a minimal caller keeps of a hit.
struct PlainHit {
    float t;
    uint32_t inst;
    uint32_t prim;
};

/// The fastest repetition: contention from other processes only ever adds time, so on a busy
/// machine the minimum is the steadiest estimate (reported next to the median).
double min_of(const std::vector<double>& v) {
    return *std::min_element(v.begin(), v.end());
}

void report(benchmark::State& state, double rays_per_iteration) {
    state.counters["Mrays/s"] = benchmark::Counter(rays_per_iteration * 1e-6,
                                                   benchmark::Counter::kIsIterationInvariantRate);
}

/// One frame of pixel-centre packets over the tile grid, each traced by `trace(valid, packet)`;
/// keeps what a minimal caller keeps of each hit.
template <class Trace>
void trace_frame16(const CameraRays& rays, std::vector<PlainHit>& out, Trace&& trace) {
    parallel_for_tiles(WIDTH, HEIGHT, [&](const TileRect& tile) {
        CameraPacket camera(rays);
        ValidMask16 valid;
        for (uint32_t y0 = tile.y0; y0 < tile.y1; y0 += PACKET_SIZE) {
            for (uint32_t x0 = tile.x0; x0 < tile.x1; x0 += PACKET_SIZE) {
                packet_lanes(tile, x0, y0, valid);
                RayHit16& packet = camera.aim_centres(x0, y0);
                trace(valid, packet);
                for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                    if (!valid[i]) continue;
                    out[std::size_t(y0 + i / PACKET_SIZE) * WIDTH + x0 + i % PACKET_SIZE] = {
                        packet.tfar[i], packet.inst_id[i], packet.prim_id[i]};
                }
            }
        }
    });
}

/// The frame loops measured, each writing into buffers the caller keeps across frames.
class FrameLoops {
public:
    explicit FrameLoops(const Fixture& f)
        : m_fixture(f), m_rays(f.desc.camera, WIDTH, HEIGHT), m_out(std::size_t(WIDTH) * HEIGHT) {
        m_settings.width = WIDTH;
        m_settings.height = HEIGHT;
    }

    /// Engine::render_primary into a reused frame: the engine's primary-ray path.
    void engine_primary() {
        STRATA_CHECK(m_fixture.engine->render_primary(m_settings, m_frame).has_value());
        benchmark::DoNotOptimize(m_frame.buffers.depth.data());
    }

    /// The by-value Engine::render_primary: adds allocating (and page-faulting) 33 MB of hit
    /// buffers per frame.
    void engine_primary_new_buffers() {
        auto frame = m_fixture.engine->render_primary(m_settings);
        benchmark::DoNotOptimize(frame.value().buffers.depth.data());
    }

    /// The plain rtcIntersect16 loop, but tracing through the engine's TlasStrategy inside a
    /// launch: separates the engine's acceleration structures from its hit buffers.
    void engine_tlas16() {
        auto launched = m_fixture.engine->launch(
            [&](const FrameState&, const TlasStrategy& tlas, const RebuildReport&) {
                trace_frame16(m_rays, m_out, [&](const ValidMask16& valid, RayHit16& packet) {
                    tlas.intersect16(valid, packet, true);
                });
                return true;
            });
        STRATA_CHECK(launched.has_value());
        benchmark::DoNotOptimize(m_out.data());
    }

    void plain_intersect16() {
        RTCScene scene = m_fixture.plain->scene();
        trace_frame16(m_rays, m_out, [&](const ValidMask16& valid, RayHit16& packet) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcIntersect16(valid.lanes, scene, &ctx, reinterpret_cast<RTCRayHit16*>(&packet));
        });
        benchmark::DoNotOptimize(m_out.data());
    }

    void plain_intersect1() {
        RTCScene scene = m_fixture.plain->scene();
        parallel_for_tiles(WIDTH, HEIGHT, [&](const TileRect& tile) {
            RTCIntersectContext ctx;
            rtcInitIntersectContext(&ctx);
            ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            const Vec3 e = m_rays.eye();
            for (uint32_t y = tile.y0; y < tile.y1; ++y) {
                for (uint32_t x = tile.x0; x < tile.x1; ++x) {
                    RayHit1 r;
                    const Vec3 d = m_rays.direction(float(x) + 0.5f, float(y) + 0.5f);
                    r.org_x = e.x, r.org_y = e.y, r.org_z = e.z, r.tnear = 0.0f;
                    r.dir_x = d.x, r.dir_y = d.y, r.dir_z = d.z, r.time = 0.0f;
                    r.tfar = std::numeric_limits<float>::infinity();
                    r.mask = 0xFFFFFFFFu, r.id = 0, r.flags = 0;
                    r.geom_id = r.inst_id = r.prim_id = INVALID_ID;
                    rtcIntersect1(scene, &ctx, reinterpret_cast<RTCRayHit*>(&r));
                    m_out[std::size_t(y) * WIDTH + x] = {r.tfar, r.inst_id, r.prim_id};
                }
            }
        });
        benchmark::DoNotOptimize(m_out.data());
    }

    /// Fraction of the last plain or TLAS frame's rays that hit something.
    double hit_fraction() const {
        const auto hits = std::count_if(m_out.begin(), m_out.end(),
                                        [](const PlainHit& h) { return h.inst != INVALID_ID; });
        return double(hits) / double(m_out.size());
    }

private:
    const Fixture& m_fixture;
    const CameraRays m_rays;
    PrimarySettings m_settings;
    Frame m_frame;
    std::vector<PlainHit> m_out;
};

/// A benchmark of one frame loop over one fixture.
template <void (FrameLoops::*LOOP)()>
void BM_Frame(benchmark::State& state) {
    FrameLoops loops(fixture_of(state));
    for (auto _ : state) (loops.*LOOP)();
    report(state, double(WIDTH) * HEIGHT);
}

void BM_EnginePrimary(benchmark::State& s) {
    BM_Frame<&FrameLoops::engine_primary>(s);
}
void BM_EnginePrimaryNewBuffers(benchmark::State& s) {
    BM_Frame<&FrameLoops::engine_primary_new_buffers>(s);
}
void BM_EngineTlas16(benchmark::State& s) {
    BM_Frame<&FrameLoops::engine_tlas16>(s);
}
void BM_PlainIntersect16(benchmark::State& s) {
    BM_Frame<&FrameLoops::plain_intersect16>(s);
}
void BM_PlainIntersect1(benchmark::State& s) {
    BM_Frame<&FrameLoops::plain_intersect1>(s);
}

/// The engine against the plain loops, frame after frame in rotating order: each iteration times
/// one frame of each loop, and the counters are medians over iterations of the engine's speed
/// relative to a plain loop (above 1: the engine is faster). Frames next to each other see the
/// same load, so on a shared machine these ratios are far steadier than ratios of separately
/// timed benchmarks.
void BM_PrimaryRatio(benchmark::State& state) {
    FrameLoops loops(fixture_of(state));
    using Loop = void (FrameLoops::*)();
    enum { PLAIN16, PLAIN1, PRIMARY, TLAS16, LOOPS };
    const Loop loop[LOOPS] = {&FrameLoops::plain_intersect16, &FrameLoops::plain_intersect1,
                              &FrameLoops::engine_primary, &FrameLoops::engine_tlas16};
    std::vector<double> ratios[3];  // primary vs plain16, primary vs plain1, tlas16 vs plain16
    uint32_t rotation = 0;
    for (auto _ : state) {
        double ms[LOOPS];
        for (uint32_t k = 0; k < LOOPS; ++k) {
            const uint32_t which = (k + rotation) % LOOPS;
            const auto t0 = std::chrono::steady_clock::now();
            (loops.*loop[which])();
            const auto t1 = std::chrono::steady_clock::now();
            ms[which] = std::chrono::duration<double, std::milli>(t1 - t0).count();
        }
        ++rotation;
        ratios[0].push_back(ms[PLAIN16] / ms[PRIMARY]);
        ratios[1].push_back(ms[PLAIN1] / ms[PRIMARY]);
        ratios[2].push_back(ms[PLAIN16] / ms[TLAS16]);
    }
    auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        return v.empty() ? 0.0 : v[v.size() / 2];
    };
    state.counters["primary_vs_16"] = median(ratios[0]);
    state.counters["primary_vs_1"] = median(ratios[1]);
    state.counters["tlas16_vs_16"] = median(ratios[2]);
    state.counters["hit_fraction"] = loops.hit_fraction();
}

/// Renders WIDTH x HEIGHT frames at 1 spp for the benchmark's iterations and reports rays.
void render_frames(benchmark::State& state, Engine& engine) {
    RenderRequest r;
    r.width = WIDTH;
    r.height = HEIGHT;
    double rays = 0.0;
    for (auto _ : state) {
        auto frame = engine.render_frame(r);
        rays = double(frame.value().info.rays);
        benchmark::DoNotOptimize(frame.value().buffers.color.data());
    }
    report(state, rays);
}

/// Full frames (sun shadows, one bounce) at 1280x720, 1 spp: rays of every kind per second.
void BM_EngineRender(benchmark::State& state) {
    render_frames(state, *fixture_of(state).engine);
    state.counters["Msamples/s"] = benchmark::Counter(
        double(WIDTH) * HEIGHT * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

/// BM_EngineRender on mesh_1m with the sphere's own vertex normals: what interpolated shading
/// normals cost a full frame (compare with BM_EngineRender/0).
void BM_EngineRenderSmooth(benchmark::State& state) {
    static const std::unique_ptr<Engine> engine = [] {
        const SceneDesc d = mesh_1m();
        auto e = make_engine(d);
        UpdateMeshPositions normals;
        normals.mesh = "m0";
        normals.normals.emplace();
        for (const Vec3& p : d.meshes[0].positions) normals.normals->push_back(glm::normalize(p));
        EditBatch b;
        b.edits.emplace_back(std::move(normals));
        (void)e->apply(std::move(b)).value();
        return e;
    }();
    state.SetLabel("mesh_1m_smooth");
    render_frames(state, *engine);
}

/// BM_EngineRender with every surface under one material of alpha mode (second argument) 0:
/// opaque (the baseline: no filter installed), 1: mask with alpha 1 (the intersection filter
/// runs on every candidate hit and keeps it), 2: blend with alpha 0.5 (half the hits are passed
/// through, so rays go further). The filter's cost is 1 against 0, in the same run.
void BM_EngineRenderCoverage(benchmark::State& state) {
    const int which = int(state.range(0));
    const int mode = int(state.range(1));
    static std::unique_ptr<Engine> engines[2][3];
    std::unique_ptr<Engine>& engine = engines[which][mode];
    if (!engine) {
        Material m;
        m.alpha_mode = mode == 0 ? AlphaMode::Opaque : mode == 1 ? AlphaMode::Mask : AlphaMode::Blend;
        m.alpha = mode == 2 ? 0.5f : 1.0f;
        engine = make_engine(which == 0 ? mesh_1m() : instances_10k(), m);
    }
    static const char* const MODES[] = {"opaque", "mask", "blend"};
    state.SetLabel(std::string(which == 0 ? "mesh_1m/" : "instances_10k/") + MODES[mode]);
    render_frames(state, *engine);
}

BENCHMARK(BM_EnginePrimary)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_EnginePrimaryNewBuffers)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_PlainIntersect1)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_PlainIntersect16)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_PrimaryRatio)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(40)
    ->UseRealTime();
BENCHMARK(BM_EngineTlas16)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_EngineRender)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_EngineRenderSmooth)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_EngineRenderCoverage)
    ->ArgsProduct({{0, 1}, {0, 1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);

/// BM_EngineRender on instances_10k with motion (argument 1: every instance moves half a unit
/// over two motion keys; 2: instead their sphere deforms over two vertex keys, its vertices
/// pushed out by a tenth of its radius; both with the shutter open all frame; 0: the same scene
/// without keys): what motion and deformation blur cost a frame, in the same run.
void BM_EngineRenderMotion(benchmark::State& state) {
    const int arg = int(state.range(0));
    const bool moving = arg != 0;
    static std::unique_ptr<Engine> engines[3];
    std::unique_ptr<Engine>& engine = engines[arg];
    if (!engine) {
        const SceneDesc desc = instances_10k();
        engine = make_engine(desc);
        if (moving) {
            EditBatch b;
            for (int i = 0; i < 10000 && arg == 1; ++i) {
                UpdateInstance u{"i" + std::to_string(i)};
                u.motion = std::vector<Affine>{Affine::identity(),
                                               Affine::translation({0.5f, 0.0f, 0.0f})};
                b.edits.emplace_back(std::move(u));
            }
            if (arg == 2) {
                UpdateMeshPositions keys{"m0", 0, {}};
                keys.motion_positions.emplace();
                for (const Vec3& p : desc.meshes[0].positions)
                    keys.motion_positions->push_back(1.1f * p);
                b.edits.emplace_back(std::move(keys));
            }
            SetCamera shutter;
            shutter.shutter_open = 0.0f;
            shutter.shutter_close = 1.0f;
            b.edits.emplace_back(shutter);
            STRATA_CHECK(engine->apply(std::move(b)).has_value());
        }
    }
    state.SetLabel(arg == 2 ? "instances_10k/deforming" : moving ? "instances_10k/motion"
                                                                 : "instances_10k/still");
    render_frames(state, *engine);
}
BENCHMARK(BM_EngineRenderMotion)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);

/// A field of 10k detailed spheres (128 segments: 32k triangles each) seen as instances_10k's
/// camera sees it. Argument 0: every sphere at full detail; 1: each sphere a level-of-detail
/// group whose full-detail level is drawn up to 30 units from the camera and a 12-segment
/// sphere beyond (most of the field); 2: the same groups with the switch beyond the scene (what
/// the per-ray choice costs when it changes nothing). What LOD saves a frame, in the same run.
void BM_EngineRenderLod(benchmark::State& state) {
    const int arg = int(state.range(0));
    const bool lod = arg != 0;
    const float switch_at = arg == 1 ? 30.0f : 1e14f;
    static std::unique_ptr<Engine> engines[3];
    std::unique_ptr<Engine>& engine = engines[arg];
    if (!engine) {
        engine = std::move(Engine::create().value());
        EditBatch b;
        for (const auto& [id, segments] : {std::pair{"fine", 128u}, std::pair{"coarse", 12u}}) {
            const MeshData sphere = make_sphere(0.45f, segments);
            AddMesh m;
            m.id = id;
            m.positions = sphere.positions;
            m.triangles = sphere.triangles;
            m.build = BUILD;
            b.edits.emplace_back(std::move(m));
        }
        for (int i = 0; i < 10000; ++i) {
            const std::string id = "i" + std::to_string(i);
            const Affine at = Affine::translation(
                {float(i % 100) - 49.5f, 0.0f, float(i / 100) - 49.5f});
            AddInstance fine;
            fine.id = id;
            fine.mesh = "fine";
            fine.transform = at;
            if (lod) {
                AddGroup g;
                g.id = "g" + id;
                g.transform = at;
                g.lod = true;
                b.edits.emplace_back(std::move(g));
                fine.parent = "g" + id;
                fine.transform = Affine::identity();
                fine.lod_far = switch_at;
                AddInstance coarse;
                coarse.id = id + ".coarse";
                coarse.mesh = "coarse";
                coarse.parent = "g" + id;
                coarse.lod_near = switch_at;
                b.edits.emplace_back(std::move(coarse));
            }
            b.edits.emplace_back(std::move(fine));
        }
        SetCamera c;
        c.eye = Vec3(0.0f, 25.0f, 60.0f);
        c.target = Vec3(0.0f, 0.0f, 5.0f);
        b.edits.emplace_back(c);
        STRATA_CHECK(engine->apply(std::move(b)).has_value());
    }
    state.SetLabel(arg == 0 ? "spheres_10k/full_detail"
                   : arg == 1 ? "spheres_10k/lod"
                              : "spheres_10k/lod_all_full_detail");
    render_frames(state, *engine);
}
BENCHMARK(BM_EngineRenderLod)
    ->Arg(0)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);

/// A 1920x1080 frame of the demo scene (4 spp, every AOV), rendered once for the encoders.
const FrameBuffers& demo_1080p() {
    static const FrameBuffers frame = [] {
        auto engine = std::move(Engine::create().value());
        STRATA_CHECK(engine->apply(make_demo_scene()).has_value());
        RenderRequest r;
        r.width = 1920;
        r.height = 1080;
        r.spp = 4;
        r.format = ImageFormat::Exr;
        r.aovs = {Aov::Albedo,     Aov::Normal,      Aov::Depth, Aov::Position,
                  Aov::InstanceId, Aov::PrimitiveId, Aov::MeshId};
        return std::move(engine->render_frame(r).value().buffers);
    }();
    return frame;
}

void BM_ToneMap1080p(benchmark::State& state) {
    const FrameBuffers& f = demo_1080p();
    std::vector<uint8_t> rgb(f.pixel_count() * 3);
    for (auto _ : state) {
        tonemap_to_srgb8(f.color.data(), f.pixel_count(), 0.0f, rgb.data());
        benchmark::DoNotOptimize(rgb.data());
    }
}

void BM_PngEncode1080p(benchmark::State& state) {
    const FrameBuffers& f = demo_1080p();
    std::vector<uint8_t> rgb(f.pixel_count() * 3);
    tonemap_to_srgb8(f.color.data(), f.pixel_count(), 0.0f, rgb.data());
    std::size_t bytes = 0;
    for (auto _ : state) {
        auto png = encode_png(rgb.data(), f.width, f.height, 3);
        bytes = png.value().size();
    }
    state.counters["MB"] = double(bytes) / 1e6;
}

/// What a PNG request pays after the render: tone mapping plus libpng.
void BM_PngFrame1080p(benchmark::State& state) {
    const FrameBuffers& f = demo_1080p();
    RenderRequest r;
    r.format = ImageFormat::Png;
    for (auto _ : state) benchmark::DoNotOptimize(encode_frame(f, r).value().bytes.data());
}

/// EXR of the beauty only (range(1) == 0) or with every AOV, for each compression.
void BM_ExrFrame1080p(benchmark::State& state) {
    FrameBuffers f = demo_1080p();
    const auto compression = static_cast<ExrCompression>(state.range(0));
    if (state.range(1) == 0) f.aovs = AovSet();
    RenderRequest r;
    r.format = ImageFormat::Exr;
    r.compression = compression;
    std::size_t bytes = 0;
    for (auto _ : state) bytes = encode_frame(f, r).value().bytes.size();
    state.SetLabel(std::string(exr_compression_name(compression)) +
                   (state.range(1) == 0 ? " beauty" : " all aovs"));
    state.counters["MB"] = double(bytes) / 1e6;
}

/// The live viewer's per-frame encoding at 1080p, quality 80: a plain JPEG of a tone-mapped
/// frame (range 0) against one with the selected instance highlighted first (range 1: a copy of
/// the 8-bit frame, highlight_instance on the instance under the centre pixel, the encode).
void BM_StreamJpeg1080p(benchmark::State& state) {
    const FrameBuffers& f = demo_1080p();
    std::vector<uint8_t> rgb(f.pixel_count() * 3);
    tonemap_to_srgb8(f.color.data(), f.pixel_count(), 0.0f, rgb.data());
    const uint32_t slot = f.instance_id[f.pixel_count() / 2 + f.width / 2];
    std::size_t tinted = 0;
    for (auto _ : state) {
        if (state.range(0) == 0) {
            benchmark::DoNotOptimize(encode_jpeg(rgb.data(), f.width, f.height, 80).value());
            continue;
        }
        std::vector<uint8_t> copy = rgb;
        tinted = highlight_instance(copy.data(), f.instance_id.data(), f.width, f.height, slot);
        benchmark::DoNotOptimize(encode_jpeg(copy.data(), f.width, f.height, 80).value());
    }
    state.SetLabel(state.range(0) == 0 ? "plain" : "highlighted");
    state.counters["tinted_px"] = double(tinted);
}

/// What tracing the instance_id AOV adds to a stream launch (640x360, 1 spp, demo scene): the
/// pixel-centre ray, which the stream hub pays once per scene version (range 1) or never (0).
void BM_StreamLaunchIds(benchmark::State& state) {
    static const std::unique_ptr<Engine> engine = [] {
        auto e = std::move(Engine::create().value());
        STRATA_CHECK(e->apply(make_demo_scene()).has_value());
        return e;
    }();
    RenderRequest r;
    r.width = 640;
    r.height = 360;
    r.format = ImageFormat::Exr;
    if (state.range(0) == 1) r.aovs = {Aov::InstanceId};
    for (auto _ : state) {
        auto frame = engine->render_frame(r);
        benchmark::DoNotOptimize(frame.value().buffers.color.data());
    }
    state.SetLabel(state.range(0) == 0 ? "color only" : "with instance_id");
}

BENCHMARK(BM_StreamJpeg1080p)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_StreamLaunchIds)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_ToneMap1080p)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_PngEncode1080p)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_PngFrame1080p)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);
BENCHMARK(BM_ExrFrame1080p)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->ComputeStatistics("min", min_of);

}  // namespace
}  // namespace strata

/// Google Benchmark's main, plus STRATA_BENCH_THREADS=N to cap TBB's worker count.
int main(int argc, char** argv) {
    std::unique_ptr<tbb::global_control> threads;
    if (const char* n = std::getenv("STRATA_BENCH_THREADS"))
        threads = std::make_unique<tbb::global_control>(
            tbb::global_control::max_allowed_parallelism, std::size_t(std::max(1, std::atoi(n))));
    benchmark::AddCustomContext("tbb_threads", std::to_string(tbb::global_control::active_value(
                                                   tbb::global_control::max_allowed_parallelism)));
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
