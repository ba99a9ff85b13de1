// Refused batches leave no trace: a batch whose edit k is invalid applies edits 0..k-1 and then
// undoes them (scene_undo.cpp). A scene that saw any number of refused batches must be exactly
// the scene that never saw them: records, ids, slots and generations (so later additions get
// the same handles), dirty bits and change lists, camera, lighting and version.

#include <limits>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/engine/random_edits.h"
#include "tests/engine/test_util.h"

namespace strata {
namespace {

void put(std::ostream& out, const Vec3& v) {
    out << v.x << ',' << v.y << ',' << v.z << ' ';
}

template <class Tag>
void put(std::ostream& out, Handle<Tag> h) {
    out << h.index << '.' << h.generation << ' ';
}

/// Everything observable about a scene's state, slot by slot, as text (diffs read well).
std::string snapshot(const Scene& s) {
    std::ostringstream out;
    out << "version " << s.version() << "\n";
    const SlotArray<MeshRecord, MeshTag>& meshes = s.meshes();
    for (uint32_t i = 0; i < meshes.slot_count(); ++i) {
        out << "mesh slot " << i << " gen " << meshes.handle_at(i).generation;
        if (!meshes.alive_at(i)) {
            out << " free\n";
            continue;
        }
        const MeshRecord& m = meshes.at_slot(i);
        out << " id " << m.id << " -> ";
        put(out, s.find_mesh(m.id));
        out << "material ";
        put(out, m.material);
        out << "build " << int(m.build.prefer) << m.build.allow_refit << m.build.compact << " dirty "
            << m.dirty.bits.value();
        for (const VertexRanges::Range& r : m.dirty.points.ranges())
            out << " [" << r.begin << ", " << r.end << ")";
        out << " users ";
        for (InstanceHandle u : m.users) put(out, u);
        out << "\n  positions ";
        for (const Vec3& p : m.positions) put(out, p);
        out << "\n  triangles ";
        for (const Triangle& t : m.triangles) out << t.x << ',' << t.y << ',' << t.z << ' ';
        out << "\n";
    }
    const SlotArray<InstanceRecord, InstanceTag>& instances = s.instances();
    for (uint32_t i = 0; i < instances.slot_count(); ++i) {
        out << "instance slot " << i << " gen " << instances.handle_at(i).generation;
        if (!instances.alive_at(i)) {
            out << " free\n";
            continue;
        }
        const InstanceRecord& r = instances.at_slot(i);
        out << " id " << r.id << " -> ";
        put(out, s.find_instance(r.id));
        out << "mesh ";
        put(out, r.mesh);
        out << "material ";
        put(out, r.material);
        for (float v : r.transform.m) out << v << ',';
        out << " visible " << r.visible << " mask " << r.mask << " user " << r.user_id
            << " user_slot " << r.user_slot << " dirty " << r.dirty.value() << "\n";
    }
    const SlotArray<MaterialRecord, MaterialTag>& materials = s.materials();
    for (uint32_t i = 0; i < materials.slot_count(); ++i) {
        out << "material slot " << i << " gen " << materials.handle_at(i).generation;
        if (!materials.alive_at(i)) {
            out << " free\n";
            continue;
        }
        const MaterialRecord& r = materials.at_slot(i);
        out << " id " << r.id << " -> ";
        put(out, s.find_material(r.id));
        put(out, r.material.base_color);
        put(out, r.material.emission);
        out << r.material.roughness << ' ' << r.material.metallic << " dirty " << r.dirty.value()
            << "\n";
    }
    const Camera& c = s.camera();
    out << "camera ";
    put(out, c.eye);
    put(out, c.target);
    put(out, c.up);
    out << c.fov_y_deg << "\nlighting ";
    const Lighting& l = s.lighting();
    put(out, l.sun_direction);
    put(out, l.sun_color);
    put(out, l.sky_color);
    out << l.sky_intensity << "\nchanges bits " << s.changes().scene().value() << " meshes ";
    for (MeshHandle h : s.changes().meshes()) put(out, h);
    out << " instances ";
    for (InstanceHandle h : s.changes().instances()) put(out, h);
    out << " materials ";
    for (MaterialHandle h : s.changes().materials()) put(out, h);
    out << "\n";
    return out.str();
}

/// An edit the scene must refuse, whatever it holds (the ids are never generated).
Edit poison(std::mt19937_64& rng) {
    constexpr float NaN = std::numeric_limits<float>::quiet_NaN();
    switch (std::uniform_int_distribution<int>(0, 4)(rng)) {
        case 0:
            return SetTransform{"no-such-instance", Affine()};
        case 1:
            return RemoveMesh{"no-such-mesh"};
        case 2:
            return test::mesh_edit("poisoned-mesh",
                                   MeshData{{{0, 0, 0}, {1, NaN, 0}, {0, 1, 0}}, {{0, 1, 2}}});
        case 3: {
            SetCamera c;
            c.fov_y_deg = 180.0f;
            return c;
        }
        default: {
            UpdateMaterial m;
            m.material = "no-such-material";
            return m;
        }
    }
}

TEST(Rollback, RefusedBatchesLeaveTheSceneAsIfTheyHadNeverBeenSent) {
    int refused = 0, undone_edits = 0;
    for (uint64_t seq = 0; seq < 60; ++seq) {
        test::RandomEdits edits(seq);
        std::mt19937_64 rng(seq ^ 0x9e3779b97f4a7c15ull);
        Scene seen, unseen;  // `seen` gets every refused batch too
        EditBatch initial = edits.initial_batch(3, 12);
        ASSERT_TRUE(seen.apply(EditBatch(initial)).has_value());
        ASSERT_TRUE(unseen.apply(std::move(initial)).has_value());
        for (int step = 0; step < 25; ++step) {
            const EditBatch batch = edits.next_batch(12);
            // The same batch with an invalid edit at a random position.
            EditBatch poisoned = batch;
            const std::size_t at =
                std::uniform_int_distribution<std::size_t>(0, batch.edits.size())(rng);
            poisoned.edits.insert(poisoned.edits.begin() + std::ptrdiff_t(at), poison(rng));
            auto refused_result = seen.apply(std::move(poisoned));
            ASSERT_FALSE(refused_result.has_value());
            EXPECT_EQ(refused_result.error().edit_index, at);
            ++refused;
            undone_edits += int(at);
            ASSERT_EQ(snapshot(seen), snapshot(unseen))
                << "sequence " << seq << " step " << step << ": refused at edit " << at;

            ASSERT_TRUE(seen.apply(EditBatch(batch)).has_value());
            ASSERT_TRUE(unseen.apply(EditBatch(batch)).has_value());
            ASSERT_EQ(snapshot(seen), snapshot(unseen)) << "sequence " << seq << " step " << step;
            if (step % 3 == 2) {  // what a commit does once it has read the changes
                seen.clear_changes();
                unseen.clear_changes();
            }
        }
    }
    EXPECT_EQ(refused, 60 * 25);
    EXPECT_GT(undone_edits, 60 * 25 * 3) << "most refusals should have had edits to undo";
}

TEST(Rollback, ARefusedClearPutsEveryObjectBackInItsSlot) {
    Scene scene;
    EditBatch b;
    b.edits.emplace_back(AddMaterial{"red", Material{}});
    b.edits.emplace_back(test::mesh_edit("box", make_box(Vec3(1.0f))));
    for (int i = 0; i < 5; ++i)
        b.edits.emplace_back(
            test::instance_edit("box-" + std::to_string(i), "box", {float(i), 0, 0}));
    b.edits.emplace_back(RemoveInstance{"box-2"});
    ASSERT_TRUE(scene.apply(std::move(b)).has_value());
    scene.clear_changes();
    const std::string before = snapshot(scene);

    EditBatch refused;
    refused.edits.emplace_back(Clear{});
    refused.edits.emplace_back(test::mesh_edit("box", make_box(Vec3(2.0f))));
    refused.edits.emplace_back(test::instance_edit("box-0", "box", {0, 1, 0}));
    refused.edits.emplace_back(SetTransform{"box-3", Affine()});  // gone since the clear
    auto result = scene.apply(std::move(refused));
    ASSERT_FALSE(result.has_value());
    EXPECT_EQ(result.error().code, ErrorCode::UnknownId);
    EXPECT_EQ(result.error().edit_index, 3u);
    EXPECT_EQ(snapshot(scene), before);
    EXPECT_TRUE(scene.changes().empty());
}

TEST(Rollback, ARefusedBatchCausesNoCommitWork) {
    auto engine = test::make_engine();
    test::apply_ok(*engine, test::mesh_edit("ball", make_sphere(1.0f, 8)),
                   test::instance_edit("ball-1", "ball", {0, 0, 0}));
    test::commit_ok(*engine);
    EditBatch refused;
    refused.edits.emplace_back(UpdateMeshPositions{"ball", 0, {Vec3(0.0f, 2.0f, 0.0f)}});
    refused.edits.emplace_back(SetTransform{"ball-1", Affine::translation({1, 0, 0})});
    refused.edits.emplace_back(RemoveInstance{"ball-9"});
    ASSERT_FALSE(engine->apply(std::move(refused)).has_value());
    const RebuildReport report = test::commit_ok(*engine);
    EXPECT_TRUE(report.no_accel_work());
    EXPECT_EQ(report.version, 1u);
}

}  // namespace
}  // namespace strata
