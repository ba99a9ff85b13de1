// What makes snapshots cheap: the scene's slot arrays and mesh buffers are copy-on-write, so a
// snapshot's image of the scene is taken without copying it and stays at its version while edits
// go on; and a snapshot is restored straight into the scene's storage (Engine::restore_snapshot)
// with the same result as applying its batch.

#include <atomic>
#include <thread>
#include <utility>

#include <gtest/gtest.h>

#include "engine/core/cow.h"
#include "engine/core/handle.h"
#include "engine/durable/edit_codec.h"
#include "engine/durable/journal_format.h"
#include "engine/scene/scene.h"
#include "tests/engine/durable_test_util.h"
#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::encoded;

struct Item {
    int value = 0;
};
struct ItemTag;

TEST(CopyOnWrite, ACopiedSlotArraySharesEveryChunkUntilOneIsWritten) {
    using Array = SlotArray<Item, ItemTag>;
    Array a;
    std::vector<Handle<ItemTag>> handles;
    for (int i = 0; i < 5 * int(Array::CHUNK); ++i) handles.push_back(a.insert({i}));
    const Array copy = a;
    EXPECT_EQ(a.shared_chunks(), 5u);
    // A write copies the one chunk it lands in; the copy keeps the old value.
    a.at(handles[3 * Array::CHUNK + 7]).value = -1;
    EXPECT_EQ(a.shared_chunks(), 4u);
    EXPECT_EQ(copy.at(handles[3 * Array::CHUNK + 7]).value, int(3 * Array::CHUNK + 7));
    // Erase, reuse and undo on the original leave the copy's slots and generations alone.
    ASSERT_TRUE(a.erase(handles[10]));
    bool reused = false;
    const auto h = a.insert({99}, &reused);
    EXPECT_TRUE(reused);
    EXPECT_EQ(h.index, handles[10].index);
    EXPECT_FALSE(a.contains(handles[10]));
    EXPECT_TRUE(copy.contains(handles[10]));
    EXPECT_EQ(copy.at(handles[10]).value, 10);
    EXPECT_EQ(copy.size(), 5 * Array::CHUNK);
    // Reading through a const array copies nothing.
    int sum = 0;
    std::as_const(a).for_each([&](auto, const Item& it) { sum += it.value > 0; });
    EXPECT_EQ(a.shared_chunks(), 3u);
}

TEST(CopyOnWrite, UndoingAnInsertPastTheEndRestoresTheArrayExactly) {
    using Array = SlotArray<Item, ItemTag>;
    Array a;
    for (int i = 0; i < int(Array::CHUNK); ++i) a.insert({i});
    const Array copy = a;
    const auto h = a.insert({1});  // opens a new chunk
    EXPECT_EQ(a.slot_count(), Array::CHUNK + 1);
    a.undo_insert(h, false);
    EXPECT_EQ(a.slot_count(), Array::CHUNK);
    EXPECT_EQ(a.insert({2}).generation, 0u);
    EXPECT_EQ(copy.slot_count(), Array::CHUNK);
}

TEST(CopyOnWrite, AVectorIsSharedByCopiesAndCopiedOnlyWhenWrittenWhileShared) {
    CowVector<int> v(std::vector<int>{1, 2, 3});
    CowVector<int> w = v;
    EXPECT_EQ(v.data(), w.data());
    v.mut()[0] = 7;
    EXPECT_NE(v.data(), w.data());
    EXPECT_EQ(w[0], 1);
    const int* before = v.data();
    v.mut()[1] = 8;  // no longer shared: written in place
    EXPECT_EQ(v.data(), before);
    CowVector<int> empty;
    EXPECT_TRUE(empty.empty());
    EXPECT_EQ(empty.size(), 0u);
}

/// A scene with meshes, materials and instances, built by random batches.
Scene random_scene(test::RandomEdits& edits, int batches) {
    Scene scene;
    for (int i = 0; i < batches; ++i) {
        auto r = scene.apply(i == 0 ? edits.initial_batch(6, 200) : edits.next_batch(8));
        EXPECT_TRUE(r.has_value()) << r.error().describe();
    }
    scene.clear_changes();
    return scene;
}

TEST(SceneImage, IsTakenWithoutCopyingTheSceneAndStaysAtItsVersionWhileEditsGoOn) {
    test::RandomEdits edits(5);
    Scene scene = random_scene(edits, 10);
    const std::string at_image = encoded(scene.to_batch());
    const SceneImage image = scene.image();
    EXPECT_EQ(image.version, scene.version());
    // Nothing was copied: the image holds the scene's own chunks and mesh buffers.
    using Instances = SlotArray<InstanceRecord, InstanceTag>;
    const std::size_t chunks = (scene.instances().slot_count() + Instances::CHUNK - 1) /
                               Instances::CHUNK;
    EXPECT_GT(chunks, 0u);
    EXPECT_EQ(scene.instances().shared_chunks(), chunks);
    scene.meshes().for_each([&](MeshHandle h, const MeshRecord& m) {
        EXPECT_EQ(image.meshes.at(h).positions.data(), m.positions.data());
    });
    // Edits of every kind go on; the image still describes the scene as it was.
    for (int i = 0; i < 30; ++i) {
        auto r = scene.apply(edits.next_batch(8));
        ASSERT_TRUE(r.has_value()) << r.error().describe();
    }
    EXPECT_NE(encoded(scene.to_batch()), at_image);
    EXPECT_EQ(encoded(image.to_batch()), at_image);
}

TEST(SceneImage, IsReadOnAnotherThreadWhileTheSceneIsEdited) {
    test::RandomEdits edits(8);
    Scene scene = random_scene(edits, 10);
    const std::string at_image = encoded(scene.to_batch());
    SceneImage image = scene.image();
    std::atomic<bool> same{true};
    std::thread reader([&] {
        for (int i = 0; i < 20; ++i) same = same && encoded(image.to_batch()) == at_image;
    });
    for (int i = 0; i < 200; ++i) ASSERT_TRUE(scene.apply(edits.next_batch(8)).has_value());
    reader.join();
    EXPECT_TRUE(same);
}

TEST(SnapshotRestore, LoadsStraightIntoTheSceneWithTheSameSceneAndHitsAsApplyingItsBatch) {
    test::RandomEdits edits(21);
    Scene source = random_scene(edits, 25);
    const std::string bytes = durable::encode_snapshot(source.to_batch(), source.version());
    auto view = durable::open_snapshot(bytes);
    ASSERT_TRUE(view.has_value());
    auto applied = test::make_engine();
    auto loaded = test::make_engine();
    auto decoded = durable::decode_snapshot(bytes);
    ASSERT_TRUE(decoded.has_value());
    ASSERT_TRUE(applied->restore(std::move(decoded->scene), view->version).has_value());
    ASSERT_TRUE(loaded->restore_snapshot(view->payload, view->version).has_value());
    EXPECT_EQ(test::version_of(*loaded), source.version());
    const auto batch_of = [](Engine& e) {
        return e.read([](const Scene& s) { return encoded(s.to_batch()); });
    };
    EXPECT_EQ(batch_of(*loaded), batch_of(*applied));
    EXPECT_EQ(batch_of(*loaded), encoded(source.to_batch()));
    EXPECT_TRUE(test::hits(*loaded) == test::hits(*applied));
}

TEST(SnapshotRestore, ARefusedSnapshotLeavesTheEngineEmptyAndNamesTheEdit) {
    EditBatch b;
    AddInstance orphan;
    orphan.id = "i";
    orphan.mesh = "missing";
    b.edits.emplace_back(AddMaterial{"red", Material{}});
    b.edits.emplace_back(orphan);
    std::string payload;
    durable::encode_batch(b, payload);
    auto engine = test::make_engine();
    const Status s = engine->restore_snapshot(payload, 9);
    ASSERT_FALSE(s.has_value());
    EXPECT_EQ(s.error().edit_index, 1u);
    EXPECT_NE(s.error().message.find("missing"), std::string::npos) << s.error().message;
    EXPECT_EQ(test::version_of(*engine), 0u);
    engine->read([](const Scene& scene) {
        EXPECT_EQ(scene.materials().size(), 0u);
        EXPECT_TRUE(scene.find_material("red").is_null());
    });
    // Undecodable bytes are an InvalidArgument without an edit index (recovery's "damaged").
    const Status bad = engine->restore_snapshot(payload.substr(0, payload.size() - 3), 9);
    ASSERT_FALSE(bad.has_value());
    EXPECT_EQ(bad.error().code, ErrorCode::InvalidArgument);
    EXPECT_EQ(bad.error().edit_index, Error::NO_INDEX);
}

}  // namespace
}  // namespace strata
