// Replacing a whole scene with a snapshot's (Engine::replace_with_snapshot, and through a data
// directory DurableStore::replace_scene): what a replica does when its log was trimmed past its
// version. The replaced engine must be indistinguishable from a fresh engine that restored the
// same snapshot (version, ids, hits, rendered frames, and what later batches do), and a replace
// that fails must leave the old scene exactly as it was.

#include <atomic>
#include <filesystem>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "engine/durable/durable_store.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"
#include "tests/engine/texture_test_util.h"

namespace strata {
namespace {

using test::point_light;
using test::TempDir;

std::string encoded_scene(const Engine& engine) {
    return engine.read([](const Scene& s) {
        std::string out;
        durable::encode_batch(s.to_batch(), out);
        return out;
    });
}

/// Random meshes and instances (with removals, so slots have holes), then groups, lights, a
/// textured material and a camera that sees the whole thing. `tag` keeps two scenes' ids apart
/// where they should differ.
void build_scene(Engine& engine, uint64_t seed, int batches, const std::string& tag) {
    test::RandomEdits edits(seed);
    for (int i = 0; i < batches; ++i) {
        auto r = engine.apply(i == 0 ? edits.initial_batch(5, 60) : edits.next_batch(6));
        ASSERT_TRUE(r.has_value()) << r.error().describe();
    }
    AddMaterial textured{"tex-" + tag, Material{}};
    textured.textures[0] = "checker-" + tag;
    AddInstance a = test::instance_edit("a-" + tag, "box-" + tag, {1, 0, 0});
    a.parent = "wheels-" + tag;
    a.material = "tex-" + tag;
    AddInstance b = test::instance_edit("b-" + tag, "box-" + tag, {-1, 0, 0});
    b.parent = "car-" + tag;
    test::apply_ok(engine, AddTexture{"checker-" + tag, test::four_colour_png()}, textured,
                   test::mesh_edit("box-" + tag, make_box(Vec3(0.8f))),
                   AddGroup{"car-" + tag, std::nullopt, Affine::translation({0, 0, -2}), true},
                   AddGroup{"wheels-" + tag, std::string("car-" + tag), Affine::identity(), true},
                   a, b, AddLight{"lamp-" + tag, point_light(Vec3(1, 4, 2), 20.0f)},
                   test::mesh_edit("backdrop-" + tag, make_box(Vec3(6.0f))),
                   test::instance_edit("backdrop-" + tag, "backdrop-" + tag),
                   SetCamera{Vec3(1, 3, 12), Vec3(0), Vec3(0, 1, 0), 50.0f});
}

std::string render_png(Engine& engine) {
    RenderRequest r;
    r.width = 48;
    r.height = 32;
    r.spp = 2;
    auto f = engine.render(r);
    EXPECT_TRUE(f.has_value()) << (f ? "" : f.error().describe());
    return f ? f->bytes : std::string();
}

/// A snapshot of a scene built by `build_scene`, at that scene's version.
std::string snapshot_of(uint64_t seed, int batches, const std::string& tag) {
    auto source = test::make_engine();
    build_scene(*source, seed, batches, tag);
    return source->read(
        [](const Scene& s) { return durable::encode_snapshot(s.to_batch(), s.version()); });
}

/// A later batch that touches the snapshot's objects: after a replace it must apply the same
/// way as on a fresh engine restored from the snapshot.
EditBatch follow_up(const std::string& tag) {
    EditBatch b;
    UpdateGroup moved;
    moved.group = "car-" + tag;
    moved.transform = Affine::translation({2, 0, -1});
    b.edits.emplace_back(moved);
    b.edits.emplace_back(RemoveInstance{"b-" + tag});
    UpdateLight dimmer;
    dimmer.light = "lamp-" + tag;
    dimmer.intensity = 5.0f;
    b.edits.emplace_back(dimmer);
    return b;
}

TEST(SnapshotReplace, AFullSceneReplacedByASnapshotMatchesAFreshEngineRestoredFromIt) {
    const std::string bytes = snapshot_of(21, 30, "new");
    auto view = durable::open_snapshot(bytes);
    ASSERT_TRUE(view.has_value());
    // The replaced engine holds another scene, built and rendered (BLASes, TLAS, frame state).
    auto replaced = test::make_engine();
    build_scene(*replaced, 5, 12, "old");
    const uint64_t old_version = test::version_of(*replaced);
    ASSERT_LT(old_version, view->version);
    (void)render_png(*replaced);
    (void)test::hits(*replaced);

    auto done = replaced->replace_with_snapshot(view->payload, view->version);
    ASSERT_TRUE(done.has_value()) << done.error().describe();
    EXPECT_EQ(done->old_version, old_version);
    EXPECT_EQ(done->version, view->version);

    auto fresh = test::make_engine();
    ASSERT_TRUE(fresh->restore_snapshot(view->payload, view->version).has_value());
    EXPECT_EQ(test::version_of(*replaced), view->version);
    EXPECT_EQ(encoded_scene(*replaced), encoded_scene(*fresh));
    replaced->read([](const Scene& s) {
        EXPECT_TRUE(s.find_instance("a-old").is_null());
        EXPECT_TRUE(s.find_group("car-old").is_null());
        EXPECT_TRUE(s.find_light("lamp-old").is_null());
        EXPECT_TRUE(s.find_texture("checker-old").is_null());
        EXPECT_FALSE(s.find_texture("checker-new").is_null());
        EXPECT_EQ(s.groups().size(), 2u);
        EXPECT_EQ(s.lights().size(), 1u);
    });
    const test::Hits hits = test::hits(*replaced);
    EXPECT_TRUE(hits == test::hits(*fresh));
    std::set<std::string> seen(hits.instance.begin(), hits.instance.end());
    EXPECT_TRUE(seen.count("backdrop-new")) << "the frame should show the new scene";
    EXPECT_FALSE(seen.count("backdrop-old"));
    EXPECT_EQ(render_png(*replaced), render_png(*fresh));

    // Following on from the snapshot's version: the same batch, the same result.
    auto next_replaced = replaced->apply(follow_up("new"), view->version);
    auto next_fresh = fresh->apply(follow_up("new"), view->version);
    ASSERT_TRUE(next_replaced.has_value()) << next_replaced.error().describe();
    ASSERT_TRUE(next_fresh.has_value()) << next_fresh.error().describe();
    EXPECT_EQ(next_replaced->version, view->version + 1);
    EXPECT_EQ(encoded_scene(*replaced), encoded_scene(*fresh));
    EXPECT_TRUE(test::hits(*replaced) == test::hits(*fresh));
    EXPECT_EQ(render_png(*replaced), render_png(*fresh));
}

TEST(SnapshotReplace, ReadersAndRendersDuringAReplaceSeeTheOldSceneOrTheNewOneNeverAMix) {
    const std::string bytes = snapshot_of(21, 30, "new");
    auto view = durable::open_snapshot(bytes);
    ASSERT_TRUE(view.has_value());
    auto engine = test::make_engine();
    build_scene(*engine, 5, 12, "old");
    const uint64_t old_version = test::version_of(*engine);
    const std::size_t new_instances = [&] {
        auto fresh = test::make_engine();
        EXPECT_TRUE(fresh->restore_snapshot(view->payload, view->version).has_value());
        return fresh->read([](const Scene& s) { return s.instances().size(); });
    }();
    const std::size_t old_instances = engine->read([](const Scene& s) {
        return s.instances().size();
    });
    std::atomic<bool> stop{false};
    std::atomic<int> mixed{0}, reads{0}, renders{0};
    std::vector<uint64_t> rendered;  // the render thread's versions, in order
    std::thread reader([&] {
        while (!stop) {
            engine->read([&](const Scene& s) {
                const bool old_scene = s.version() == old_version &&
                                       !s.find_instance("a-old").is_null() &&
                                       s.find_instance("a-new").is_null() &&
                                       s.instances().size() == old_instances;
                const bool new_scene = s.version() == view->version &&
                                       s.find_instance("a-old").is_null() &&
                                       !s.find_instance("a-new").is_null() &&
                                       s.instances().size() == new_instances;
                if (!old_scene && !new_scene) ++mixed;
            });
            ++reads;
        }
    });
    std::thread renderer([&] {
        PrimarySettings settings;
        settings.width = 32;
        settings.height = 24;
        while (!stop) {
            auto f = engine->render_primary(settings);
            if (f) rendered.push_back(f->info.version);
            ++renders;
        }
    });
    while (reads < 10 || renders < 2) std::this_thread::yield();
    auto done = engine->replace_with_snapshot(view->payload, view->version);
    const int renders_at_swap = renders;
    while (renders < renders_at_swap + 2) std::this_thread::yield();
    stop = true;
    reader.join();
    renderer.join();
    ASSERT_TRUE(done.has_value()) << done.error().describe();
    EXPECT_EQ(mixed, 0);
    ASSERT_FALSE(rendered.empty());
    EXPECT_EQ(rendered.front(), old_version);
    EXPECT_EQ(rendered.back(), view->version);
    for (std::size_t i = 0; i < rendered.size(); ++i) {
        EXPECT_TRUE(rendered[i] == old_version || rendered[i] == view->version) << rendered[i];
        if (i > 0) {
            EXPECT_LE(rendered[i - 1], rendered[i]) << "a render went back in time";
        }
    }
}

TEST(SnapshotReplace, AnEmptyEngineIsReplacedLikeARestore) {
    const std::string bytes = snapshot_of(3, 8, "s");
    auto view = durable::open_snapshot(bytes);
    ASSERT_TRUE(view.has_value());
    auto replaced = test::make_engine();
    auto fresh = test::make_engine();
    auto done = replaced->replace_with_snapshot(view->payload, view->version);
    ASSERT_TRUE(done.has_value()) << done.error().describe();
    EXPECT_EQ(done->old_version, 0u);
    ASSERT_TRUE(fresh->restore_snapshot(view->payload, view->version).has_value());
    EXPECT_EQ(encoded_scene(*replaced), encoded_scene(*fresh));
    EXPECT_TRUE(test::hits(*replaced) == test::hits(*fresh));
}

TEST(SnapshotReplace, AFailedReplaceLeavesTheOldSceneAsItWas) {
    const std::string bytes = snapshot_of(21, 10, "new");
    auto view = durable::open_snapshot(bytes);
    ASSERT_TRUE(view.has_value());
    auto engine = test::make_engine();
    build_scene(*engine, 5, 6, "old");
    const uint64_t version = test::version_of(*engine);
    const std::string scene = encoded_scene(*engine);
    const test::Hits hits = test::hits(*engine);
    const std::string png = render_png(*engine);
    auto unchanged = [&](const char* what) {
        SCOPED_TRACE(what);
        EXPECT_EQ(test::version_of(*engine), version);
        EXPECT_EQ(encoded_scene(*engine), scene);
        EXPECT_TRUE(test::hits(*engine) == hits);
        EXPECT_EQ(render_png(*engine), png);
    };

    // A damaged payload (cut short): undecodable, nothing replaced, the hook never runs.
    bool hook_ran = false;
    auto hook = [&]() -> Status {
        hook_ran = true;
        return {};
    };
    auto cut = engine->replace_with_snapshot(view->payload.substr(0, view->payload.size() - 7),
                                             view->version, hook);
    ASSERT_FALSE(cut.has_value());
    EXPECT_EQ(cut.error().code, ErrorCode::InvalidArgument) << cut.error().describe();
    EXPECT_FALSE(hook_ran);
    unchanged("damaged payload");

    // A payload the rules refuse (an instance of a mesh it does not have): the edit is named.
    EditBatch orphan;
    orphan.edits.emplace_back(test::instance_edit("i", "missing"));
    std::string refused_payload;
    durable::encode_batch(orphan, refused_payload);
    auto refused = engine->replace_with_snapshot(refused_payload, version + 5, hook);
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().edit_index, 0u);
    EXPECT_FALSE(hook_ran);
    unchanged("refused payload");

    // A snapshot at or below the scene's version replaces nothing.
    auto older = engine->replace_with_snapshot(view->payload, version, hook);
    ASSERT_FALSE(older.has_value());
    EXPECT_EQ(older.error().code, ErrorCode::VersionMismatch);
    EXPECT_FALSE(hook_ran);
    unchanged("not newer");

    // The hook's error (the data directory could not write the snapshot) stops the swap.
    auto hook_failed = engine->replace_with_snapshot(view->payload, view->version, [] {
        return Status(failure(ErrorCode::Storage, "disk full"));
    });
    ASSERT_FALSE(hook_failed.has_value());
    EXPECT_EQ(hook_failed.error().message, "disk full");
    unchanged("hook failed");

    // And the engine still takes batches at its old version.
    EXPECT_TRUE(engine->apply(follow_up("old"), version).has_value());
}

// Through a data directory: the replace is durable, and a restart recovers the snapshot's version
// plus the records after it, never the old scene followed by a gap.

durable::StoreOptions options_for(const TempDir& dir) {
    durable::StoreOptions o;
    o.dir = dir.path();
    o.journal.mode = durable::FsyncMode::Always;
    o.snapshot_threshold_bytes = UINT64_MAX;  // snapshots only when a test asks
    return o;
}

struct Stored {
    std::unique_ptr<Engine> engine = test::make_engine();
    std::unique_ptr<durable::DurableStore> store;
    explicit Stored(const TempDir& dir) {
        auto s = durable::DurableStore::open(options_for(dir), *engine);
        EXPECT_TRUE(s.has_value()) << (s ? "" : s.error().describe());
        if (s) store = std::move(s.value());
    }
    ~Stored() {
        store.reset();
        engine.reset();
    }
};

std::set<std::string> files_in(const TempDir& dir) {
    std::set<std::string> out;
    for (const auto& e : std::filesystem::directory_iterator(dir.path()))
        out.insert(e.path().filename().string());
    out.erase("LOCK");
    return out;
}

TEST(SnapshotReplace, ThroughADataDirectoryARestartRecoversTheSnapshotAndTheRecordsAfterIt) {
    TempDir dir;
    const std::string bytes = snapshot_of(21, 30, "new");
    auto view = durable::open_snapshot(bytes);
    ASSERT_TRUE(view.has_value());
    std::string scene;
    test::Hits hits;
    {
        Stored s(dir);
        ASSERT_TRUE(s.store);
        build_scene(*s.engine, 5, 4, "old");
        ASSERT_TRUE(s.store->snapshot_now().has_value());
        test::apply_ok(*s.engine, SetCamera{Vec3(2, 3, 12), Vec3(0), Vec3(0, 1, 0), 50.0f});
        ASSERT_LT(test::version_of(*s.engine), view->version);

        auto done = s.store->replace_scene(bytes);
        ASSERT_TRUE(done.has_value()) << done.error().describe();
        EXPECT_EQ(test::version_of(*s.engine), view->version);
        EXPECT_EQ(s.store->stats().last_snapshot_version, view->version);
        // The old scene's snapshot and journal are gone; the new segment starts at the snapshot.
        EXPECT_EQ(files_in(dir), (std::set<std::string>{durable::snapshot_name(view->version),
                                                         durable::segment_name(view->version)}));
        ASSERT_TRUE(s.engine->apply(follow_up("new"), view->version).has_value());
        scene = encoded_scene(*s.engine);
        hits = test::hits(*s.engine);
    }
    Stored s(dir);
    ASSERT_TRUE(s.store);
    EXPECT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(s.store->recovery().snapshot_version, view->version);
    EXPECT_EQ(s.store->recovery().records_replayed, 1u);
    EXPECT_EQ(test::version_of(*s.engine), view->version + 1);
    EXPECT_EQ(encoded_scene(*s.engine), scene);
    EXPECT_TRUE(test::hits(*s.engine) == hits);
}

TEST(SnapshotReplace, ThroughADataDirectoryAFailedReplaceChangesNeitherSceneNorFiles) {
    TempDir dir;
    const std::string bytes = snapshot_of(21, 10, "new");
    std::string scene;
    uint64_t version = 0;
    std::set<std::string> files;
    {
        Stored s(dir);
        ASSERT_TRUE(s.store);
        build_scene(*s.engine, 5, 4, "old");
        version = test::version_of(*s.engine);
        scene = encoded_scene(*s.engine);
        files = files_in(dir);
        // Damaged bytes: a flipped byte in the payload fails the snapshot's checksum.
        std::string damaged = bytes;
        damaged[damaged.size() / 2] ^= 0x20;
        EXPECT_FALSE(s.store->replace_scene(damaged).has_value());
        // Whole bytes the engine refuses to load, with a valid checksum.
        EditBatch orphan;
        orphan.edits.emplace_back(test::instance_edit("i", "missing"));
        auto refused = s.store->replace_scene(durable::encode_snapshot(orphan, version + 9));
        ASSERT_FALSE(refused.has_value());
        EXPECT_EQ(refused.error().edit_index, 0u);
        EXPECT_EQ(test::version_of(*s.engine), version);
        EXPECT_EQ(encoded_scene(*s.engine), scene);
        EXPECT_EQ(files_in(dir), files);
        // The journal goes on as before.
        ASSERT_TRUE(s.engine->apply(follow_up("old"), version).has_value());
        scene = encoded_scene(*s.engine);
    }
    Stored s(dir);
    ASSERT_TRUE(s.store);
    EXPECT_EQ(test::version_of(*s.engine), version + 1);
    EXPECT_EQ(encoded_scene(*s.engine), scene);
}

}  // namespace
}  // namespace strata
