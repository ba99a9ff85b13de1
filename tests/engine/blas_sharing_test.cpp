// BLASes shared between engines on one Embree device (engine/accel/blas_pool.h): an identical
// mesh in a second engine holds the first one's BLAS instead of building its own, a change to a
// shared mesh builds a copy and leaves the other engine's frames as they were, memory is counted
// once and follows the BLAS as engines let go of it, and one engine's own meshes never share.

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "engine/accel/blas_pool.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::commit_ok;
using test::instance_edit;
using test::mesh_edit;

class BlasSharing : public ::testing::TestWithParam<TlasKind> {
protected:
    void SetUp() override {
        auto made = SharedEmbree::create("");
        ASSERT_TRUE(made.has_value());
        device = std::move(made.value());
    }
    std::unique_ptr<Engine> engine() {
        EngineConfig config;
        config.accel.tlas = GetParam();
        config.accel.shared_device = device;
        auto e = test::create_engine(config);
        EXPECT_TRUE(e.has_value());
        return std::move(e.value());
    }
    /// An engine holding the city: a sphere, instanced twice, and a box.
    std::unique_ptr<Engine> city() {
        auto e = engine();
        apply_ok(*e, mesh_edit("ball", make_sphere(1.0f, 48)),
                 mesh_edit("crate", make_box(Vec3(1))), instance_edit("b0", "ball", {-1.5f, 0, 0}),
                 instance_edit("b1", "ball", {1.5f, 0, 0}),
                 instance_edit("c0", "crate", {0, -2, 0}));
        return e;
    }
    static std::string frame(Engine& e) {
        RenderRequest request;
        request.width = 48;
        request.height = 32;
        request.spp = 1;
        auto r = e.render(request);
        EXPECT_TRUE(r.has_value());
        return r.has_value() ? r.value().bytes : std::string();
    }

    std::shared_ptr<SharedEmbree> device;
};

TEST_P(BlasSharing, ASecondEngineHoldsTheFirstsBlasesInsteadOfBuildingThem) {
    auto a = city();
    const RebuildReport first = commit_ok(*a);
    EXPECT_EQ(first.blas_rebuilds, 2u);
    EXPECT_EQ(device->pool()->size(), 2u);
    const int64_t built = a->memory_bytes(MemoryCategory::Blas);
    ASSERT_GT(built, 0);

    auto b = city();
    const RebuildReport second = commit_ok(*b);
    EXPECT_EQ(second.blas_rebuilds, 0u) << second.summary();
    EXPECT_EQ(second.primitives_built, 0u);
    ASSERT_EQ(second.rebuilt.size(), 2u);
    for (const MeshBuildEntry& e : second.rebuilt) {
        EXPECT_EQ(e.reason, BuildReason::Shared) << e.mesh;
        EXPECT_EQ(e.bytes, 0);
    }
    // Counted once: by the engine that built them.
    EXPECT_EQ(b->memory_bytes(MemoryCategory::Blas), 0);
    EXPECT_EQ(a->memory_bytes(MemoryCategory::Blas), built);
    EXPECT_EQ(frame(*a), frame(*b));
}

TEST_P(BlasSharing, AChangeToASharedMeshBuildsACopyAndLeavesTheOtherEnginesFramesAsTheyWere) {
    auto a = city();
    commit_ok(*a);
    auto b = city();
    commit_ok(*b);
    const std::string before = frame(*a);

    MeshData dented = make_sphere(1.0f, 48);
    for (Vec3& p : dented.positions) p *= 0.6f;
    apply_ok(*b, UpdateMeshPositions{"ball", 0, dented.positions});
    const RebuildReport r = commit_ok(*b);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].mesh, "ball");
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Unshared);
    EXPECT_EQ(r.blas_refits, 0u);
    EXPECT_GT(b->memory_bytes(MemoryCategory::Blas), 0);

    EXPECT_EQ(frame(*a), before) << "the other engine's ball changed";
    EXPECT_NE(frame(*b), before);
    // The copy is b's own: a small edit refits it in place.
    for (Vec3& p : dented.positions) p *= 1.01f;
    apply_ok(*b, UpdateMeshPositions{"ball", 0, dented.positions});
    const RebuildReport again = commit_ok(*b);
    EXPECT_EQ(again.blas_refits, 1u) << again.summary();
    EXPECT_EQ(again.blas_rebuilds, 0u);
    // Back in the shared shape, its rebuild (the bounds grew past the refit policy) finds a's
    // BLAS again and holds it.
    apply_ok(*b, UpdateMeshPositions{"ball", 0, make_sphere(1.0f, 48).positions});
    const RebuildReport back = commit_ok(*b);
    ASSERT_EQ(back.rebuilt.size(), 1u) << back.summary();
    EXPECT_EQ(back.rebuilt[0].reason, BuildReason::Shared);
    EXPECT_EQ(b->memory_bytes(MemoryCategory::Blas), 0);
    EXPECT_EQ(frame(*b), before);
}

TEST_P(BlasSharing, TheMemoryFollowsTheBlasWhenItsBuilderLetsGo) {
    auto a = city();
    commit_ok(*a);
    auto b = city();
    commit_ok(*b);
    const int64_t shared = a->memory_bytes(MemoryCategory::Blas);
    const std::string seen = frame(*b);

    apply_ok(*a, Clear{});
    commit_ok(*a);
    EXPECT_EQ(a->memory_bytes(MemoryCategory::Blas), 0);
    EXPECT_EQ(b->memory_bytes(MemoryCategory::Blas), shared) << "b counts what it holds now";
    EXPECT_EQ(frame(*b), seen);
    // Held by b alone, but a's TLAS may still reference it (a stale static-tier copy): a
    // position edit builds b a copy rather than refit what a may trace.
    apply_ok(*b, UpdateMeshPositions{"crate", 0, make_box(Vec3(0.5f)).positions});
    const RebuildReport r = commit_ok(*b);
    ASSERT_EQ(r.rebuilt.size(), 1u) << r.summary();
    EXPECT_EQ(r.rebuilt[0].reason, BuildReason::Unshared);
    EXPECT_EQ(r.blas_refits, 0u);
    // The copy was never shared: it refits in place.
    apply_ok(*b, UpdateMeshPositions{"crate", 0, make_box(Vec3(0.52f)).positions});
    EXPECT_EQ(commit_ok(*b).blas_refits, 1u);

    a.reset();
    apply_ok(*b, Clear{});
    commit_ok(*b);
    EXPECT_EQ(b->memory_bytes(MemoryCategory::Blas), 0);
    EXPECT_EQ(device->pool()->size(), 0u);
}

TEST_P(BlasSharing, AnEnginesOwnIdenticalMeshesAndDifferentContentAreNotShared) {
    auto a = engine();
    apply_ok(*a, mesh_edit("one", make_sphere(1.0f, 24)), mesh_edit("two", make_sphere(1.0f, 24)),
             instance_edit("i1", "one"), instance_edit("i2", "two"));
    EXPECT_EQ(commit_ok(*a).blas_rebuilds, 2u);
    auto b = engine();
    BuildOptions fast_build;
    fast_build.prefer = BuildPreference::FastBuild;
    fast_build.allow_refit = false;
    apply_ok(*b, mesh_edit("other", make_sphere(1.0f, 25)),
             mesh_edit("built", make_sphere(1.0f, 24), fast_build), instance_edit("i1", "other"),
             instance_edit("i2", "built"));
    const RebuildReport r = commit_ok(*b);
    EXPECT_EQ(r.blas_rebuilds, 2u) << "other content, other build options: built";
    MeshData moved = make_sphere(1.0f, 24);
    moved.positions.back().x += 1e-3f;  // one vertex apart, past the sampled key's reach
    auto c = engine();
    apply_ok(*c, mesh_edit("near", moved), instance_edit("i", "near"));
    EXPECT_EQ(commit_ok(*c).blas_rebuilds, 1u);
}

TEST_P(BlasSharing, EnginesCommittingAndRenderingAtOnceShareAndCopyWithoutLosingABlas) {
    // Each thread loads the city, renders, dents its ball (a copy), renders, and clears, over
    // and over, while the others do the same: holds, copies and releases race each other.
    constexpr int THREADS = 3, ROUNDS = 12;
    std::vector<std::unique_ptr<Engine>> engines;
    for (int t = 0; t < THREADS; ++t) engines.push_back(engine());
    std::atomic<int> failures{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < THREADS; ++t) {
        threads.emplace_back([&, t] {
            Engine& e = *engines[std::size_t(t)];
            MeshData dented = make_sphere(1.0f, 48);
            for (Vec3& p : dented.positions) p *= 0.5f + 0.1f * float(t);
            for (int round = 0; round < ROUNDS; ++round) {
                EditBatch load;
                load.edits = {mesh_edit("ball", make_sphere(1.0f, 48)),
                              mesh_edit("crate", make_box(Vec3(1))), instance_edit("b0", "ball"),
                              instance_edit("c0", "crate", {0, -2, 0})};
                EditBatch dent;
                dent.edits = {UpdateMeshPositions{"ball", 0, dented.positions}};
                EditBatch clear;
                clear.edits = {Clear{}};
                for (EditBatch* batch : {&load, &dent, &clear}) {
                    const bool ok = e.apply(std::move(*batch)).has_value() &&
                                    e.commit().has_value() && !frame(e).empty();
                    if (!ok) ++failures;
                }
            }
        });
    }
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(failures.load(), 0);
    for (const auto& e : engines) EXPECT_EQ(e->memory_bytes(MemoryCategory::Blas), 0);
    EXPECT_EQ(device->pool()->size(), 0u);
}

INSTANTIATE_TEST_SUITE_P(BothTlasStrategies, BlasSharing,
                         ::testing::Values(TlasKind::Incremental, TlasKind::Embree),
                         [](const ::testing::TestParamInfo<TlasKind>& p) {
                             return std::string(tlas_kind_name(p.param));
                         });

}  // namespace
}  // namespace strata
