// Durability at the engine level: a DurableStore over a temporary directory, real files, real
// fsyncs. After a restart the scene has the same version, the same ids and the same hits; torn
// and damaged journals give the documented outcome and a message naming file and offset.

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include <gtest/gtest.h>

#include "engine/durable/durable_store.h"
#include "engine/durable/file_io.h"
#include "engine/durable/journal_format.h"
#include "engine/durable/past_version.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"
#include "tests/engine/texture_test_util.h"

namespace strata {
namespace {

using durable::DurableStore;
using test::TempDir;

durable::StoreOptions options_for(const TempDir& dir,
                                  durable::FsyncMode mode = durable::FsyncMode::Always) {
    durable::StoreOptions o;
    o.dir = dir.path();
    o.journal.mode = mode;
    o.snapshot_threshold_bytes = UINT64_MAX;  // snapshots only when a test asks
    return o;
}

/// An engine and its store; the store goes first (it detaches the journal from the engine).
struct Server {
    std::unique_ptr<Engine> engine;
    std::unique_ptr<DurableStore> store;

    Server() = default;
    Server(Server&&) = default;
    ~Server() { stop(); }
    void stop() {
        store.reset();
        engine.reset();
    }
};

Server start(const durable::StoreOptions& o) {
    Server s;
    s.engine = test::make_engine();
    auto store = DurableStore::open(o, *s.engine);
    EXPECT_TRUE(store.has_value()) << (store ? "" : store.error().describe());
    if (store) s.store = std::move(store.value());
    return s;
}

/// Applies `n` random batches (the generator's model stays in step); returns the last version.
uint64_t apply_random(Engine& engine, test::RandomEdits& edits, int n, bool initial) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) {
        auto r = engine.apply(initial && i == 0 ? edits.initial_batch(4, 30) : edits.next_batch(6));
        EXPECT_TRUE(r.has_value()) << r.error().describe();
        if (r) v = r->version;
    }
    return v;
}

std::string only_segment(const TempDir& dir) {
    std::string found;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
        uint64_t base = 0;
        if (durable::parse_segment_name(e.path().filename().string(), base)) {
            EXPECT_TRUE(found.empty()) << "more than one segment";
            found = e.path().string();
        }
    }
    return found;
}

TEST(Durability, ARestartBringsBackTheSameVersionIdsAndHits) {
    TempDir dir;
    test::RandomEdits edits(7);
    test::Hits before;
    uint64_t version = 0;
    {
        Server s = start(options_for(dir));
        apply_random(*s.engine, edits, 40, true);
        // Something surely in view, whatever the random batches left (a clear, a camera).
        version = test::apply_ok(*s.engine, test::mesh_edit("backdrop", make_box(Vec3(6.0f))),
                                 test::instance_edit("backdrop-1", "backdrop"),
                                 SetCamera{Vec3(1, 3, 12), Vec3(0), Vec3(0, 1, 0), 50.0f});
        // A refused batch changes nothing and is not journaled.
        EditBatch bad;
        bad.edits.emplace_back(RemoveMesh{"no-such-mesh"});
        ASSERT_FALSE(s.engine->apply(std::move(bad)).has_value());
        before = test::hits(*s.engine);
    }
    Server s = start(options_for(dir));
    EXPECT_EQ(s.store->recovery().records_replayed, version);
    EXPECT_EQ(test::version_of(*s.engine), version);
    const test::Hits after = test::hits(*s.engine);
    EXPECT_TRUE(after == before);
    std::size_t hit = 0;
    for (const auto& id : after.instance) hit += !id.empty();
    EXPECT_GT(hit, after.instance.size() / 20) << "the frame should show geometry";
}

TEST(Durability, ASnapshotPlusTheJournalAfterItRestoresTheScene) {
    TempDir dir;
    test::RandomEdits edits(11);
    test::Hits before;
    uint64_t version = 0;
    std::string scene_before;
    {
        Server s = start(options_for(dir));
        apply_random(*s.engine, edits, 20, true);
        ASSERT_TRUE(s.store->snapshot_now().has_value());
        version = apply_random(*s.engine, edits, 15, false);
        before = test::hits(*s.engine);
        const auto stats = s.store->stats();
        EXPECT_EQ(stats.snapshots_written, 1u);
        EXPECT_EQ(stats.last_snapshot_version, 20u);
        EXPECT_GT(stats.last_snapshot_bytes, 0u);
    }
    // The segment before the snapshot was dropped: one snapshot, one segment.
    int snapshots = 0, segments = 0;
    for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
        uint64_t n;
        snapshots += durable::parse_snapshot_name(e.path().filename().string(), n);
        segments += durable::parse_segment_name(e.path().filename().string(), n);
    }
    EXPECT_EQ(snapshots, 1);
    EXPECT_EQ(segments, 1);
    Server s = start(options_for(dir));
    EXPECT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(s.store->recovery().snapshot_version, 20u);
    EXPECT_EQ(s.store->recovery().records_replayed, 15u);
    EXPECT_EQ(test::version_of(*s.engine), version);
    EXPECT_TRUE(test::hits(*s.engine) == before);
}

TEST(Durability, BulkInstanceEditsSurviveARestartFromJournalAndFromSnapshot) {
    TempDir dir;
    test::Hits before;
    std::vector<std::string> state;
    uint64_t version = 0;
    {
        Server s = start(options_for(dir));
        test::apply_ok(*s.engine, test::mesh_edit("ball", make_sphere(0.3f, 10)),
                       AddGroup{"row", std::nullopt, Affine::translation({0, -1, 0}), true},
                       SetCamera{Vec3(0, 4, 14), Vec3(0), std::nullopt, 60.0f});
        AddInstances add;
        add.ids.prefix = "b";
        add.ids.count = 400;
        add.meshes = {"ball"};
        for (int i = 0; i < 400; ++i)
            add.transforms.push_back(
                Affine::translation({float(i % 20 - 10), 0, float(i / 20 - 10)}));
        test::apply_ok(*s.engine, add);
        UpdateInstances lift;
        lift.ids.list = {"b3", "b77", "b250"};
        lift.transforms.assign(3, Affine::translation({0, 2, 0}));
        test::apply_ok(*s.engine, lift);
        ASSERT_TRUE(s.store->snapshot_now().has_value());
        AddInstances more;
        more.ids.list = {"r0", "r1"};
        more.meshes = {"ball", "ball"};
        more.parent = "row";
        RemoveInstances cut;
        cut.ids.prefix = "b";
        cut.ids.first = 100;
        cut.ids.count = 50;
        UpdateInstances hide;
        hide.ids.prefix = "b";
        hide.ids.first = 300;
        hide.ids.count = 10;
        hide.visible = false;
        version = test::apply_ok(*s.engine, more, cut, hide);
        before = test::hits(*s.engine);
        state = test::state_of(*s.engine);
    }
    Server s = start(options_for(dir));
    EXPECT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(s.store->recovery().records_replayed, 1u);
    EXPECT_EQ(test::version_of(*s.engine), version);
    EXPECT_TRUE(test::state_of(*s.engine) == state);
    EXPECT_TRUE(test::hits(*s.engine) == before);
    // The undo stack came back with the journal: the last batch is taken back in one undo.
    auto undo = s.engine->undo_batch(version);
    ASSERT_TRUE(undo.has_value()) << undo.error().describe();
    ASSERT_TRUE(s.engine->apply(std::move(undo.value()), version).has_value());
    EXPECT_EQ(s.engine->read([](const Scene& sc) { return sc.instances().size(); }), 400u);
    EXPECT_FALSE(s.engine->read([](const Scene& sc) { return sc.find_instance("b120").is_null(); }));
}

TEST(Durability, GroupsAndParentsSurviveARestartThroughTheJournalAndASnapshot) {
    TempDir dir;
    test::Hits before;
    std::vector<std::string> paths_before;
    auto paths = [](Engine& e) {
        return e.read([](const Scene& s) {
            std::vector<std::string> out;
            s.instances().for_each([&](InstanceHandle, const InstanceRecord& i) {
                std::string p = i.id + ":";
                for (const std::string& g : s.group_path(i.parent)) p += "/" + g;
                p += i.world_visible ? "" : " hidden";
                out.push_back(p);
            });
            std::sort(out.begin(), out.end());
            return out;
        });
    };
    {
        Server s = start(options_for(dir));
        AddInstance w0 = test::instance_edit("w0", "box", {1, 0, 0});
        w0.parent = "wheels";
        AddInstance w1 = test::instance_edit("w1", "box", {-1, 0, 0});
        w1.parent = "wheels";
        AddInstance body = test::instance_edit("body", "box", {0, 1, 0});
        body.parent = "car";
        test::apply_ok(*s.engine, test::mesh_edit("box", make_box(Vec3(0.8f))),
                       AddGroup{"car", std::nullopt, Affine::translation({0, 0, -2}), true},
                       AddGroup{"wheels", std::string("car"), Affine::identity(), true}, w0, w1,
                       body, SetCamera{Vec3(0, 2, 9), Vec3(0), Vec3(0, 1, 0), 50.0f});
        ASSERT_TRUE(s.store->snapshot_now().has_value());
        // After the snapshot: journal records with every group op.
        UpdateInstance out;
        out.instance = "w1";
        out.parent = std::optional<std::string>();
        test::apply_ok(*s.engine,
                       UpdateGroup{"car", std::nullopt, Affine::translation({1, 0, -2}), std::nullopt},
                       out, AddGroup{"spare", std::string("car"), Affine::identity(), false});
        AddInstance hidden = test::instance_edit("s0", "box", {0, 2, 0});
        hidden.parent = "spare";
        test::apply_ok(*s.engine, hidden, UpdateGroup{"wheels", std::nullopt, std::nullopt, false});
        test::apply_ok(*s.engine, UpdateGroup{"wheels", std::nullopt, std::nullopt, true},
                       AddGroup{"gone", std::nullopt, Affine::identity(), true},
                       RemoveGroup{"gone", false});
        before = test::hits(*s.engine);
        paths_before = paths(*s.engine);
    }
    Server s = start(options_for(dir));
    EXPECT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(s.store->recovery().records_replayed, 3u);
    EXPECT_EQ(paths(*s.engine), paths_before);
    EXPECT_EQ(paths_before, (std::vector<std::string>{"body:/car", "s0:/car/spare hidden",
                                                      "w0:/car/wheels", "w1:"}));
    EXPECT_TRUE(test::hits(*s.engine) == before);
}

TEST(Durability, NormalsAndUvsSurviveARestartFromJournalAndFromSnapshot) {
    TempDir dir;
    AddMesh m = test::mesh_edit("ball", make_sphere(1.0f, 8));
    for (const Vec3& p : m.positions) m.normals.push_back(glm::normalize(p));
    for (const Vec3& p : m.positions) m.uvs.emplace_back(p.x, p.y);
    UpdateMeshPositions part;
    part.mesh = "ball";
    part.offset = 1;
    part.normals = std::vector<Vec3>{{0, 1, 0}};
    ReplaceMeshTopology topo;
    topo.mesh = "quad";
    topo.triangles = {{0, 2, 1}};
    topo.uvs = std::vector<Vec2>{};
    AddMesh quad = test::mesh_edit("quad", make_plane(Vec3(1.0f), 1, 1));
    quad.uvs = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
    auto attributes = [](const Engine& e) {
        return e.read([](const Scene& s) {
            std::vector<std::vector<float>> out;
            for (const char* id : {"ball", "quad"}) {
                const MeshRecord* r = s.mesh(s.find_mesh(id)).value();
                std::vector<float> flat;
                for (const Vec3& n : r->normals) flat.insert(flat.end(), {n.x, n.y, n.z});
                flat.push_back(-1.0f);  // separates normals from uvs
                for (const Vec2& uv : r->uvs) flat.insert(flat.end(), {uv.x, uv.y});
                out.push_back(std::move(flat));
            }
            return out;
        });
    };
    std::vector<std::vector<float>> before;
    {
        Server s = start(options_for(dir));
        test::apply_ok(*s.engine, m, quad);
        test::apply_ok(*s.engine, part, topo);
        before = attributes(*s.engine);
        ASSERT_EQ(before[1].size(), 1u) << "the quad's uvs were removed";
    }
    {
        Server s = start(options_for(dir));
        EXPECT_EQ(s.store->recovery().records_replayed, 2u);
        EXPECT_EQ(attributes(*s.engine), before);
        ASSERT_TRUE(s.store->snapshot_now().has_value());
    }
    Server s = start(options_for(dir));
    EXPECT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(attributes(*s.engine), before);
}

TEST(Durability, TexturesAndMaterialBindingsSurviveARestartFromJournalAndFromSnapshot) {
    TempDir dir;
    AddMaterial m{"m", Material{}};
    m.textures[0] = "checker";
    m.material.base_color_sampler = {TextureWrap::Mirror, TextureFilter::Nearest};
    UpdateMaterial rebind;
    rebind.material = "m";
    rebind.textures[0] = std::optional<std::string>("photo");
    rebind.wrap = TextureWrap::Clamp;
    auto state = [](const Engine& e) {
        return e.read([](const Scene& s) {
            std::string out;
            s.textures().for_each([&](TextureHandle, const TextureRecord& t) {
                out += t.id + ":" + std::to_string(t.image->width) + "x" +
                       std::to_string(t.image->height) + ";";
            });
            const MaterialRecord* mat = s.material(s.find_material("m")).value();
            out += "m->" + s.texture(mat->textures[0]).value()->id + " wrap " +
                   texture_wrap_name(mat->material.base_color_sampler.wrap) + " filter " +
                   texture_filter_name(mat->material.base_color_sampler.filter);
            out += " bytes " + std::to_string(s.mesh_totals().texture_bytes);
            return out;
        });
    };
    std::string before;
    {
        Server s = start(options_for(dir));
        test::apply_ok(*s.engine, AddTexture{"checker", test::four_colour_png()}, m);
        const std::string photo = test::jpeg_bytes(8, 4, 200, 100, 50);
        test::apply_ok(*s.engine, AddTexture{"photo", photo}, rebind, RemoveTexture{"checker"});
        before = state(*s.engine);
        // 32 texels of 6 bytes, and the file.
        ASSERT_EQ(before, "photo:8x4;m->photo wrap clamp filter nearest bytes " +
                              std::to_string(192 + photo.size()));
    }
    {
        Server s = start(options_for(dir));
        EXPECT_EQ(s.store->recovery().records_replayed, 2u);
        EXPECT_EQ(state(*s.engine), before);
        ASSERT_TRUE(s.store->snapshot_now().has_value());
    }
    Server s = start(options_for(dir));
    EXPECT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(state(*s.engine), before);
}

TEST(Durability, ATornLastRecordIsCutOffAndReported) {
    TempDir dir;
    test::RandomEdits edits(3);
    {
        Server s = start(options_for(dir));
        apply_random(*s.engine, edits, 10, true);
    }
    const std::string segment = only_segment(dir);
    const auto size = std::filesystem::file_size(segment);
    std::filesystem::resize_file(segment, size - 3);
    Server s = start(options_for(dir));
    EXPECT_EQ(test::version_of(*s.engine), 9u);
    EXPECT_EQ(s.store->recovery().torn_truncated, 1u);
    bool noted = false;
    for (const auto& n : s.store->recovery().notes)
        noted |= n.find("torn last record") != std::string::npos;
    EXPECT_TRUE(noted);
    // The journal goes on after the cut: the next batch is version 10 and survives a restart.
    test::apply_ok(*s.engine, SetCamera{Vec3(0, 1, 9), std::nullopt, std::nullopt, std::nullopt});
    s.stop();
    Server again = start(options_for(dir));
    EXPECT_EQ(test::version_of(*again.engine), 10u);
}

TEST(Durability, AFlippedByteInTheMiddleRefusesToStartNamingFileAndOffset) {
    TempDir dir;
    test::RandomEdits edits(5);
    {
        Server s = start(options_for(dir));
        apply_random(*s.engine, edits, 10, true);
    }
    const std::string segment = only_segment(dir);
    auto bytes = durable::read_whole_file(segment).value();
    const auto scan = durable::scan_segment(bytes);
    ASSERT_EQ(scan.records.size(), 10u);
    const uint64_t at = scan.records[4].offset;
    bytes[at + 20] ^= 0x40;
    std::ofstream(segment, std::ios::binary | std::ios::trunc) << bytes;

    auto engine = test::make_engine();
    auto refused = DurableStore::open(options_for(dir), *engine);
    ASSERT_FALSE(refused.has_value());
    const std::string msg = refused.error().message;
    EXPECT_NE(msg.find(segment), std::string::npos) << msg;
    EXPECT_NE(msg.find("offset " + std::to_string(at)), std::string::npos) << msg;
    EXPECT_NE(msg.find("--recover-truncate"), std::string::npos) << msg;

    auto o = options_for(dir);
    o.recovery.truncate_damage = true;
    Server s = start(o);
    EXPECT_EQ(test::version_of(*s.engine), 4u);
}

TEST(Durability, AnEmptyJournalFileStartsAnEmptyScene) {
    TempDir dir;
    std::ofstream(dir.file(durable::segment_name(0)));  // zero bytes
    Server s = start(options_for(dir));
    ASSERT_TRUE(s.store);
    EXPECT_EQ(test::version_of(*s.engine), 0u);
    test::apply_ok(*s.engine, SetCamera{Vec3(0, 1, 9), std::nullopt, std::nullopt, std::nullopt});
    s.stop();
    EXPECT_EQ(test::version_of(*start(options_for(dir)).engine), 1u);
}

TEST(Durability, ASnapshotWithoutAJournalIsLoadedAlone) {
    TempDir dir;
    test::RandomEdits edits(9);
    auto engine = test::make_engine();
    apply_random(*engine, edits, 5, true);
    const test::Hits before = test::hits(*engine);
    const EditBatch scene = engine->read([](const Scene& s) { return s.to_batch(); });
    ASSERT_TRUE(durable::write_file_atomically(dir.path(), durable::snapshot_name(5),
                                               durable::encode_snapshot(scene, 5))
                    .has_value());
    Server s = start(options_for(dir));
    EXPECT_EQ(test::version_of(*s.engine), 5u);
    EXPECT_TRUE(test::hits(*s.engine) == before);
}

TEST(Durability, ADamagedSnapshotRefusesToStart) {
    TempDir dir;
    std::ofstream(dir.file(durable::snapshot_name(3)), std::ios::binary) << "STRATAS1 not really";
    auto engine = test::make_engine();
    auto refused = DurableStore::open(options_for(dir), *engine);
    ASSERT_FALSE(refused.has_value());
    EXPECT_NE(refused.error().message.find(durable::snapshot_name(3)), std::string::npos)
        << refused.error().message;
}

TEST(Durability, TwoStoresCannotShareADirectory) {
    TempDir dir;
    Server first = start(options_for(dir));
    auto engine = test::make_engine();
    auto second = DurableStore::open(options_for(dir), *engine);
    ASSERT_FALSE(second.has_value());
    EXPECT_NE(second.error().message.find("in use by another strata-server"), std::string::npos)
        << second.error().message;
}

TEST(Durability, AMissingDirectoryIsCreated) {
    TempDir dir;
    auto o = options_for(dir);
    o.dir = dir.path() + "/a/b";
    Server s = start(o);
    ASSERT_TRUE(s.store);
    EXPECT_TRUE(std::filesystem::is_directory(o.dir));
}

TEST(Durability, ConcurrentBatchesShareFsyncs) {
    TempDir dir;
    Server s = start(options_for(dir));
    test::apply_ok(*s.engine, test::mesh_edit("box", make_box(Vec3(1))));
    constexpr int THREADS = 8, PER_THREAD = 40;
    std::vector<std::thread> threads;
    for (int t = 0; t < THREADS; ++t) {
        threads.emplace_back([&, t] {
            for (int i = 0; i < PER_THREAD; ++i)
                test::apply_ok(
                    *s.engine,
                    test::instance_edit("i" + std::to_string(t) + "-" + std::to_string(i), "box"));
        });
    }
    for (auto& t : threads) t.join();
    const auto stats = s.store->stats();
    EXPECT_EQ(stats.journal_records, 1u + THREADS * PER_THREAD);
    // Every batch waited for an fsync; most shared one with others.
    EXPECT_LT(stats.fsyncs, stats.journal_records);
    EXPECT_GT(stats.batches_per_fsync_max, 1u);
    uint64_t observed = 0;
    for (uint64_t b : stats.fsync_buckets) observed += b;
    EXPECT_GT(observed, 0u);
    s.stop();
    EXPECT_EQ(test::version_of(*start(options_for(dir)).engine), 1u + THREADS * PER_THREAD);
}

TEST(Durability, EveryFsyncModeKeepsWhatAGracefulStopWrote) {
    for (auto mode :
         {durable::FsyncMode::Always, durable::FsyncMode::Batch, durable::FsyncMode::Off}) {
        TempDir dir;
        test::RandomEdits edits(21);
        uint64_t version = 0;
        {
            Server s = start(options_for(dir, mode));
            version = apply_random(*s.engine, edits, 12, true);
        }
        EXPECT_EQ(test::version_of(*start(options_for(dir, mode)).engine), version)
            << durable::fsync_mode_name(mode);
    }
}

using test::state_of;

TEST(PastVersion, EveryVersionTheDirectoryHoldsLoadsAsItWasWithoutTouchingIt) {
    TempDir dir;
    Server s = start(options_for(dir));
    test::RandomEdits edits(11);
    std::map<uint64_t, std::vector<std::string>> states;
    for (int i = 0; i < 12; ++i) {
        const uint64_t v = apply_random(*s.engine, edits, 1, i == 0);
        states[v] = state_of(*s.engine);
        if (i == 3) {
            // Before any snapshot, the journal reaches back to the empty scene.
            auto past = durable::load_past_version(dir.path(), 2, EngineConfig{});
            ASSERT_TRUE(past.has_value()) << past.error().describe();
            EXPECT_EQ(state_of(*past.value()), states[2]);
        }
        if (i == 5) {
            ASSERT_TRUE(s.store->snapshot_now().has_value());
        }
    }
    const auto files_before = std::distance(std::filesystem::directory_iterator(dir.path()),
                                            std::filesystem::directory_iterator());
    for (uint64_t v = 1; v <= 13; ++v) {
        durable::PastVersionLoad load;
        auto past = durable::load_past_version(dir.path(), v, EngineConfig{}, &load);
        if (v < 6 || v == 13) {
            // Before the snapshot (its files are gone), or after the journal's end.
            ASSERT_FALSE(past.has_value()) << v;
            EXPECT_EQ(past.error().code, ErrorCode::OutOfRange) << past.error().describe();
            continue;
        }
        ASSERT_TRUE(past.has_value()) << v << ": " << past.error().describe();
        EXPECT_EQ(past.value()->version(), v);
        EXPECT_EQ(state_of(*past.value()), states[v]) << v;
        EXPECT_EQ(load.snapshot_version, 6u);
        EXPECT_EQ(load.records_replayed, v - 6);
        // It renders: its first commit builds everything.
        EXPECT_TRUE(past.value()->commit().has_value());
    }
    // Nothing in the directory changed, and the live scene went on.
    EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                            std::filesystem::directory_iterator()),
              files_before);
    EXPECT_EQ(state_of(*s.engine), states[12]);
    EXPECT_TRUE(s.engine->apply(edits.next_batch(3)).has_value());
}

TEST(PastVersion, ADamagedRecordOnTheWayIsAStorageErrorNamingTheFile) {
    TempDir dir;
    {
        Server s = start(options_for(dir));
        test::RandomEdits edits(5);
        apply_random(*s.engine, edits, 4, true);
    }
    const std::string segment = only_segment(dir);
    std::fstream f(segment, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(durable::SEGMENT_HEADER_BYTES + durable::RECORD_HEADER_BYTES + 2);
    f.put('\x5a');
    f.close();
    auto past = durable::load_past_version(dir.path(), 4, EngineConfig{});
    ASSERT_FALSE(past.has_value());
    EXPECT_EQ(past.error().code, ErrorCode::Storage);
    EXPECT_NE(past.error().message.find(segment), std::string::npos) << past.error().message;
}

TEST(PastVersion, KeptHistoryReachesBehindSnapshotsAndSurvivesARestart) {
    TempDir dir;
    durable::StoreOptions o = options_for(dir);
    o.keep_history_bytes = 64 << 20;
    std::map<uint64_t, std::vector<std::string>> states;
    test::RandomEdits edits(23);
    {
        Server s = start(o);
        for (int i = 0; i < 12; ++i) {
            const uint64_t v = apply_random(*s.engine, edits, 1, i == 0);
            states[v] = state_of(*s.engine);
            if (i == 3 || i == 7) {
                ASSERT_TRUE(s.store->snapshot_now().has_value());
            }
        }
    }
    {
        // Recovery starts from the newest snapshot and leaves the older files where they are.
        Server s = start(o);
        EXPECT_EQ(state_of(*s.engine), states[12]);
        EXPECT_EQ(s.store->recovery().snapshot_version, 8u);
        for (uint64_t v = 1; v <= 12; ++v) {
            auto past = durable::load_past_version(dir.path(), v, EngineConfig{});
            ASSERT_TRUE(past.has_value()) << v << ": " << past.error().describe();
            EXPECT_EQ(state_of(*past.value()), states[v]) << v;
        }
    }
    // A budget that holds nothing older: the next snapshot removes what it covers.
    o.keep_history_bytes = 1;
    Server s = start(o);
    apply_random(*s.engine, edits, 1, false);
    ASSERT_TRUE(s.store->snapshot_now().has_value());
    auto gone = durable::load_past_version(dir.path(), 9, EngineConfig{});
    ASSERT_FALSE(gone.has_value());
    EXPECT_EQ(gone.error().code, ErrorCode::OutOfRange);
}

// Step: the history across snapshots -------------------------------------------------------------

/// Applies the engine's undo (or redo) batch at its version; false when there is none.
bool take_back(Engine& e, bool redo = false) {
    auto batch = redo ? e.redo_batch(e.version()) : e.undo_batch(e.version());
    if (!batch) return false;
    auto applied = e.apply(std::move(batch.value()), e.version());
    EXPECT_TRUE(applied.has_value()) << applied.error().describe();
    return applied.has_value();
}

bool has_mesh(const Engine& e, const char* id) {
    return e.read([&](const Scene& s) { return !s.find_mesh(id).is_null(); });
}

TEST(HistoryFile, UndoReachesPastSnapshotsAfterARestart) {
    TempDir dir;
    {
        Server s = start(options_for(dir));
        EditBatch first;
        first.edits.emplace_back(test::mesh_edit("a", make_box(Vec3(1))));
        first.info.message = "the first box";
        ASSERT_TRUE(s.engine->apply(std::move(first)).has_value());
        test::apply_ok(*s.engine, test::mesh_edit("b", make_box(Vec3(1))));
        test::apply_ok(*s.engine, test::mesh_edit("c", make_box(Vec3(1))));
        ASSERT_TRUE(take_back(*s.engine));  // c undone: on the redo stack
        ASSERT_TRUE(s.store->snapshot_now().has_value());
        test::apply_ok(*s.engine, test::mesh_edit("d", make_box(Vec3(1))));
        ASSERT_TRUE(s.store->snapshot_now().has_value());  // two snapshots between
        test::apply_ok(*s.engine, test::mesh_edit("e", make_box(Vec3(1))));
    }
    Server s = start(options_for(dir));
    ASSERT_TRUE(s.store->recovery().loaded_snapshot);
    EXPECT_EQ(s.store->recovery().snapshot_version, 5u);
    const HistoryPage page = s.engine->history(100, 0);
    ASSERT_EQ(page.entries.size(), 6u);  // five versions and the undo
    EXPECT_EQ(page.entries.back().info.message, "the first box");
    EXPECT_EQ(page.undo_depth, 4u);  // e, d, b, a: c was undone, and d emptied the redo stack
    // Undo walks back over both snapshots to the empty scene.
    for (const char* id : {"e", "d", "b", "a"}) {
        ASSERT_TRUE(take_back(*s.engine)) << id;
        EXPECT_FALSE(has_mesh(*s.engine, id)) << id;
    }
    EXPECT_FALSE(take_back(*s.engine));
    EXPECT_EQ(s.engine->read([](const Scene& sc) { return sc.meshes().size(); }), 0u);
    // Redo brings them back in order.
    ASSERT_TRUE(take_back(*s.engine, true));
    EXPECT_TRUE(has_mesh(*s.engine, "a"));
}

TEST(HistoryFile, AMissingOrDamagedHistoryFileCostsTheHistoryNotTheScene) {
    for (const bool damaged : {false, true}) {
        TempDir dir;
        {
            Server s = start(options_for(dir));
            test::apply_ok(*s.engine, test::mesh_edit("a", make_box(Vec3(1))));
            ASSERT_TRUE(s.store->snapshot_now().has_value());
            test::apply_ok(*s.engine, test::mesh_edit("b", make_box(Vec3(1))));
        }
        const std::string history = dir.file(durable::history_name(1));
        if (damaged) {
            std::fstream f(history, std::ios::in | std::ios::out | std::ios::binary);
            f.seekp(40);
            f.put('\x7f');
        } else {
            ASSERT_EQ(std::remove(history.c_str()), 0);
        }
        Server s = start(options_for(dir));
        EXPECT_TRUE(has_mesh(*s.engine, "a"));
        EXPECT_TRUE(has_mesh(*s.engine, "b"));
        bool noted = false;
        for (const std::string& n : s.store->recovery().notes)
            noted = noted || n.find("checksum mismatch") != std::string::npos;
        EXPECT_EQ(noted, damaged);
        // The journal after the snapshot still gives its undo; nothing before it.
        ASSERT_TRUE(take_back(*s.engine));
        EXPECT_FALSE(has_mesh(*s.engine, "b"));
        EXPECT_FALSE(take_back(*s.engine));
    }
}

TEST(HistoryFile, EncodingRoundTripsAndRefusesDamage) {
    HistoryState h;
    EditBatch inverse;
    inverse.edits.emplace_back(RemoveMesh{"a"});
    h.entries.push_back({1, BatchInfo{BatchKind::Edits, 0, 1795000000000, "first"}, 1, {{0, 1}}});
    h.undo.push_back({1, std::make_shared<const EditBatch>(inverse)});
    inverse.info = BatchInfo{BatchKind::Undo, 1, 0, ""};
    h.redo.push_back({1, std::make_shared<const EditBatch>(inverse)});
    const std::string bytes = durable::encode_history(h, 7);
    auto back = durable::decode_history(bytes);
    ASSERT_TRUE(back.has_value()) << back.error().describe();
    EXPECT_EQ(back->version, 7u);
    EXPECT_EQ(durable::encode_history(back->state, 7), bytes);
    for (std::size_t n = 0; n < bytes.size(); ++n)
        EXPECT_FALSE(durable::decode_history(std::string_view(bytes).substr(0, n)).has_value()) << n;
    EXPECT_FALSE(durable::decode_history(durable::encode_snapshot({}, 7)).has_value());
}

}  // namespace
}  // namespace strata
