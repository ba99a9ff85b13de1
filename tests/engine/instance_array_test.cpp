// The incremental TLAS's static tier as an instance array (engine/accel/instance_array.h): when
// the policy makes one, what it costs in memory, and the cases it leaves to instance geometries.
// Tracing against Embree's own instances: differential_test.cpp, and the whole suite again in
// CTest's strata_engine_tests.instance_arrays.

#include <cstdint>
#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "engine/accel/instance_array.h"
#include "tests/engine/hit_frames.h"
#include "tests/engine/many_instances.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

/// An incremental-TLAS engine whose static tier is an array from `n` instances on. Made with
/// Engine::create: these tests pin the policy whatever test::create_engine's environment says.
std::unique_ptr<Engine> arrays_from(uint32_t n, bool merges = true) {
    EngineConfig c;
    c.accel.tlas = TlasKind::Incremental;
    c.accel.tlas_policy.array_min_instances = n;
    c.accel.tlas_policy.background_merge = merges;
    auto engine = Engine::create(c);
    EXPECT_TRUE(engine.has_value());
    return std::move(engine.value());
}

constexpr uint32_t NEVER = std::numeric_limits<uint32_t>::max();

TEST(InstanceArray, TheStaticTierIsAnArrayFromThePolicysInstanceCountOn) {
    for (const int n : {2999, 3000}) {
        test::ManyInstances gen(3);
        auto engine = arrays_from(3000);
        ASSERT_TRUE(engine->apply(gen.initial_batch(n)).has_value());
        const RebuildReport r = test::commit_ok(*engine);
        EXPECT_EQ(r.tlas.static_array, n == 3000) << n;
        EXPECT_EQ(r.tlas.static_instances, uint64_t(n));
    }
}

// Embree's memory monitor sees the BVH, not its instance geometries' objects, so the TLAS bytes
// reported for geometries leave those out; an array's table is counted. What each holds in all
// is measured by tests/bench/load_bench.py (NOTES.md).
TEST(InstanceArray, CountsItsTableAsTlasMemoryAndFreesItWithTheInstances) {
    constexpr int N = 20000;
    int64_t bytes[2] = {};
    for (const bool array : {false, true}) {
        test::ManyInstances gen(4);
        auto engine = arrays_from(array ? 0 : NEVER);
        ASSERT_TRUE(engine->apply(gen.initial_batch(N)).has_value());
        const RebuildReport r = test::commit_ok(*engine);
        EXPECT_EQ(r.tlas.static_array, array);
        bytes[array] = r.memory_tlas_bytes;
        test::apply_ok(*engine, Clear{});
        EXPECT_EQ(test::commit_ok(*engine).memory_tlas_bytes, 0) << array;
    }
    ::testing::Test::RecordProperty("geometries_bvh_bytes_per_instance", int(bytes[0] / N));
    ::testing::Test::RecordProperty("array_bytes_per_instance", int(bytes[1] / N));
    EXPECT_GE(bytes[1], bytes[0] / 2 + N * int64_t(sizeof(InstanceEntry)));
}

TEST(InstanceArray, MotionKeysMakeInstanceGeometriesUntilTheLastKeysGo) {
    auto engine = arrays_from(0);
    test::apply_ok(*engine, test::mesh_edit("box", make_box(Vec3(1.0f))),
                   test::instance_edit("a", "box"), test::instance_edit("b", "box", {3, 0, 0}));
    EXPECT_TRUE(test::commit_ok(*engine).tlas.static_array);
    UpdateInstance keys;
    keys.instance = "a";
    keys.motion = std::vector<Affine>{Affine::identity(), Affine::translation({0, 1, 0})};
    test::apply_ok(*engine, keys);
    EXPECT_FALSE(test::commit_ok(*engine).tlas.static_array);
    keys.motion = std::vector<Affine>{};
    test::apply_ok(*engine, keys);
    EXPECT_TRUE(test::commit_ok(*engine).tlas.static_array);
}

TEST(InstanceArray, AStaleCopyOfARemovedMeshsInstanceIsNeverTraced) {
    // An array holds no reference on the BLASes it instances: the removed mesh's BLAS goes at
    // once, and the stale copy that still names it must never be entered (ASan would see it).
    // No merges: one running would hold a second table and BVH as TLAS memory.
    auto engine = arrays_from(0, false);
    EditBatch b;
    b.edits.emplace_back(test::mesh_edit("rock", make_box({0.5f, 0.5f, 0.5f})));
    b.edits.emplace_back(test::mesh_edit("ball", make_sphere(0.5f, 64)));
    for (int i = 0; i < 2000; ++i) {
        const Vec3 at(float(i % 50), 0.0f, float(i / 50));
        b.edits.emplace_back(test::instance_edit("r" + std::to_string(i), "rock", at));
    }
    b.edits.emplace_back(test::instance_edit("ball-1", "ball", {3, 0.5f, 3}));
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    const RebuildReport before = test::commit_ok(*engine);
    ASSERT_TRUE(before.tlas.static_array);

    test::apply_ok(*engine, RemoveInstance{"ball-1"}, RemoveMesh{"ball"});
    const RebuildReport removed = test::commit_ok(*engine);
    EXPECT_EQ(removed.tlas.stale_copies, 1u);
    EXPECT_LT(removed.memory_blas_bytes, before.memory_blas_bytes / 2);
    EXPECT_LE(removed.memory_tlas_bytes, before.memory_tlas_bytes);

    EngineConfig reference;
    reference.accel.tlas = TlasKind::Embree;
    auto scratch = Engine::create(reference);
    ASSERT_TRUE(scratch.has_value());
    ASSERT_TRUE(scratch.value()
                    ->apply(engine->read([](const Scene& s) { return s.to_batch(); }))
                    .has_value());
    const std::string diff = test::compare(test::render(*engine, 0xFFFFFFFFu, nullptr, 192, 128),
                                           test::render(**scratch, 0xFFFFFFFFu, nullptr, 192, 128));
    EXPECT_TRUE(diff.empty()) << diff;
}

}  // namespace
}  // namespace strata
