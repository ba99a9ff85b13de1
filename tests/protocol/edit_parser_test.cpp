// JSON edit ops -> engine edit structs, and where errors point.

#include <cstring>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/scene/shapes.h"
#include "protocol/base64.h"
#include "protocol/edit_ops.h"
#include "protocol/edit_parser.h"
#include "protocol/problem.h"

namespace strata::protocol {
namespace {

ParsedBatch parse_ok(const std::string& text) {
    auto r = parse_edit_batch(text, {});
    EXPECT_TRUE(r.has_value()) << text << ": " << (r.has_value() ? "" : r.error().detail);
    return r.has_value() ? std::move(r.value()) : ParsedBatch{};
}

template <class T>
T one(const std::string& edit) {
    ParsedBatch b = parse_ok("{\"edits\": [" + edit + "]}");
    EXPECT_EQ(b.batch.edits.size(), 1u);
    EXPECT_TRUE(std::holds_alternative<T>(b.batch.edits.at(0))) << edit;
    return std::get<T>(b.batch.edits.at(0));
}

Problem fails(const std::string& edits) {
    auto r = parse_edit_batch("{\"edits\": [" + edits + "]}", {});
    EXPECT_FALSE(r.has_value()) << edits;
    return r.has_value() ? Problem{} : r.error();
}

std::string b64(const void* data, std::size_t n) {
    return encode_base64(std::string_view(static_cast<const char*>(data), n));
}

TEST(EditParser, AddMeshReadsFlatArraysBuildOptionsAndMaterial) {
    const auto e =
        one<AddMesh>(R"({"op": "add_mesh", "id": "tri", "positions": [0,0,0, 1,0,0, 0,1,0],
        "indices": [0,1,2], "build": {"prefer": "fast_build", "allow_refit": false}, "material": "red"})");
    EXPECT_EQ(e.id, "tri");
    EXPECT_THAT(e.positions, ::testing::ElementsAre(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)));
    EXPECT_THAT(e.triangles, ::testing::ElementsAre(Triangle(0, 1, 2)));
    EXPECT_EQ(e.build.prefer, BuildPreference::FastBuild);
    EXPECT_FALSE(e.build.allow_refit);
    EXPECT_FALSE(e.build.compact);
    EXPECT_EQ(e.material, "red");
}

TEST(EditParser, BuildCompactIsABooleanOption) {
    const auto e = one<AddMesh>(R"({"op": "add_mesh", "id": "tri", "positions": [0,0,0, 1,0,0, 0,1,0],
        "indices": [0,1,2], "build": {"compact": true}})");
    EXPECT_TRUE(e.build.compact);
    EXPECT_TRUE(e.build.allow_refit);
    const Problem p = fails(R"({"op": "add_mesh", "id": "tri", "positions": [0,0,0, 1,0,0, 0,1,0],
        "indices": [0,1,2], "build": {"compact": 1}})");
    EXPECT_EQ(p.pointer, "/edits/0/build/compact");
}

TEST(EditParser, AddMeshReadsLittleEndianBase64Arrays) {
    const float p[9] = {0, 0, 0, 1.5f, 0, 0, 0, -2, 0};
    const uint32_t i[3] = {2, 1, 0};
    const auto e =
        one<AddMesh>(R"({"op": "add_mesh", "id": "b", "positions_b64": ")" + b64(p, sizeof p) +
                     R"(", "indices_b64": ")" + b64(i, sizeof i) + "\"}");
    EXPECT_THAT(e.positions,
                ::testing::ElementsAre(Vec3(0, 0, 0), Vec3(1.5f, 0, 0), Vec3(0, -2, 0)));
    EXPECT_THAT(e.triangles, ::testing::ElementsAre(Triangle(2, 1, 0)));
}

TEST(EditParser, LargeArraysArriveWhole) {
    std::string positions, indices;
    for (int v = 0; v < 3000; ++v) positions += (v ? "," : "") + std::to_string(v) + ".25";
    for (int t = 0; t < 999; ++t)
        indices += (t ? "," : "") + std::to_string(t) + "," + std::to_string(t + 1) + ",0";
    const auto e = one<AddMesh>(R"({"op": "add_mesh", "id": "big", "positions": [)" + positions +
                                R"(], "indices": [)" + indices + "]}");
    ASSERT_EQ(e.positions.size(), 1000u);
    EXPECT_EQ(e.positions[999], Vec3(2997.25f, 2998.25f, 2999.25f));
    ASSERT_EQ(e.triangles.size(), 999u);
    EXPECT_EQ(e.triangles[998], Triangle(998, 999, 0));
}

TEST(EditParser, ShapesUseTheEngineGeneratorsWithDefaults) {
    EXPECT_EQ(
        one<AddMesh>(R"({"op":"add_mesh","id":"s","shape":{"type":"sphere"}})").triangles.size(),
        sphere_triangle_count(32));
    EXPECT_EQ(one<AddMesh>(R"({"op":"add_mesh","id":"b","shape":{"type":"box","size":[1,2,3]}})")
                  .positions[7],
              Vec3(0.5f, 1.0f, 1.5f));
    const auto plane = one<AddMesh>(
        R"({"op":"add_mesh","id":"p","shape":{"type":"plane","size":[4,2],"subdivisions":[4,2]}})");
    EXPECT_EQ(plane.positions.size(), 15u);
    EXPECT_EQ(plane.triangles.size(), 16u);
    EXPECT_EQ(plane.positions.back(), Vec3(2.0f, 0.0f, 1.0f));
}

TEST(EditParser, SpheresAreSmoothAndBoxesAndPlanesFlat) {
    const auto sphere = one<AddMesh>(
        R"({"op":"add_mesh","id":"s","shape":{"type":"sphere","radius":2.5,"segments":12}})");
    ASSERT_EQ(sphere.normals.size(), sphere.positions.size());
    for (std::size_t i = 0; i < sphere.positions.size(); ++i) {
        EXPECT_NEAR(glm::length(sphere.normals[i]), 1.0f, 1e-5f);
        EXPECT_NEAR(glm::dot(sphere.normals[i], sphere.positions[i]), 2.5f, 1e-4f);
    }
    EXPECT_TRUE(one<AddMesh>(R"({"op":"add_mesh","id":"b","shape":{"type":"box"}})")
                    .normals.empty());
    EXPECT_TRUE(one<AddMesh>(R"({"op":"add_mesh","id":"p","shape":{"type":"plane"}})")
                    .normals.empty());
    // Normals given beside the shape replace the sphere's.
    const auto given = one<AddMesh>(
        R"({"op":"add_mesh","id":"s","shape":{"type":"sphere","segments":3},"normals":[0,1,0]})");
    EXPECT_EQ(given.normals, std::vector<Vec3>{Vec3(0, 1, 0)});
}

TEST(EditParser, UpdateMeshIsAPositionsUpdateOrATopologyChange) {
    const auto move = one<UpdateMeshPositions>(
        R"({"op":"update_mesh","mesh":"m","positions":[1,2,3],"offset":7})");
    EXPECT_EQ(move.mesh, "m");
    EXPECT_EQ(move.offset, 7u);
    EXPECT_THAT(move.positions, ::testing::ElementsAre(Vec3(1, 2, 3)));
    const auto topo =
        one<ReplaceMeshTopology>(R"({"op":"update_mesh","mesh":"m","indices":[0,2,1]})");
    EXPECT_FALSE(topo.positions.has_value());
    EXPECT_THAT(topo.triangles, ::testing::ElementsAre(Triangle(0, 2, 1)));
    const auto both = one<ReplaceMeshTopology>(
        R"({"op":"update_mesh","mesh":"m","positions":[0,0,0],"indices":[0,0,0]})");
    ASSERT_TRUE(both.positions.has_value());
    EXPECT_EQ(both.positions->size(), 1u);
}

TEST(EditParser, NormalsAndUvsComeFlatOrBase64) {
    const auto e = one<AddMesh>(
        R"({"op":"add_mesh","id":"t","positions":[0,0,0, 1,0,0, 0,1,0],"indices":[0,1,2],
        "normals":[0,0,1, 0,0.5,1, 0,0,2],"uvs":[0,0, 1,0, 0.5,1]})");
    EXPECT_THAT(e.normals, ::testing::ElementsAre(Vec3(0, 0, 1), Vec3(0, 0.5f, 1), Vec3(0, 0, 2)));
    EXPECT_THAT(e.uvs, ::testing::ElementsAre(Vec2(0, 0), Vec2(1, 0), Vec2(0.5f, 1)));

    const float n[6] = {0, 1, 0, 1, 0, 0};
    const float uv[4] = {0.25f, 0.75f, 1, -1};
    const auto u = one<UpdateMeshPositions>(
        R"({"op":"update_mesh","mesh":"t","offset":1,"normals_b64":")" + b64(n, sizeof n) +
        R"(","uvs_b64":")" + b64(uv, sizeof uv) + "\"}");
    EXPECT_TRUE(u.positions.empty());
    EXPECT_EQ(u.offset, 1u);
    ASSERT_TRUE(u.normals.has_value());
    EXPECT_THAT(*u.normals, ::testing::ElementsAre(Vec3(0, 1, 0), Vec3(1, 0, 0)));
    ASSERT_TRUE(u.uvs.has_value());
    EXPECT_THAT(*u.uvs, ::testing::ElementsAre(Vec2(0.25f, 0.75f), Vec2(1, -1)));

    const auto removed =
        one<ReplaceMeshTopology>(R"({"op":"update_mesh","mesh":"t","indices":[0,2,1],"uvs":[]})");
    EXPECT_FALSE(removed.normals.has_value());
    ASSERT_TRUE(removed.uvs.has_value());
    EXPECT_TRUE(removed.uvs->empty());

    EXPECT_EQ(fails(R"({"op":"update_mesh","mesh":"t","uvs":[0,0,1]})").pointer, "/edits/0/uvs");
    EXPECT_EQ(fails(R"({"op":"update_mesh","mesh":"t","uvs_b64":"AAAAAAAA"})").pointer,
              "/edits/0/uvs_b64");
}

TEST(EditParser, TangentsComeFlatOrBase64AsXyzwQuadruples) {
    const auto e = one<AddMesh>(
        R"({"op":"add_mesh","id":"t","positions":[0,0,0, 1,0,0, 0,1,0],"indices":[0,1,2],
        "tangents":[1,0,0,1, 1,0,0,1, 0,1,0,-1]})");
    EXPECT_THAT(e.tangents,
                ::testing::ElementsAre(Vec4(1, 0, 0, 1), Vec4(1, 0, 0, 1), Vec4(0, 1, 0, -1)));

    const float t[8] = {0, 1, 0, 1, 1, 0, 0, -1};
    const auto u = one<UpdateMeshPositions>(
        R"({"op":"update_mesh","mesh":"t","offset":1,"tangents_b64":")" + b64(t, sizeof t) + "\"}");
    ASSERT_TRUE(u.tangents.has_value());
    EXPECT_THAT(*u.tangents, ::testing::ElementsAre(Vec4(0, 1, 0, 1), Vec4(1, 0, 0, -1)));
    const auto topology = one<ReplaceMeshTopology>(
        R"({"op":"update_mesh","mesh":"t","indices":[0,2,1],"tangents":[]})");
    ASSERT_TRUE(topology.tangents.has_value());
    EXPECT_TRUE(topology.tangents->empty());

    EXPECT_EQ(fails(R"({"op":"update_mesh","mesh":"t","tangents":[1,0,0]})").pointer,
              "/edits/0/tangents");
    EXPECT_EQ(fails(R"({"op":"update_mesh","mesh":"t","tangents_b64":"AAAAAAAA"})").pointer,
              "/edits/0/tangents_b64");
    EXPECT_EQ(fails(R"({"op":"update_mesh","mesh":"t","tangents":[1,0,0,1],"tangents_b64":""})")
                  .pointer,
              "/edits/0/tangents_b64");
    EXPECT_EQ(fails(R"({"op":"update_mesh","mesh":"t","vertices":[0],"positions":[0,0,0],
                       "tangents":[1,0,0,1]})")
                  .pointer,
              "/edits/0/tangents");
    // The engine's errors point at the member the client used.
    ParsedBatch b = parse_ok(R"({"edits": [{"op":"update_mesh","mesh":"t","tangents_b64":")" +
                             b64(t, sizeof t) + "\"}]}");
    Error engine_error = make_error(ErrorCode::InvalidArgument, "w", "tangents/3");
    engine_error.edit_index = 0;
    EXPECT_EQ(problem_from_batch_error(engine_error, b.sources).pointer, "/edits/0/tangents_b64");
}

TEST(EditParser, EngineErrorsInNormalsPointAtTheBase64MemberWhenUsed) {
    const float n[3] = {0, 0, 0};
    ParsedBatch b = parse_ok(R"({"edits": [{"op":"update_mesh","mesh":"t","normals_b64":")" +
                             b64(n, sizeof n) + "\"}]}");
    Error e = make_error(ErrorCode::InvalidArgument, "normal of vertex 0 is zero", "normals/0");
    e.edit_index = 0;
    EXPECT_EQ(problem_from_batch_error(e, b.sources).pointer, "/edits/0/normals_b64");
}

TEST(EditParser, InstanceOpsReadEveryField) {
    const auto add = one<AddInstance>(R"({"op":"add_instance","id":"i","mesh":"m","material":"red",
        "transform":{"translate":[1,2,3]},"visible":false,"mask":4294967295,"user_id":9})");
    EXPECT_EQ(add.mesh, "m");
    EXPECT_EQ(add.material, "red");
    EXPECT_EQ(add.transform, Affine::translation({1, 2, 3}));
    EXPECT_FALSE(add.visible);
    EXPECT_EQ(add.mask, 0xFFFFFFFFu);
    EXPECT_EQ(add.user_id, 9u);
    const auto upd =
        one<UpdateInstance>(R"({"op":"update_instance","instance":"i","material":null,"mask":3})");
    ASSERT_TRUE(upd.material.has_value());
    EXPECT_FALSE(upd.material->has_value());
    EXPECT_EQ(upd.mask, 3u);
    EXPECT_FALSE(upd.transform.has_value());
    EXPECT_FALSE(upd.visible.has_value());
    EXPECT_EQ(one<SetTransform>(
                  R"({"op":"set_transform","instance":"i","transform":[1,0,0,4,0,1,0,0,0,0,1,0]})")
                  .transform,
              Affine::translation({4, 0, 0}));
    EXPECT_EQ(one<RemoveInstance>(R"({"op":"remove_instance","instance":"i"})").instance, "i");
}

TEST(EditParser, MaterialCameraLightingAndSceneOps) {
    const auto mat =
        one<AddMaterial>(R"({"op":"add_material","id":"m","base_color":[1,0,0],"metallic":1})");
    EXPECT_EQ(mat.material.base_color, Vec3(1, 0, 0));
    EXPECT_EQ(mat.material.metallic, 1.0f);
    EXPECT_EQ(mat.material.roughness, Material{}.roughness);
    const auto upd =
        one<UpdateMaterial>(R"({"op":"update_material","material":"m","roughness":0.25})");
    EXPECT_EQ(upd.roughness, 0.25f);
    EXPECT_FALSE(upd.base_color.has_value());
    const auto cam = one<SetCamera>(R"({"op":"set_camera","eye":[0,1,2],"fov_y_deg":30})");
    EXPECT_EQ(cam.eye, Vec3(0, 1, 2));
    EXPECT_EQ(cam.fov_y_deg, 30.0f);
    EXPECT_FALSE(cam.target.has_value());
    EXPECT_EQ(one<SetLighting>(R"({"op":"set_lighting","sky_intensity":2})").sky_intensity, 2.0f);
    const auto tlas = one<MarkDirty>(R"({"op":"mark_dirty","target":"tlas","action":"refit"})");
    EXPECT_FALSE(tlas.mesh.has_value());
    EXPECT_EQ(tlas.action, DirtyAction::Refit);
    EXPECT_EQ(
        one<MarkDirty>(R"({"op":"mark_dirty","target":{"mesh":"m"},"action":"rebuild"})").mesh,
        "m");
    one<Clear>(R"({"op":"clear"})");
    one<RemoveMesh>(R"({"op":"remove_mesh","mesh":"m"})");
    // Textures: base64 bytes kept as they are (decoded by the engine), materials bind them.
    EXPECT_EQ(one<AddTexture>(R"({"op":"add_texture","id":"t","data":"iVBORw=="})").data,
              std::string("\x89PNG", 4));
    EXPECT_EQ(one<RemoveTexture>(R"({"op":"remove_texture","texture":"t"})").texture, "t");
    EXPECT_EQ(one<RemoveMaterial>(R"({"op":"remove_material","material":"m"})").material, "m");
    const auto bound = one<AddMaterial>(
        R"({"op":"add_material","id":"m","base_color_texture":"t","sampler":{"wrap":"clamp"}})");
    EXPECT_EQ(bound.textures[0], std::optional<std::string>("t"));
    EXPECT_EQ(bound.material.base_color_sampler.wrap, TextureWrap::Clamp);
    EXPECT_EQ(bound.material.base_color_sampler.filter, TextureFilter::Bilinear);
    const auto unbound = one<UpdateMaterial>(
        R"({"op":"update_material","material":"m","base_color_texture":null,"sampler":{"filter":"nearest"}})");
    ASSERT_TRUE(unbound.textures[0].has_value());
    EXPECT_FALSE(unbound.textures[0]->has_value());
    EXPECT_EQ(unbound.filter, std::optional<TextureFilter>(TextureFilter::Nearest));
    EXPECT_FALSE(unbound.wrap.has_value());
}

TEST(EditParser, EveryOpHasAParserAndAnEngineStruct) {
    std::vector<std::string_view> names;
    for (const EditOp& op : edit_ops()) names.push_back(op.name);
    EXPECT_THAT(names, ::testing::ElementsAre(
                           "add_mesh", "update_mesh", "replace_triangles", "remove_mesh",
                           "add_texture",
                           "remove_texture", "add_material", "update_material",
                           "remove_material", "add_instance",
                           "update_instance", "set_transform", "remove_instance",
                           "add_instances", "update_instances", "remove_instances", "add_group",
                           "update_group", "remove_group", "add_light", "update_light",
                           "remove_light", "mark_dirty", "set_camera", "set_lighting", "set_time",
                           "clear"));
}

TEST(EditParser, ReplaceTrianglesReadsItsRunAndItsNewTrianglesInEitherEncoding) {
    const auto e = one<ReplaceMeshTriangles>(
        R"({"op":"replace_triangles","mesh":"t","first":4,"count":2,"indices":[0,1,2, 2,1,3]})");
    EXPECT_EQ(e.mesh, "t");
    EXPECT_EQ(e.first, 4u);
    EXPECT_EQ(e.count, 2u);
    EXPECT_EQ(e.triangles, (std::vector<Triangle>{{0, 1, 2}, {2, 1, 3}}));
    const uint32_t t[3] = {0, 2, 1};
    const auto b = one<ReplaceMeshTriangles>(
        R"({"op":"replace_triangles","mesh":"t","first":0,"count":0,"indices_b64":")" +
        b64(t, sizeof t) + "\"}");
    EXPECT_EQ(b.triangles, (std::vector<Triangle>{{0, 2, 1}}));
    const auto hole = one<ReplaceMeshTriangles>(
        R"({"op":"replace_triangles","mesh":"t","first":1,"count":3,"indices":[]})");
    EXPECT_TRUE(hole.triangles.empty());

    EXPECT_EQ(fails(R"({"op":"replace_triangles","mesh":"t","first":0,"indices":[]})").pointer,
              "/edits/0/count");
    EXPECT_EQ(fails(R"({"op":"replace_triangles","mesh":"t","first":0,"count":1})").pointer,
              "/edits/0/indices");
    EXPECT_EQ(fails(R"({"op":"replace_triangles","mesh":"t","first":-1,"count":1,"indices":[]})")
                  .pointer,
              "/edits/0/first");
    EXPECT_EQ(fails(R"({"op":"replace_triangles","mesh":"t","first":0,"count":1,"indices":[0,1]})")
                  .pointer,
              "/edits/0/indices");
    EXPECT_EQ(fails(R"({"op":"replace_triangles","mesh":"t","first":0,"count":1,"indices":[],
                       "indices_b64":""})")
                  .pointer,
              "/edits/0/indices_b64");
    EXPECT_EQ(fails(R"({"op":"replace_triangles","mesh":"t","first":0,"count":1,"indices":[],
                       "offset":2})")
                  .pointer,
              "/edits/0/offset");
    // The engine's errors point at the member the client used.
    ParsedBatch parsed = parse_ok(
        R"({"edits": [{"op":"replace_triangles","mesh":"t","first":0,"count":0,"indices_b64":")" +
        b64(t, sizeof t) + "\"}]}");
    Error engine_error = make_error(ErrorCode::OutOfRange, "w", "indices/2");
    engine_error.edit_index = 0;
    EXPECT_EQ(problem_from_batch_error(engine_error, parsed.sources).pointer,
              "/edits/0/indices_b64");
}

TEST(EditParser, BulkInstanceOpsReadEveryFormOfIdsAndTransforms) {
    const auto add = one<AddInstances>(
        R"({"op":"add_instances","ids":{"prefix":"t-","first":7,"count":2},"mesh":"m",)"
        R"("material":["a","b"],"transforms":[1,0,0,1, 0,1,0,2, 0,0,1,3, 2,0,0,0, 0,2,0,0, 0,0,2,0],)"
        R"("parent":"g","visible":false})");
    EXPECT_EQ(add.ids.at(1), "t-8");
    EXPECT_EQ(add.meshes, std::vector<std::string>{"m"});
    EXPECT_EQ(add.materials, (std::vector<std::string>{"a", "b"}));
    ASSERT_EQ(add.transforms.size(), 2u);
    EXPECT_EQ(add.transforms[0].m[7], 2.0f);
    EXPECT_EQ(add.transforms[1].m[5], 2.0f);
    EXPECT_EQ(add.parent, std::optional<std::string>("g"));
    EXPECT_FALSE(add.visible);

    // Base64 of the identity and a translation by x = 2.
    const auto update = one<UpdateInstances>(
        R"({"op":"update_instances","ids":["a","b"],"transforms_b64":")"
        R"(AACAPwAAAAAAAAAAAAAAAAAAAAAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAgD8AAAAAAACAPwAAAAAAAAAAAAAAQAAA)"
        R"(AAAAAIA/AAAAAAAAAAAAAAAAAAAAAAAAgD8AAAAA"})");
    ASSERT_EQ(update.transforms.size(), 2u);
    EXPECT_EQ(update.transforms[1].m[3], 2.0f);
    EXPECT_FALSE(update.visible.has_value());
    const auto objects = one<UpdateInstances>(
        R"({"op":"update_instances","ids":["a"],"transforms":[{"translate":[1,2,3]}],"visible":true})");
    EXPECT_EQ(objects.transforms[0].m[11], 3.0f);
    EXPECT_EQ(objects.visible, std::optional<bool>(true));
    EXPECT_EQ(one<RemoveInstances>(R"({"op":"remove_instances","ids":["x","y"]})").ids.list.size(), 2u);

    // Value errors: 422 with the member's pointer.
    const Problem b64 = fails(R"({"op":"update_instances","ids":["a"],"transforms_b64":"AAAA"})");
    EXPECT_EQ(b64.status, 422);
    EXPECT_EQ(b64.pointer, "/edits/0/transforms_b64");
    const Problem flat = fails(R"({"op":"update_instances","ids":["a"],"transforms":[1,2,3]})");
    EXPECT_EQ(flat.status, 422);
    EXPECT_EQ(flat.pointer, "/edits/0/transforms");
}

TEST(EditParser, NumbersBeyondFloatRangeAreNotFiniteWithTheirPointer) {
    const Problem e =
        fails(R"({"op":"clear"}, {"op":"update_mesh","mesh":"m","positions":[0,1e999,0]})");
    EXPECT_EQ(e.status, 422);
    EXPECT_EQ(e.type, ProblemType::NotFinite);
    EXPECT_EQ(e.edit_index, 1u);
    EXPECT_EQ(e.pointer, "/edits/1/positions/1");
    EXPECT_EQ(fails(R"({"op":"set_camera","fov_y_deg":1e39})").pointer, "/edits/0/fov_y_deg");
}

TEST(EditParser, Base64PositionsWithNaNAreNotFinite) {
    const float p[3] = {0, std::nanf(""), 0};
    const Problem e =
        fails(R"({"op":"update_mesh","mesh":"m","positions_b64":")" + b64(p, sizeof p) + "\"}");
    EXPECT_EQ(e.type, ProblemType::NotFinite);
    EXPECT_EQ(e.pointer, "/edits/0/positions_b64");
}

TEST(EditParser, ASchemaErrorAnywhereWinsOverAnEarlierValueError) {
    const Problem e =
        fails(R"({"op":"update_mesh","mesh":"m","positions":[1e999,0,0]}, {"op":"nope"})");
    EXPECT_EQ(e.type, ProblemType::InvalidRequest);
    EXPECT_EQ(e.pointer, "/edits/1/op");
    EXPECT_EQ(e.edit_index, 1u);
}

TEST(EditParser, UnknownMembersNameTheMemberAndWhatIsAllowed) {
    const Problem e = fails(R"({"op":"set_transform","instance":"i","transfrom":[]})");
    EXPECT_EQ(e.pointer, "/edits/0/transfrom");
    EXPECT_THAT(e.detail, ::testing::HasSubstr("unknown member 'transfrom'"));
    EXPECT_THAT(e.detail, ::testing::HasSubstr("transform"));
}

TEST(EditParser, EngineErrorsPointAtTheWireMemberTheEditUsed) {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    ParsedBatch b =
        parse_ok(R"({"edits": [{"op":"clear"}, {"op":"add_mesh","id":"x","positions_b64":")" +
                 b64(p, sizeof p) + R"(","indices":[0,1,5]}]})");
    Error e = make_error(ErrorCode::OutOfRange, "triangle 0 uses vertex 5", "indices/2");
    e.edit_index = 1;
    Problem problem = problem_from_batch_error(e, b.sources);
    EXPECT_EQ(problem.status, 422);
    EXPECT_EQ(problem.pointer, "/edits/1/indices/2");
    EXPECT_EQ(problem.edit_index, 1u);
    e.field = "positions/3";
    EXPECT_EQ(problem_from_batch_error(e, b.sources).pointer, "/edits/1/positions_b64");
    EXPECT_EQ(problem_type_uri(problem.type), "https://strata.dev/problems/out-of-range");
}

TEST(EditParser, ProblemDocumentsCarryTheRfc9457MembersAndOurs) {
    const Json j = problem_to_json(fails(R"({"op":"add_material","id":"m","roughness":"x"})"));
    EXPECT_EQ(j["type"], "https://strata.dev/problems/invalid-request");
    EXPECT_EQ(j["title"], "Invalid request");
    EXPECT_EQ(j["status"], 400);
    EXPECT_THAT(j["detail"].get<std::string>(),
                ::testing::HasSubstr("expected a number, got string"));
    EXPECT_EQ(j["edit_index"], 0);
    EXPECT_EQ(j["pointer"], "/edits/0/roughness");
}

}  // namespace
}  // namespace strata::protocol
