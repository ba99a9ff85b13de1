// The incremental TLAS's tiers as the rebuild report shows them, its fallback policy, the merge
// swap, and a render that runs while a merge builds and edits keep landing.

#include <atomic>
#include <chrono>
#include <thread>

#include <gtest/gtest.h>

#include "tests/engine/hit_frames.h"
#include "tests/engine/many_instances.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

EngineConfig incremental(double max_dynamic_fraction = 0.10, bool merges = true,
                         uint32_t min_instances = 1024) {
    EngineConfig c;
    c.accel.tlas = TlasKind::Incremental;
    c.accel.tlas_policy.max_dynamic_fraction = max_dynamic_fraction;
    c.accel.tlas_policy.background_merge = merges;
    c.accel.tlas_policy.min_instances = min_instances;
    return c;
}

std::unique_ptr<Engine> engine_with(const EngineConfig& config) {
    auto engine = test::create_engine(config);
    EXPECT_TRUE(engine.has_value());
    return std::move(engine.value());
}

std::string rebuild_reason(const RebuildReport& r) {
    return r.tlas.static_rebuild;
}

/// `engine`'s frame has the hits of a fresh Embree build of its scene, and shows instances.
void expect_the_hits_of_a_fresh_build(Engine& engine) {
    EngineConfig reference;
    reference.accel.tlas = TlasKind::Embree;
    auto scratch = engine_with(reference);
    ASSERT_TRUE(scratch->apply(engine.read([](const Scene& s) { return s.to_batch(); }))
                    .has_value());
    const test::HitFrame shown = test::render(engine, 0xFFFFFFFFu, nullptr, 192, 128);
    const test::HitFrame fresh = test::render(*scratch, 0xFFFFFFFFu, nullptr, 192, 128);
    const std::string diff = test::compare(shown, fresh);
    EXPECT_TRUE(diff.empty()) << diff;
    std::size_t hits = 0;
    for (const auto& id : shown.instance_ids) hits += !id.empty();
    EXPECT_GT(hits, shown.instance_ids.size() / 10) << "the frame shows the instances";
}

TEST(IncrementalTlas, TheFirstBuildPutsEveryInstanceInTheStaticTier) {
    test::ManyInstances gen(1);
    auto engine = engine_with(incremental());
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_STREQ(r.tlas.strategy, "incremental");
    EXPECT_EQ(rebuild_reason(r), "first_build");
    EXPECT_EQ(r.tlas.static_instances, 2000u);
    EXPECT_EQ(r.tlas.dynamic_instances, 0u);
    EXPECT_EQ(r.tlas.stale_copies, 0u);
    EXPECT_FALSE(r.tlas.merge_running);
}

TEST(IncrementalTlas, AMoveGoesToTheDynamicTierAndLeavesAStaleCopy) {
    test::ManyInstances gen(2);
    auto engine = engine_with(incremental(0.10, false));
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(gen.moves(1)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Update);
    EXPECT_EQ(rebuild_reason(r), "");
    EXPECT_EQ(r.tlas.static_instances, 2000u);
    EXPECT_EQ(r.tlas.dynamic_instances, 1u);
    EXPECT_EQ(r.tlas.stale_copies, 1u);
    EXPECT_EQ(r.tlas_instances, 2000u);
}

TEST(IncrementalTlas, AFinishedMergeIsSwappedInByTheNextCommitEvenWithoutEdits) {
    test::ManyInstances gen(3);
    auto engine = engine_with(incremental());
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(gen.moves(5)).has_value());
    const RebuildReport moved = test::commit_ok(*engine);  // starts a merge
    EXPECT_GE(moved.tlas.dynamic_instances, 1u);

    engine->wait_for_background();
    const RebuildReport swapped = test::commit_ok(*engine);  // no scene change
    EXPECT_TRUE(swapped.tlas.merge_swapped);
    EXPECT_GT(swapped.tlas.merge_build_ms, 0.0);
    EXPECT_EQ(swapped.tlas.dynamic_instances, 0u);
    EXPECT_EQ(swapped.tlas.stale_copies, 0u);
    EXPECT_EQ(swapped.tlas.static_instances, 2000u);
    EXPECT_FALSE(swapped.no_accel_work());

    const RebuildReport idle = test::commit_ok(*engine);
    EXPECT_FALSE(idle.tlas.merge_swapped);
    EXPECT_TRUE(idle.no_accel_work());
    const EngineCounters c = engine->counters();
    EXPECT_EQ(c.tlas_merges, 1u);
    EXPECT_GT(c.tlas_merge_seconds, 0.0);
}

TEST(IncrementalTlas, EditsMadeWhileAMergeBuildsStayInTheDynamicTierAfterTheSwap) {
    test::ManyInstances gen(4);
    auto engine = engine_with(incremental());
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    test::commit_ok(*engine);
    // "i7" is moved before the merge starts (the commit starts it) and again after.
    test::apply_ok(*engine, SetTransform{"i7", Affine::translation({0, 1, 0})});
    test::commit_ok(*engine);
    test::apply_ok(*engine, SetTransform{"i7", Affine::translation({0, 2, 0})},
                   SetTransform{"i8", Affine::translation({0, 3, 0})});
    engine->wait_for_background();
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_TRUE(r.tlas.merge_swapped);
    EXPECT_EQ(r.tlas.dynamic_instances, 2u);  // i7 (again) and i8
    EXPECT_EQ(r.tlas.stale_copies, 2u);
    engine->wait_for_background();
    const RebuildReport later = test::commit_ok(*engine);
    EXPECT_TRUE(later.tlas.merge_swapped);
    EXPECT_EQ(later.tlas.dynamic_instances, 0u);
}

// Embree never shrinks a scene's geometry table and walks all of it at each commit of the scene.
// A dynamic tier of geometries (an entry has motion keys) that held thousands of instances and
// drained moves to a fresh scene, and the instances edited since still trace as a fresh build of
// the scene does.
TEST(IncrementalTlas, ADrainedDynamicTierMovesToAFreshSceneAndTracesAsAFreshBuild) {
    test::ManyInstances gen(8);
    auto engine = engine_with(incremental(0.9));
    ASSERT_TRUE(engine->apply(gen.initial_batch(5000)).has_value());
    test::commit_ok(*engine);
    UpdateInstance keyed{"i4998"};  // motion keys: the tier is Embree geometries, not an array
    keyed.motion = std::vector<Affine>{Affine::translation({0, 0.25f, 0}),
                                       Affine::translation({0.5f, 0.25f, 0})};
    test::apply_ok(*engine, keyed);
    ASSERT_TRUE(engine->apply(gen.moves(3000)).has_value());
    const RebuildReport big = test::commit_ok(*engine);  // starts a merge
    if (big.tlas.static_array) GTEST_SKIP() << "an instance array takes no merges of keyed edits";
    ASSERT_EQ(rebuild_reason(big), "");
    ASSERT_GT(big.tlas.dynamic_instances, 2000u);
    ASSERT_FALSE(big.tlas.dynamic_array);
    EXPECT_EQ(big.tlas.dynamic_slots, big.tlas.dynamic_instances);

    engine->wait_for_background();
    // Edited again after the merge started, the keyed instance stays in the tier.
    test::apply_ok(*engine, SetTransform{"i4998", Affine::translation({0, 0.5f, 0})});
    ASSERT_TRUE(engine->apply(gen.moves(3)).has_value());
    const RebuildReport drained = test::commit_ok(*engine);
    ASSERT_TRUE(drained.tlas.merge_swapped);
    EXPECT_FALSE(drained.tlas.dynamic_array);
    EXPECT_GE(drained.tlas.dynamic_instances, 1u);
    EXPECT_LE(drained.tlas.dynamic_instances, 4u);
    EXPECT_EQ(drained.tlas.dynamic_slots, drained.tlas.dynamic_instances);
    expect_the_hits_of_a_fresh_build(*engine);
}

/// Moves instances "i<first>" .. "i<first + count - 1>", each to a place of its own (no ties),
/// in one commit, and returns the commit's tiers.
TlasTiers move_instances(Engine& engine, uint32_t first, uint32_t count) {
    EditBatch b;
    for (uint32_t i = first; i < first + count; ++i) {
        const float f = float(i);
        b.edits.emplace_back(SetTransform{"i" + std::to_string(i),
                                          Affine::translation({0.37f * f, 0.011f * f, 0.5f})});
    }
    EXPECT_TRUE(engine.apply(std::move(b)).has_value());
    return test::commit_ok(engine).tlas;
}

/// Gives instance `id` two motion keys (empty `keys`: takes them away) in one commit.
TlasTiers set_motion(Engine& engine, const std::string& id, std::vector<Affine> keys) {
    UpdateInstance u{id};
    u.motion = std::move(keys);
    test::apply_ok(engine, u);
    return test::commit_ok(engine).tlas;
}

const std::vector<Affine> TWO_KEYS{Affine::translation({0, 0.25f, 0}),
                                   Affine::translation({0.5f, 0.25f, 0})};

// The dynamic tier is an instance array (one user geometry, the fast build) until an entry has
// motion keys, which an array cannot hold: then Embree instance geometries, and an array again
// once the keys are gone. Every form traces as a fresh build does.
TEST(IncrementalTlas, TheDynamicTierIsAnArrayUntilAnEntryHasMotionKeys) {
    test::ManyInstances gen(10);
    auto engine = engine_with(incremental(0.9, false));
    ASSERT_TRUE(engine->apply(gen.initial_batch(3000)).has_value());
    test::commit_ok(*engine);
    const TlasTiers moved = move_instances(*engine, 0, 50);
    EXPECT_EQ(moved.dynamic_instances, 50u);
    EXPECT_TRUE(moved.dynamic_array);
    EXPECT_STREQ(moved.dynamic_quality, "low");
    expect_the_hits_of_a_fresh_build(*engine);
    const TlasTiers keyed = set_motion(*engine, "i7", TWO_KEYS);
    EXPECT_EQ(keyed.dynamic_instances, 50u);
    EXPECT_FALSE(keyed.dynamic_array);
    EXPECT_EQ(keyed.dynamic_slots, 50u);
    expect_the_hits_of_a_fresh_build(*engine);
    const TlasTiers more = move_instances(*engine, 50, 10);  // geometries while i7 has keys
    EXPECT_EQ(more.dynamic_instances, 60u);
    EXPECT_FALSE(more.dynamic_array);
    const TlasTiers plain = set_motion(*engine, "i7", {});
    EXPECT_EQ(plain.dynamic_instances, 60u);
    EXPECT_TRUE(plain.dynamic_array);
    expect_the_hits_of_a_fresh_build(*engine);
}

// A dynamic tier of Embree geometries builds at MEDIUM quality while it is small and at LOW
// once it is large, and one in between keeps what it had.
TEST(IncrementalTlas, TheDynamicTierOfGeometriesBuildsAtTheQualityForItsSize) {
    test::ManyInstances gen(9);
    EngineConfig config = incremental(0.9, false);
    config.accel.tlas_policy.dynamic_medium_max = 100;
    auto engine = engine_with(config);
    ASSERT_TRUE(engine->apply(gen.initial_batch(3000)).has_value());
    test::commit_ok(*engine);
    const TlasTiers few = set_motion(*engine, "i2999", TWO_KEYS);  // geometries from here on
    EXPECT_EQ(few.dynamic_instances, 1u);
    EXPECT_FALSE(few.dynamic_array);
    EXPECT_STREQ(few.dynamic_quality, "medium");
    const TlasTiers between = move_instances(*engine, 0, 150);  // 151: between 100 and 200
    EXPECT_EQ(between.dynamic_instances, 151u);
    EXPECT_STREQ(between.dynamic_quality, "medium");
    const TlasTiers many = move_instances(*engine, 150, 100);
    EXPECT_EQ(many.dynamic_instances, 251u);
    EXPECT_STREQ(many.dynamic_quality, "low");
    expect_the_hits_of_a_fresh_build(*engine);
    const TlasTiers still = move_instances(*engine, 0, 10);  // the same 251 instances
    EXPECT_EQ(still.dynamic_instances, 251u);
    EXPECT_STREQ(still.dynamic_quality, "low");
    // A requested rebuild empties the tier; the next keyed edit builds at MEDIUM again.
    test::apply_ok(*engine, MarkDirty{std::nullopt, DirtyAction::Rebuild});
    EXPECT_EQ(test::commit_ok(*engine).tlas.dynamic_instances, 0u);
    const TlasTiers again = set_motion(*engine, "i5", TWO_KEYS);
    EXPECT_EQ(again.dynamic_instances, 1u);
    EXPECT_STREQ(again.dynamic_quality, "medium");
    expect_the_hits_of_a_fresh_build(*engine);
}

TEST(IncrementalTlas, ADynamicTierOverItsLimitWaitsForTheMergeUnderWayInsteadOfRebuilding) {
    test::ManyInstances gen(10);
    auto engine = engine_with(incremental(0.10));  // 200 of 2000
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(gen.moves(150)).has_value());
    const RebuildReport first = test::commit_ok(*engine);  // starts a merge of these moves
    ASSERT_GT(first.tlas.dynamic_instances, 100u);

    // Over the limit with the earlier moves: the merge that holds them is waited for and swapped
    // in, and only the new moves stay dynamic.
    ASSERT_TRUE(engine->apply(gen.moves(100)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_EQ(rebuild_reason(r), "");
    EXPECT_TRUE(r.tlas.merge_swapped);
    EXPECT_GE(r.tlas.dynamic_instances, 90u);
    EXPECT_LE(r.tlas.dynamic_instances, 100u);
    EXPECT_EQ(engine->counters().tlas_static_rebuilds, 1u);  // the first build only
    expect_the_hits_of_a_fresh_build(*engine);
}

TEST(IncrementalTlas, SmallScenesRebuildTheWholeTlasAtEachUpdate) {
    test::ManyInstances gen(5);
    auto engine = engine_with(incremental());
    ASSERT_TRUE(engine->apply(gen.initial_batch(100)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(gen.moves(1)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_EQ(rebuild_reason(r), "small_scene");
    EXPECT_EQ(r.tlas.dynamic_instances, 0u);
    EXPECT_EQ(r.tlas.stale_copies, 0u);
    EXPECT_FALSE(r.tlas.merge_running);
}

TEST(IncrementalTlas, ADynamicTierOverItsLimitIsFoldedIntoTheStaticTier) {
    test::ManyInstances gen(6);
    auto engine = engine_with(incremental(0.05, false));
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(gen.moves(60)).has_value());
    EXPECT_EQ(rebuild_reason(test::commit_ok(*engine)), "");
    ASSERT_TRUE(engine->apply(gen.moves(60)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_EQ(rebuild_reason(r), "dynamic_tier_full");
    EXPECT_EQ(r.tlas.dynamic_instances, 0u);
    EXPECT_EQ(r.tlas.stale_copies, 0u);
    EXPECT_EQ(engine->counters().tlas_static_rebuilds, 2u);  // the first build and this one
}

TEST(IncrementalTlas, ARequestedRebuildEmptiesTheDynamicTier) {
    test::ManyInstances gen(7);
    auto engine = engine_with(incremental(0.10, false));
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    test::commit_ok(*engine);
    ASSERT_TRUE(engine->apply(gen.moves(10)).has_value());
    test::commit_ok(*engine);
    test::apply_ok(*engine, MarkDirty{std::nullopt, DirtyAction::Rebuild});
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_EQ(r.tlas_action, TlasAction::Rebuild);
    EXPECT_EQ(rebuild_reason(r), "requested");
    EXPECT_EQ(r.tlas.dynamic_instances, 0u);
    EXPECT_EQ(r.tlas.static_instances, 2000u);
}

TEST(IncrementalTlas, ARemovedMeshLeavesTheBlasMemoryEvenWhileStaleCopiesReferenceIt) {
    auto engine = engine_with(incremental(0.10, false));
    EditBatch b;
    b.edits.emplace_back(test::mesh_edit("rock", make_box({0.5f, 0.5f, 0.5f})));
    b.edits.emplace_back(test::mesh_edit("ball", make_sphere(0.5f, 64)));
    for (int i = 0; i < 2000; ++i)
        b.edits.emplace_back(
            test::instance_edit("r" + std::to_string(i), "rock", {float(i), 0, 0}));
    b.edits.emplace_back(test::instance_edit("ball-1", "ball", {0, 2, 0}));
    ASSERT_TRUE(engine->apply(std::move(b)).has_value());
    const RebuildReport before = test::commit_ok(*engine);

    // The ball's instance leaves a stale static copy that still references the ball's BLAS.
    test::apply_ok(*engine, RemoveInstance{"ball-1"}, RemoveMesh{"ball"});
    const RebuildReport removed = test::commit_ok(*engine);
    EXPECT_EQ(removed.tlas.stale_copies, 1u);
    EXPECT_LT(removed.memory_blas_bytes, before.memory_blas_bytes / 2);

    // Folding the tiers frees the copy and, with it, the BLAS: the TLAS bytes go back down.
    test::apply_ok(*engine, MarkDirty{std::nullopt, DirtyAction::Rebuild});
    const RebuildReport rebuilt = test::commit_ok(*engine);
    EXPECT_EQ(rebuilt.tlas.stale_copies, 0u);
    EXPECT_EQ(rebuilt.memory_blas_bytes, removed.memory_blas_bytes);
    EXPECT_LT(rebuilt.memory_tlas_bytes, removed.memory_tlas_bytes);
    EXPECT_GT(rebuilt.memory_tlas_bytes, 0);
}

TEST(IncrementalTlas, TheEmbreeStrategyStaysSelectable) {
    EngineConfig c;
    c.accel.tlas = TlasKind::Embree;
    test::ManyInstances gen(8);
    auto engine = engine_with(c);
    ASSERT_TRUE(engine->apply(gen.initial_batch(2000)).has_value());
    const RebuildReport r = test::commit_ok(*engine);
    EXPECT_STREQ(r.tlas.strategy, "embree");
    EXPECT_EQ(r.tlas.static_instances, 2000u);
    EXPECT_EQ(parse_tlas_kind("embree"), TlasKind::Embree);
    EXPECT_EQ(parse_tlas_kind("incremental"), TlasKind::Incremental);
    EXPECT_FALSE(parse_tlas_kind("partitioned").has_value());
}

// A launch commits, then traces while holding only the launch mutex: edits keep landing and a
// merge may finish meanwhile, but it is swapped in only by a later commit. Every frame must
// show exactly the version its commit reported: the same hits as a fresh build of that version.
TEST(IncrementalTlas, ARenderDuringAMergeTracesExactlyOneVersion) {
    constexpr int INSTANCES = 8000;
    constexpr int BATCHES = 200;
    test::ManyInstances gen(9);
    const EditBatch initial = gen.initial_batch(INSTANCES);
    std::vector<EditBatch> batches;
    for (int i = 0; i < BATCHES; ++i) batches.push_back(gen.moves(3));

    auto engine = engine_with(incremental(0.25));
    ASSERT_TRUE(engine->apply(EditBatch(initial)).has_value());
    test::commit_ok(*engine);
    const uint64_t base = engine->read([](const Scene& s) { return s.version(); });

    std::atomic<int> next{0};
    std::atomic<bool> stop{false};
    std::thread editor([&] {
        // Edits land while launches trace; each batch moves the version by one.
        while (!stop.load() && next.load() < BATCHES) {
            EditBatch b = batches[std::size_t(next.load())];
            if (!engine->apply(std::move(b)).has_value()) break;
            next.fetch_add(1);
            std::this_thread::sleep_for(std::chrono::microseconds(300));
        }
    });

    int frames = 0, during_merge = 0;
    std::vector<std::pair<uint64_t, test::HitFrame>> shown;
    while (frames < 6) {
        RebuildReport report;
        test::HitFrame f = test::render(*engine, 0xFFFFFFFFu, &report, 192, 128);
        during_merge += report.tlas.merge_running;
        shown.emplace_back(report.version, std::move(f));
        ++frames;
    }
    stop.store(true);
    editor.join();

    for (auto& [version, frame] : shown) {
        ASSERT_GE(version, base);
        const uint64_t applied = version - base;
        ASSERT_LE(applied, uint64_t(BATCHES));
        EngineConfig reference;
        reference.accel.tlas = TlasKind::Embree;
        auto scratch = engine_with(reference);
        ASSERT_TRUE(scratch->apply(EditBatch(initial)).has_value());
        for (uint64_t i = 0; i < applied; ++i)
            ASSERT_TRUE(scratch->apply(EditBatch(batches[i])).has_value());
        const test::HitFrame fresh = test::render(*scratch, 0xFFFFFFFFu, nullptr, 192, 128);
        const std::string diff = test::compare(frame, fresh);
        EXPECT_TRUE(diff.empty()) << "frame of version " << version << " differs:\n" << diff;
    }
    EXPECT_EQ(frames, 6);
    ::testing::Test::RecordProperty("frames_during_merge", during_merge);
}

}  // namespace
}  // namespace strata
