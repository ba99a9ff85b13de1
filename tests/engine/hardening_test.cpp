// What hostile or careless clients can ask of the engine: cameras whose arithmetic overflows,
// scenes beyond their budget, renders that must stop early, memory reports that must stay
// truthful across slot reuse.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <utility>

#include <embree3/rtcore.h>

#include "engine/accel/embree_device.h"
#include "engine/core/cancel.h"
#include "tests/engine/test_util.h"

namespace strata::test {
namespace {

using namespace std::chrono_literals;

Camera camera(Vec3 eye, Vec3 target) {
    Camera c;
    c.eye = eye;
    c.target = target;
    return c;
}

TEST(CameraCheck, FiniteNumbersWhoseArithmeticOverflowsAreRefused) {
    // Every number is finite, but target - eye is not (and rays from such an eye trip an
    // assertion in Embree).
    const Status overflow = check_camera(camera(Vec3(-3e38f), Vec3(3e38f)));
    ASSERT_FALSE(overflow.has_value());
    EXPECT_EQ(overflow.error().field, "eye");
    EXPECT_FALSE(check_camera(camera({1e19f, 0, 0}, {0, 0, 0})).has_value());
    EXPECT_FALSE(check_camera(camera({0, 0, 0}, {0, 0, 2e15f})).has_value());
    EXPECT_TRUE(check_camera(camera({1e14f, 0, 0}, {-1e14f, 0, 1})).has_value());
    // Up vectors whose squared length overflows a float.
    Camera huge_up = camera({0, 0, 5}, {0, 0, 0});
    huge_up.up = Vec3(0, 3e38f, 3e38f);
    EXPECT_TRUE(check_camera(huge_up).has_value());
    huge_up.up = Vec3(0, 0, 3e38f);
    EXPECT_FALSE(check_camera(huge_up).has_value());
}

TEST(CameraCheck, ASetCameraEditWithAnOverflowingCameraChangesNothing) {
    auto engine = make_engine();
    SetCamera e;
    e.eye = Vec3(-3e38f);
    e.target = Vec3(3e38f);
    EditBatch batch;
    batch.edits.emplace_back(e);
    auto r = engine->apply(std::move(batch));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 0u);
}

MeshData sphere_of(uint64_t triangles) {
    uint32_t segments = 3;
    while (sphere_triangle_count(segments + 1) <= triangles) ++segments;
    return make_sphere(1.0f, segments);
}

std::unique_ptr<Engine> engine_with_budget(uint64_t triangles, uint64_t vertices) {
    EngineConfig config;
    config.budget = {triangles, vertices};
    auto engine = test::create_engine(config);
    EXPECT_TRUE(engine.has_value());
    return std::move(engine.value());
}

TEST(SceneBudget, ABatchBeyondTheTriangleBudgetIsRefusedAndNamesTheEdit) {
    auto engine = engine_with_budget(10000, 1u << 20);
    apply_ok(*engine, mesh_edit("small", sphere_of(4000)));
    EditBatch batch;
    batch.edits.emplace_back(Clear{});  // ... then two meshes, the second one over the budget
    batch.edits.emplace_back(mesh_edit("a", sphere_of(6000)));
    batch.edits.emplace_back(mesh_edit("b", sphere_of(6000)));
    auto r = engine->apply(std::move(batch));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_EQ(r.error().edit_index, 2u);
    EXPECT_THAT(r.error().message, ::testing::HasSubstr("max_scene_triangles"));
    EXPECT_EQ(engine->read([](const Scene& s) { return s.counts().meshes; }), 1u);
}

TEST(SceneBudget, EachMeshCostsItsOverheadSoManyTinyMeshesAreRefused) {
    // Ten boxes of 12 triangles: 120 triangles and ten overheads fit; an eleventh does not.
    auto engine = engine_with_budget(10 * (12 + MESH_OVERHEAD_TRIANGLES) + 50, 1u << 20);
    EditBatch ten;
    for (int i = 0; i < 10; ++i)
        ten.edits.emplace_back(mesh_edit("box" + std::to_string(i), make_box(Vec3(1.0f))));
    ASSERT_TRUE(engine->apply(std::move(ten)).has_value());
    EditBatch eleventh;
    eleventh.edits.emplace_back(mesh_edit("box10", make_box(Vec3(1.0f))));
    auto r = engine->apply(std::move(eleventh));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_THAT(r.error().message, ::testing::HasSubstr("132 triangles in 11 meshes, and 0 groups"));
    EXPECT_THAT(r.error().message, ::testing::HasSubstr("max_scene_triangles"));
    // Removing a mesh gives its overhead back.
    apply_ok(*engine, RemoveMesh{"box0"}, mesh_edit("box10", make_box(Vec3(1.0f))));
}

TEST(SceneBudget, GroupsCostTheirOverheadToo) {
    auto engine = engine_with_budget(100 * GROUP_OVERHEAD_TRIANGLES, 1u << 20);
    auto group = [](int i) {
        AddGroup g;
        g.id = "g" + std::to_string(i);
        return g;
    };
    EditBatch hundred;
    for (int i = 0; i < 100; ++i) hundred.edits.emplace_back(group(i));
    ASSERT_TRUE(engine->apply(std::move(hundred)).has_value());
    EditBatch more;
    more.edits.emplace_back(group(100));
    auto r = engine->apply(std::move(more));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
    EXPECT_THAT(r.error().message, ::testing::HasSubstr("and 101 groups"));
    // A removed group gives its overhead back, and so does clear.
    apply_ok(*engine, RemoveGroup{"g0", false}, group(100));
    apply_ok(*engine, Clear{});
    EXPECT_EQ(engine->read([](const Scene& s) { return s.mesh_totals().budget_triangles(); }), 0u);
}

TEST(SceneBudget, ReplacingAMeshCountsOnlyWhatRemains) {
    auto engine = engine_with_budget(10000, 1u << 20);
    apply_ok(*engine, mesh_edit("a", sphere_of(6000)));
    // Remove and re-add in one batch: the end state is within the budget.
    apply_ok(*engine, RemoveMesh{"a"}, mesh_edit("a", sphere_of(9000)));
    ReplaceMeshTopology bigger;
    bigger.mesh = "a";
    bigger.triangles.assign(20000, Triangle(0, 1, 2));
    EditBatch batch;
    batch.edits.emplace_back(bigger);
    auto r = engine->apply(std::move(batch));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::TooLarge);
}

TEST(SceneBudget, TheVertexBudgetCountsToo) {
    auto engine = engine_with_budget(1u << 20, 100);
    MeshData many_vertices;
    many_vertices.positions.assign(200, Vec3(0.0f));
    many_vertices.positions[1] = {1, 0, 0};
    many_vertices.positions[2] = {0, 1, 0};
    many_vertices.triangles = {Triangle(0, 1, 2)};
    EditBatch batch;
    batch.edits.emplace_back(mesh_edit("m", many_vertices));
    auto r = engine->apply(std::move(batch));
    ASSERT_FALSE(r.has_value());
    EXPECT_THAT(r.error().message, ::testing::HasSubstr("vertices"));
}

TEST(MemoryReport, NewMeshesInRemovedMeshesSlotsKeepEveryCategoryTruthful) {
    // Clearing and rebuilding in one batch reuses every slot: the old BLASes are still
    // referenced by the old TLAS instances while the new ones are built. Freed during the TLAS
    // phase, they used to be counted there: the TLAS went negative and the BLAS stayed doubled.
    auto engine = make_engine();
    auto scene = [](EditBatch& b) {
        for (int i = 0; i < 20; ++i) {
            b.edits.emplace_back(mesh_edit("m" + std::to_string(i), make_sphere(1.0f, 48)));
            b.edits.emplace_back(instance_edit("i" + std::to_string(i), "m" + std::to_string(i),
                                               Vec3(float(i), 0, 0)));
        }
    };
    EditBatch first;
    scene(first);
    ASSERT_TRUE(engine->apply(std::move(first)).has_value());
    commit_ok(*engine);
    const int64_t blas = engine->memory_bytes(MemoryCategory::Blas);
    const int64_t tlas = engine->memory_bytes(MemoryCategory::Tlas);
    ASSERT_GT(blas, 0);
    ASSERT_GT(tlas, 0);

    EditBatch again;
    again.edits.emplace_back(Clear{});
    scene(again);
    ASSERT_TRUE(engine->apply(std::move(again)).has_value());
    commit_ok(*engine);
    EXPECT_GT(engine->memory_bytes(MemoryCategory::Tlas), 0);
    EXPECT_NEAR(double(engine->memory_bytes(MemoryCategory::Blas)), double(blas), 0.05 * blas);

    apply_ok(*engine, Clear{});
    commit_ok(*engine);
    EXPECT_EQ(engine->memory_bytes(MemoryCategory::Blas), 0);
    EXPECT_EQ(engine->memory_bytes(MemoryCategory::Tlas), 0);
}

/// Allocates a one-triangle Embree scene on `d`, builds it and frees it again; returns what the
/// device's categories held while it lived: {blas, tlas}.
std::pair<int64_t, int64_t> bytes_of_a_scene_built_on(EmbreeDevice& d) {
    RTCScene scene = rtcNewScene(d.get());
    RTCGeometry g = rtcNewGeometry(d.get(), RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0,
                                                          RTC_FORMAT_FLOAT3, 12, 3));
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    std::copy(p, p + 9, v);
    auto* t = static_cast<unsigned*>(
        rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, 1));
    t[0] = 0, t[1] = 1, t[2] = 2;
    rtcCommitGeometry(g);
    rtcAttachGeometry(scene, g);
    rtcCommitScene(scene);
    const std::pair<int64_t, int64_t> held{d.bytes(MemoryCategory::Blas),
                                           d.bytes(MemoryCategory::Tlas)};
    rtcReleaseGeometry(g);
    rtcReleaseScene(scene);
    return held;
}

TEST(MemoryReport, AThreadsCategoryForOneDeviceNeverCountsAnotherDevicesMemory) {
    // Background TLAS builds tag their threads (TBB workers included) with the TLAS category. A
    // worker that kept its tag after its arena's observer went (one engine's TLAS destroyed, or
    // a merge's arena) counted the next engine's BLAS builds as TLAS memory on that thread: the
    // BLAS category later went negative by what the TLAS kept.
    auto a = EmbreeDevice::create("threads=1");
    auto b = EmbreeDevice::create("threads=1");
    ASSERT_TRUE(a.has_value() && b.has_value());
    (*a)->set_thread_category(int(MemoryCategory::Tlas));
    {
        MemoryScope scope(**b, MemoryCategory::Blas);
        const auto [blas, tlas] = bytes_of_a_scene_built_on(**b);
        EXPECT_GT(blas, 0);
        EXPECT_EQ(tlas, 0);
    }
    EXPECT_EQ((*b)->bytes(MemoryCategory::Blas), 0);
    // The override still applies to its own device.
    {
        MemoryScope scope(**a, MemoryCategory::Blas);
        const auto [blas, tlas] = bytes_of_a_scene_built_on(**a);
        EXPECT_EQ(blas, 0);
        EXPECT_GT(tlas, 0);
    }
    (*a)->set_thread_category(-1);
    EXPECT_EQ((*a)->bytes(MemoryCategory::Tlas), 0);
}

std::unique_ptr<Engine> engine_with_a_sphere() {
    auto engine = make_engine();
    apply_ok(*engine, mesh_edit("ball", make_sphere(1.0f, 64)), instance_edit("b", "ball"));
    return engine;
}

TEST(RenderCancel, ACancelledTokenStopsTheRenderWithACancelledError) {
    auto engine = engine_with_a_sphere();
    CancelToken token;
    token.cancel(CancelReason::Shutdown);
    RenderRequest request;
    request.width = request.height = 64;
    request.cancel = &token;
    auto r = engine->render(request);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::Cancelled);
    EXPECT_THAT(r.error().message, ::testing::HasSubstr("shutting down"));
}

TEST(RenderCancel, APassedDeadlineStopsTheRender) {
    auto engine = engine_with_a_sphere();
    CancelToken token;
    token.set_deadline(CancelToken::Clock::now() - 1ms);
    RenderRequest request;
    request.cancel = &token;
    auto r = engine->render(request);
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(token.reason(), CancelReason::Deadline);
}

TEST(RenderCancel, ALongRenderStopsSoonAfterItsTokenIsCancelled) {
    auto engine = engine_with_a_sphere();
    // 640x360 at 4096 spp takes minutes on two cores; cancelled, it must end far sooner.
    RenderRequest request;
    request.spp = MAX_RENDER_SPP;
    request.accumulate = true;
    CancelToken token;
    request.cancel = &token;
    std::thread canceller([&] {
        std::this_thread::sleep_for(200ms);
        token.cancel(CancelReason::ClientGone);
    });
    const auto start = std::chrono::steady_clock::now();
    auto r = engine->render(request);
    const auto took = std::chrono::steady_clock::now() - start;
    canceller.join();
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, ErrorCode::Cancelled);
    EXPECT_LT(took, 20s);

    // The half-accumulated sums were dropped: the next accumulating frame starts over.
    request.width = request.height = 16;
    request.spp = 2;
    request.cancel = nullptr;
    auto next = engine->render(request);
    ASSERT_TRUE(next.has_value()) << next.error().describe();
    EXPECT_EQ(next.value().info.samples, 2u);
}

}  // namespace
}  // namespace strata::test
