// A table of invalid edits: each is rejected with its specific error (code, edit index, field),
// and the scene's version and contents are unchanged.

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "tests/engine/test_util.h"

namespace strata {
namespace {

using test::apply_ok;
using test::instance_edit;
using test::mesh_edit;

constexpr float NaN = std::numeric_limits<float>::quiet_NaN();
constexpr float INF = std::numeric_limits<float>::infinity();

struct InvalidCase {
    const char* name;
    std::vector<Edit> edits;  ///< the invalid edit is the last one
    ErrorCode code;
    const char* field;  ///< expected Error::field ("" when none)
};

AddMesh tiny_mesh(const std::string& id) {
    return mesh_edit(id, make_box(Vec3(1.0f)));
}

UpdateMeshPositions positions(const std::string& mesh, uint32_t offset, std::vector<Vec3> p) {
    return UpdateMeshPositions{mesh, offset, std::move(p)};
}

Affine with(float a00, float a11, float a22) {
    Affine t;
    t.m[0] = a00;
    t.m[5] = a11;
    t.m[10] = a22;
    return t;
}

std::vector<InvalidCase> invalid_cases() {
    AddMesh nan_mesh = tiny_mesh("bad");
    nan_mesh.positions[3].y = NaN;
    AddMesh inf_mesh = tiny_mesh("bad");
    inf_mesh.positions[0].x = INF;
    AddMesh index_out = tiny_mesh("bad");
    index_out.triangles[5].z = 8;
    AddMesh no_triangles = tiny_mesh("bad");
    no_triangles.triangles.clear();
    AddMesh no_vertices;
    no_vertices.id = "bad";
    AddMesh no_id = tiny_mesh("");
    AddMesh unknown_material = tiny_mesh("bad");
    unknown_material.material = "nope";

    AddInstance unknown_mesh = instance_edit("i9", "nope");
    AddInstance duplicate_instance = instance_edit("i0", "box");
    AddInstance singular = instance_edit("i9", "box");
    singular.transform = with(1, 0, 1);
    AddInstance flat = instance_edit("i9", "box");
    flat.transform = with(1, 1, 1e-9f);
    AddInstance nan_transform = instance_edit("i9", "box");
    nan_transform.transform.m[3] = NaN;
    AddInstance bad_material = instance_edit("i9", "box");
    bad_material.material = "nope";

    UpdateInstance update_unknown;
    update_unknown.instance = "nope";
    update_unknown.visible = false;
    UpdateInstance update_singular;
    update_singular.instance = "i0";
    update_singular.transform = with(0, 0, 0);

    ReplaceMeshTopology topo_out;
    topo_out.mesh = "box";
    topo_out.triangles = {{0, 1, 99}};
    ReplaceMeshTopology topo_empty;
    topo_empty.mesh = "box";
    ReplaceMeshTopology topo_shrunk;  // fewer vertices than the old triangles need
    topo_shrunk.mesh = "box";
    topo_shrunk.positions = std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    topo_shrunk.triangles = {{0, 1, 2}, {0, 2, 3}};

    UpdateMaterial mat_range;
    mat_range.material = "paint";
    mat_range.roughness = 1.5f;
    UpdateMaterial mat_nan;
    mat_nan.material = "paint";
    mat_nan.emission = Vec3(0, NaN, 0);
    UpdateMaterial mat_unknown;
    mat_unknown.material = "nope";
    Material negative;
    negative.base_color = Vec3(-0.1f, 0.5f, 0.5f);

    SetCamera cam_nan;
    cam_nan.eye = Vec3(NaN, 0, 0);
    SetCamera cam_fov;
    cam_fov.fov_y_deg = 180.0f;
    SetCamera cam_same;
    cam_same.eye = Vec3(0.0f);
    cam_same.target = Vec3(0.0f);
    SetCamera cam_up;
    cam_up.eye = Vec3(0, 5, 0);
    cam_up.target = Vec3(0, 0, 0);
    cam_up.up = Vec3(0, 1, 0);
    SetLighting light_dir;
    light_dir.sun_direction = Vec3(0.0f);
    SetLighting light_inf;
    light_inf.sky_intensity = INF;
    SetLighting light_negative;
    light_negative.sun_color = Vec3(1, -1, 1);

    return {
        {"MeshWithNaNPosition", {nan_mesh}, ErrorCode::NotFinite, "positions/10"},
        {"MeshWithInfinitePosition", {inf_mesh}, ErrorCode::NotFinite, "positions/0"},
        {"TriangleIndexOutOfRange", {index_out}, ErrorCode::OutOfRange, "indices/17"},
        {"MeshWithoutTriangles", {no_triangles}, ErrorCode::EmptyMesh, "indices"},
        {"MeshWithoutVertices", {no_vertices}, ErrorCode::EmptyMesh, "positions"},
        {"MeshWithEmptyId", {no_id}, ErrorCode::InvalidArgument, "id"},
        {"DuplicateMeshId", {tiny_mesh("box")}, ErrorCode::DuplicateId, "id"},
        {"DuplicateMeshIdWithinBatch",
         {tiny_mesh("m2"), tiny_mesh("m2")},
         ErrorCode::DuplicateId,
         "id"},
        {"MeshWithUnknownMaterial", {unknown_material}, ErrorCode::UnknownId, "material"},
        {"UpdateUnknownMesh", {positions("nope", 0, {{0, 0, 0}})}, ErrorCode::UnknownId, "mesh"},
        {"UpdateRangePastTheEnd",
         {positions("box", 7, {{0, 0, 0}, {1, 1, 1}})},
         ErrorCode::OutOfRange,
         "offset"},
        {"UpdateMoreVerticesThanTheMeshHas",
         {positions("box", 0, std::vector<Vec3>(9))},
         ErrorCode::OutOfRange,
         "positions"},
        {"UpdateWithNaN",
         {positions("box", 2, {{0, NaN, 0}})},
         ErrorCode::NotFinite,
         "positions/1"},
        {"UpdateWithNothing", {positions("box", 0, {})}, ErrorCode::InvalidArgument, "positions"},
        {"TopologyIndexOutOfRange", {topo_out}, ErrorCode::OutOfRange, "indices/2"},
        {"TopologyWithoutTriangles", {topo_empty}, ErrorCode::EmptyMesh, "indices"},
        {"TopologyWithTooFewNewVertices", {topo_shrunk}, ErrorCode::OutOfRange, "indices/5"},
        {"RemoveUnknownMesh", {RemoveMesh{"nope"}}, ErrorCode::UnknownId, "mesh"},
        {"RemoveMeshStillInstanced", {RemoveMesh{"box"}}, ErrorCode::InUse, "mesh"},
        {"RemoveMeshAfterAddingAnInstanceInTheBatch",
         {RemoveInstance{"i0"}, instance_edit("i5", "box"), RemoveMesh{"box"}},
         ErrorCode::InUse,
         "mesh"},
        {"InstanceOfUnknownMesh", {unknown_mesh}, ErrorCode::UnknownId, "mesh"},
        {"InstanceOfMeshRemovedEarlierInBatch",
         {RemoveInstance{"i0"}, RemoveMesh{"box"}, instance_edit("i9", "box")},
         ErrorCode::UnknownId,
         "mesh"},
        {"DuplicateInstanceId", {duplicate_instance}, ErrorCode::DuplicateId, "id"},
        {"SingularTransform", {singular}, ErrorCode::DegenerateTransform, "transform"},
        {"FlattenedTransform", {flat}, ErrorCode::DegenerateTransform, "transform"},
        {"NaNTransform", {nan_transform}, ErrorCode::NotFinite, "transform"},
        {"InstanceWithUnknownMaterial", {bad_material}, ErrorCode::UnknownId, "material"},
        {"UpdateUnknownInstance", {update_unknown}, ErrorCode::UnknownId, "instance"},
        {"UpdateInstanceToSingular",
         {update_singular},
         ErrorCode::DegenerateTransform,
         "transform"},
        {"SetTransformOfUnknownInstance",
         {SetTransform{"nope", Affine::identity()}},
         ErrorCode::UnknownId,
         "instance"},
        {"SetTransformOfRemovedInstance",
         {RemoveInstance{"i0"}, SetTransform{"i0", Affine::identity()}},
         ErrorCode::UnknownId,
         "instance"},
        {"RemoveUnknownInstance", {RemoveInstance{"nope"}}, ErrorCode::UnknownId, "instance"},
        {"DuplicateMaterial", {AddMaterial{"paint", {}}}, ErrorCode::DuplicateId, "id"},
        {"MaterialWithNegativeColor",
         {AddMaterial{"neg", negative}},
         ErrorCode::InvalidArgument,
         "base_color"},
        {"MaterialRoughnessOutOfRange", {mat_range}, ErrorCode::InvalidArgument, "roughness"},
        {"MaterialEmissionNaN", {mat_nan}, ErrorCode::NotFinite, "emission"},
        {"UpdateUnknownMaterial", {mat_unknown}, ErrorCode::UnknownId, "material"},
        {"MarkDirtyUnknownMesh",
         {MarkDirty{std::string("nope"), DirtyAction::Refit}},
         ErrorCode::UnknownId,
         "target/mesh"},
        {"CameraWithNaN", {cam_nan}, ErrorCode::NotFinite, "eye"},
        {"CameraFovOutOfRange", {cam_fov}, ErrorCode::InvalidArgument, "fov_y_deg"},
        {"CameraEyeOnTarget", {cam_same}, ErrorCode::InvalidArgument, "target"},
        {"CameraUpAlongView", {cam_up}, ErrorCode::InvalidArgument, "up"},
        {"SunDirectionZero", {light_dir}, ErrorCode::InvalidArgument, "sun_direction"},
        {"SkyIntensityInfinite", {light_inf}, ErrorCode::NotFinite, "sky_intensity"},
        {"SunColorNegative", {light_negative}, ErrorCode::InvalidArgument, "sun_color"},
        {"AnythingAfterClearIsGone",
         {Clear{}, SetTransform{"i0", Affine::identity()}},
         ErrorCode::UnknownId,
         "instance"},
    };
}

class InvalidEdit : public ::testing::TestWithParam<InvalidCase> {};

TEST_P(InvalidEdit, IsRejectedWithItsErrorAndChangesNothing) {
    auto engine = test::make_engine();
    apply_ok(*engine, tiny_mesh("box"), AddMaterial{"paint", {}}, instance_edit("i0", "box"));
    test::commit_ok(*engine);
    const uint64_t version = engine->read([](const Scene& s) { return s.version(); });
    const EditBatch before = engine->read([](const Scene& s) { return s.to_batch(); });

    // Valid edits go first so the test also shows they are not applied.
    EditBatch batch;
    batch.edits.emplace_back(SetTransform{"i0", Affine::translation({5, 5, 5})});
    batch.edits.emplace_back(tiny_mesh("extra"));
    for (const Edit& e : GetParam().edits) batch.edits.push_back(e);
    const std::size_t bad_index = batch.edits.size() - 1;

    auto r = engine->apply(std::move(batch));
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().code, GetParam().code) << r.error().describe();
    EXPECT_EQ(r.error().edit_index, bad_index) << r.error().describe();
    EXPECT_EQ(r.error().field, GetParam().field) << r.error().describe();
    EXPECT_FALSE(r.error().message.empty());

    const auto [version_after, unchanged_tracker, no_extra, after] =
        engine->read([](const Scene& s) {
            return std::tuple(s.version(), s.changes().empty(), s.find_mesh("extra").is_null(),
                              s.to_batch());
        });
    EXPECT_EQ(version_after, version);
    EXPECT_TRUE(unchanged_tracker);
    EXPECT_TRUE(no_extra);
    ASSERT_EQ(after.edits.size(), before.edits.size());
    EXPECT_EQ(std::get<AddInstance>(after.edits[2]).transform, Affine::identity());
    EXPECT_TRUE(test::commit_ok(*engine).no_accel_work());
}

INSTANTIATE_TEST_SUITE_P(Table, InvalidEdit, ::testing::ValuesIn(invalid_cases()),
                         [](const auto& p) { return std::string(p.param.name); });

TEST(Validation, EditsSeeEarlierEditsOfTheSameBatch) {
    auto engine = test::make_engine();
    // Create, use, remove and re-create ids inside one batch.
    MeshData big = make_box(Vec3(2.0f));
    ReplaceMeshTopology grow;
    grow.mesh = "m";
    grow.positions = make_plane(Vec3(1.0f), 4, 4).positions;  // 25 vertices
    grow.triangles = make_plane(Vec3(1.0f), 4, 4).triangles;
    const uint64_t v =
        apply_ok(*engine, AddMaterial{"red", {}}, tiny_mesh("m"), instance_edit("a", "m"),
                 RemoveInstance{"a"}, RemoveMesh{"m"}, mesh_edit("m", big), instance_edit("a", "m"),
                 grow, positions("m", 20, std::vector<Vec3>(5, Vec3(0.5f))));
    EXPECT_EQ(v, 1u);
    engine->read([](const Scene& s) {
        EXPECT_EQ(s.meshes().size(), 1u);
        EXPECT_EQ(s.mesh(s.find_mesh("m")).value()->positions.size(), 25u);
        EXPECT_EQ(s.instances().size(), 1u);
        return 0;
    });
}

TEST(Validation, EachAppliedBatchIncrementsTheVersionByOne) {
    auto engine = test::make_engine();
    EXPECT_EQ(apply_ok(*engine, tiny_mesh("a"), tiny_mesh("b")), 1u);
    EXPECT_EQ(apply_ok(*engine, SetCamera{}), 2u);
    EXPECT_FALSE(engine->apply(EditBatch{{RemoveMesh{"zz"}}}).has_value());
    EXPECT_EQ(apply_ok(*engine, Clear{}), 3u);
    test::commit_ok(*engine);
    EXPECT_EQ(engine->read([](const Scene& s) { return s.version(); }), 3u);
}

TEST(Handles, AStaleHandleIsRefused) {
    auto engine = test::make_engine();
    apply_ok(*engine, tiny_mesh("m"), instance_edit("a", "m"));
    // Plain variables, not a structured binding: clang 14 (the sanitizer build) refuses to
    // capture bindings in the lambda below.
    const auto handles = engine->read(
        [](const Scene& s) { return std::pair(s.find_mesh("m"), s.find_instance("a")); });
    const MeshHandle mesh = handles.first;
    const InstanceHandle inst = handles.second;
    apply_ok(*engine, RemoveInstance{"a"}, instance_edit("b", "m"));
    engine->read([&](const Scene& s) {
        const InstanceHandle b = s.find_instance("b");
        EXPECT_EQ(b.index, inst.index) << "the slot is reused";
        EXPECT_NE(b.generation, inst.generation);
        auto stale = s.instance(inst);
        EXPECT_FALSE(stale.has_value());
        EXPECT_EQ(stale.error().code, ErrorCode::StaleHandle);
        EXPECT_TRUE(s.instance(b).has_value());
        EXPECT_TRUE(s.mesh(mesh).has_value());
        EXPECT_FALSE(s.mesh(MeshHandle{}).has_value());
        EXPECT_FALSE(s.mesh(MeshHandle{mesh.index, mesh.generation + 1}).has_value());
        return 0;
    });
}

TEST(Handles, SlotArrayRefusesErasedAndForeignHandles) {
    SlotArray<int, MeshTag> slots;
    const MeshHandle a = slots.insert(1);
    const MeshHandle b = slots.insert(2);
    EXPECT_TRUE(slots.erase(a));
    EXPECT_FALSE(slots.erase(a));
    EXPECT_EQ(slots.get(a), nullptr);
    const MeshHandle c = slots.insert(3);
    EXPECT_EQ(c.index, a.index);
    EXPECT_EQ(slots.get(a), nullptr);
    EXPECT_EQ(*slots.get(c), 3);
    EXPECT_EQ(*slots.get(b), 2);
    EXPECT_EQ(slots.get(MeshHandle{99, 0}), nullptr);
    EXPECT_EQ(slots.size(), 2u);
}

}  // namespace
}  // namespace strata
