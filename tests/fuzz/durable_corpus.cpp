// Writes the seed corpora of journal_record_fuzzer and snapshot_fuzzer with the encoder itself,
// so that the seeds always match the current formats (scripts/run-fuzz.sh runs it before them):
//
//   durable_corpus JOURNAL_DIR SNAPSHOT_DIR
//
// Journal seeds: every edit kind alone as a record payload, a batch of all of them, a segment
// file of several records, and the same segment torn in its last record. Snapshot seeds: the
// snapshot of a small scene (every record type, non-default fields), an empty scene's, the bare
// payload of the first (which the fuzzer wraps in a header), one whose ids break the id rule and
// one of ten thousand clears.

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "engine/durable/journal_format.h"
#include "engine/scene/edit_history.h"
#include "engine/scene/scene.h"
#include "tests/fuzz/durable_fuzz_util.h"

namespace strata {
namespace {

std::vector<Edit> every_kind() {
    std::vector<Edit> edits;
    AddMesh m;
    m.id = "tri";
    m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    m.triangles = {{0, 1, 2}, {1, 3, 2}};
    m.build = {BuildPreference::FastBuild, false, true};
    m.material = "red";
    // Every vertex attribute: the extension layout's and the tagged ones.
    m.normals.assign(4, Vec3(0, 0, 1));
    m.uvs = {{0, 1}, {1, 1}, {0, 0}, {1, 0}};
    m.uvs1 = m.uvs;
    m.tangents.assign(4, Vec4(1, 0, 0, 1));
    edits.emplace_back(AddMaterial{"red", Material{{1, 0, 0}, 0.25f, 0.5f, {0, 0, 0}}});
    edits.emplace_back(std::move(m));
    edits.emplace_back(UpdateMeshPositions{"tri", 1, {{2, 0, 0}}});
    edits.emplace_back(ReplaceMeshTopology{"tri", std::nullopt, {{0, 2, 1}}});
    edits.emplace_back(UpdateMaterial{"red", Vec3(0.5f), std::nullopt, 0.1f, std::nullopt});
    AddInstance i;
    i.id = "a";
    i.mesh = "tri";
    i.transform = Affine::translation({1, 2, 3});
    i.visible = false;
    i.mask = 6;
    i.user_id = 77;
    i.name = "first crate";  // a tagged field
    edits.emplace_back(i);
    UpdateInstance u;
    u.instance = "a";
    u.material = std::optional<std::string>("red");
    u.visible = true;
    u.motion = std::vector<Affine>{Affine::identity(), Affine::translation({1, 0, 0})};
    edits.emplace_back(u);
    AddGroup lod;
    lod.id = "lod";
    lod.lod = true;
    lod.lod_far = 40.0f;
    edits.emplace_back(lod);
    UpdateInstance level;
    level.instance = "a";
    level.parent = std::optional<std::string>("lod");
    level.lod_near = 5.0f;
    level.lod_far = 20.0f;
    level.motion_interpolation = MotionInterpolation::Srt;
    edits.emplace_back(level);
    UpdateInstance animated;
    animated.instance = "a";
    animated.motion = std::vector<Affine>{};
    animated.animation = std::vector<Keyframe>{{0.0f, Affine::identity()},
                                               {1.5f, Affine::translation({0, 2, 0})}};
    animated.animation_loop = true;
    edits.emplace_back(animated);
    edits.emplace_back(SetTime{0.75f, 0.04f});
    edits.emplace_back(SetTransform{"a", Affine::scaling({2, 2, 2})});
    edits.emplace_back(MarkDirty{std::string("tri"), DirtyAction::Refit});
    edits.emplace_back(SetCamera{Vec3(1), std::nullopt, std::nullopt, 30.0f});
    SetCamera shutter;
    shutter.shutter_open = 0.25f;
    shutter.shutter_close = 0.75f;
    edits.emplace_back(shutter);
    edits.emplace_back(SetLighting{std::nullopt, Vec3(2), std::nullopt, 0.5f});
    edits.emplace_back(UpdateMeshVertices{"tri", {3, 0}, {{2, 1, 0}, {0, 0, 1}}});
    edits.emplace_back(ReplaceMeshTriangles{"tri", 0, 1, {{0, 2, 1}, {1, 2, 3}}});
    UpdateMeshPositions attributes{"tri", 2, {}};
    attributes.tangents = std::vector<Vec4>{{0, 1, 0, -1}};
    attributes.uvs1 = std::vector<Vec2>{};
    edits.emplace_back(std::move(attributes));
    AddInstances many;
    many.ids.prefix = "t";
    many.ids.count = 3;
    many.meshes = {"tri"};
    many.transforms.assign(3, Affine::translation({0, 1, 0}));
    edits.emplace_back(many);
    UpdateInstances moved;
    moved.ids.list = {"t0", "t2"};
    moved.transforms = {Affine::scaling({2, 2, 2}), Affine::identity()};
    moved.visible = false;
    edits.emplace_back(moved);
    RemoveInstances removed;
    removed.ids.prefix = "t";
    removed.ids.count = 3;
    edits.emplace_back(removed);
    // Points and curves: the kind rows, radii and strands (tagged fields).
    AddMesh dots;
    dots.id = "dots";
    dots.kind = MeshKind::Points;
    dots.positions = {{0, 0, 0}, {1, 0, 0}};
    dots.radii = {0.5f, 0.25f};
    edits.emplace_back(std::move(dots));
    AddMesh hair;
    hair.id = "hair";
    hair.kind = MeshKind::Curves;
    hair.basis = CurveBasis::CatmullRom;
    hair.style = CurveStyle::Flat;
    hair.positions = {{0, 0, 0}, {0, 1, 0}, {0, 2, 0}, {0, 3, 0}};
    hair.radii.assign(4, 0.1f);
    hair.strands = {4};
    edits.emplace_back(std::move(hair));
    UpdateMeshPositions thinner{"hair", 1, {}};
    thinner.radii = std::vector<float>{0.05f};
    edits.emplace_back(std::move(thinner));
    ReplaceMeshTopology regrown{"hair", std::vector<Vec3>(5, Vec3(1)), {}};
    regrown.radii = std::vector<float>(5, 0.1f);
    regrown.strands = std::vector<uint32_t>{5};
    edits.emplace_back(std::move(regrown));
    // Vertex keys (a tagged attribute): given whole, a range of them, removed.
    AddMesh sheet;
    sheet.id = "sheet";
    sheet.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    sheet.triangles = {{0, 1, 2}};
    sheet.motion_positions = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    edits.emplace_back(std::move(sheet));
    UpdateMeshPositions bent{"sheet", 2, {}};
    bent.motion_positions = std::vector<Vec3>{{0, 1, 2}};
    edits.emplace_back(std::move(bent));
    UpdateMeshPositions still{"sheet", 0, {}};
    still.motion_positions = std::vector<Vec3>{};
    edits.emplace_back(std::move(still));
    edits.emplace_back(RemoveInstance{"a"});
    edits.emplace_back(RemoveMesh{"tri"});
    edits.emplace_back(RemoveMaterial{"red"});
    edits.emplace_back(Clear{});
    return edits;
}

bool write(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out << bytes;
    if (!out.good()) std::fprintf(stderr, "cannot write %s\n", path.c_str());
    return out.good();
}

std::string record(const EditBatch& batch, uint64_t version) {
    durable::PendingRecord r = durable::prepare_record(batch);
    durable::stamp_record(r, version);
    return r.bytes;
}

}  // namespace
}  // namespace strata

int main(int argc, char** argv) {
    using namespace strata;
    if (argc != 3) {
        std::fprintf(stderr, "usage: durable_corpus JOURNAL_DIR SNAPSHOT_DIR\n");
        return 2;
    }
    const std::string journal = argv[1], snapshot = argv[2];
    bool ok = true;

    // Step: journal payloads and segments.
    const std::vector<Edit> kinds = every_kind();
    EditBatch all;
    for (std::size_t k = 0; k < kinds.size(); ++k) {
        EditBatch one;
        one.edits.push_back(kinds[k]);
        ok &= write(journal + "/payload-" + std::to_string(k), fuzz::encoded(one));
        all.edits.push_back(kinds[k]);
    }
    ok &= write(journal + "/payload-all", fuzz::encoded(all));
    EditBatch first, second;
    first.edits.assign(kinds.begin(), kinds.begin() + 6);
    second.edits.push_back(kinds[7]);
    // The history's info on a record (an undo of version 42, with a message).
    second.info = BatchInfo{BatchKind::Undo, 42, 1795000000000, "undo the crate"};
    ok &= write(journal + "/payload-info", fuzz::encoded(second));
    const std::string segment =
        durable::segment_header(41) + record(first, 42) + record(second, 43) + record(all, 44);
    ok &= write(journal + "/segment", segment);
    ok &= write(journal + "/segment-torn", segment.substr(0, segment.size() - 5));
    ok &= write(journal + "/segment-empty", durable::segment_header(0));

    // Step: snapshots of a small scene, built by the scene's own rules.
    Scene scene;
    EditBatch build;
    build.edits.assign(kinds.begin(), kinds.begin() + 11);  // up to set_lighting
    AddInstance b;
    b.id = "b";
    b.mesh = "tri";
    build.edits.emplace_back(b);
    if (!scene.apply(std::move(build))) {
        std::fprintf(stderr, "the seed scene was refused\n");
        return 1;
    }
    const EditBatch state = scene.to_batch();
    ok &= write(snapshot + "/scene.snap", durable::encode_snapshot(state, scene.version()));
    ok &= write(snapshot + "/empty.snap", durable::encode_snapshot(Scene().to_batch(), 0));
    ok &= write(snapshot + "/scene-payload", fuzz::encoded(state));

    // Step: a history file of that scene's making: an entry and an undo step per edit, the last
    // one undone (a redo step), as the engine records them.
    Scene made;
    EditHistory history;
    for (std::size_t k = 0; k < 11; ++k) {
        EditBatch one;
        one.edits.push_back(kinds[k]);
        auto ops = count_ops(one);
        EditBatch inverse;
        auto version = made.apply(std::move(one), nullptr, &inverse);
        if (!version) {
            std::fprintf(stderr, "the seed history's edit %zu was refused\n", k);
            return 1;
        }
        history.record(version.value(), {}, std::move(ops), std::move(inverse));
    }
    if (auto undo = history.undo_batch()) {
        const BatchInfo info = undo->info;
        auto ops = count_ops(*undo);
        EditBatch inverse;
        auto version = made.apply(std::move(*undo), nullptr, &inverse);
        if (version) history.record(version.value(), info, std::move(ops), std::move(inverse));
    }
    ok &= write(snapshot + "/scene.hist", durable::encode_history(history.state(), made.version()));

    // Step: snapshots only the rules can refuse: ids and names that break the text rule, and a
    // payload of many one-byte clears.
    EditBatch bad_ids;
    bad_ids.edits.push_back(kinds[0]);
    AddMesh bad_mesh = std::get<AddMesh>(kinds[1]);
    bad_mesh.id = "m\xff";
    bad_ids.edits.push_back(bad_mesh);
    AddInstance bad_instance = std::get<AddInstance>(kinds[5]);
    bad_instance.id = "i\r\n";
    bad_instance.mesh = "m\xff";
    bad_instance.name = "esc\x1b[2J";
    bad_ids.edits.push_back(bad_instance);
    ok &= write(snapshot + "/bad-ids.snap", durable::encode_snapshot(bad_ids, 3));
    EditBatch clears;
    clears.edits.assign(10000, Clear{});
    ok &= write(snapshot + "/many-clears.snap", durable::encode_snapshot(clears, 1));
    return ok ? 0 : 1;
}
