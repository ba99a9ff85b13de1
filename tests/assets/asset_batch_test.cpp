// The asset as one engine batch: shared meshes stay shared in the scene (one BLAS, many
// instances), world transforms are composed, the batch is atomic, and what the scene cannot hold
// yet is named.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/engine.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/base64.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

std::unique_ptr<Engine> make_engine() {
    auto e = Engine::create();
    EXPECT_TRUE(e.has_value());
    return std::move(e.value());
}

TEST(AssetBatch, ASharedGltfMeshIsOneSceneMeshWithSeveralInstances) {
    const std::string path = std::string(STRATA_ASSIMP_MODELS_DIR) +
                             "/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb";
    const std::string glb = read_file(path);
    if (glb.empty()) GTEST_SKIP() << path << " missing: install assimp-testmodels";
    auto asset = import_asset(AssetFormat::Glb, bytes_of(glb), "2CylinderEngine.glb", {});
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"engine", true, {}});
    EXPECT_EQ(b.meshes.size(), 34u);
    EXPECT_EQ(b.instances.size(), 115u);
    EXPECT_EQ(b.materials.size(), 34u);
    // The asset's group plus one per node with children (15 of the 82 nodes have some).
    EXPECT_EQ(b.groups.front(), "engine");

    const std::size_t b_groups = b.groups.size();
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    auto report = engine->commit();
    ASSERT_TRUE(report.has_value()) << report.error().describe();
    EXPECT_EQ(report.value().rebuilt.size(), 34u);  // one BLAS per mesh, not per instance
    engine->read([&](const Scene& s) {
        const SceneCounts c = s.counts();
        EXPECT_EQ(c.meshes, 34u);
        EXPECT_EQ(c.instances, 115u);
        std::size_t most = 0;
        s.meshes().for_each(
            [&](auto, const MeshRecord& m) { most = std::max(most, m.users.size()); });
        EXPECT_EQ(most, 20u);
        EXPECT_GT(c.instanced_triangles, c.triangles);
        EXPECT_EQ(c.groups, b_groups);
    });
}

TEST(AssetBatch, TheNodeTreeBecomesGroupsAndInstancesGetTheComposedWorldTransform) {
    const std::string nodes = R"([
      {"children": [1], "translation": [10, 0, 0]},
      {"mesh": 0, "translation": [0, 5, 0], "scale": [3, 3, 3]}])";
    auto asset = import_text(AssetFormat::Gltf, triangle_gltf(nodes));
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"t", true, "holder"});
    ASSERT_EQ(b.groups, (std::vector<std::string>{"t", "t.group0"}));
    ASSERT_EQ(b.instances, std::vector<std::string>{"t.node1"});
    auto engine = make_engine();
    EditBatch holder;
    AddGroup g;
    g.id = "holder";
    g.transform = Affine::translation({0, 0, 100});
    holder.edits.emplace_back(g);
    ASSERT_TRUE(engine->apply(std::move(holder)).has_value());
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    engine->read([](const Scene& s) {
        const InstanceRecord* inst = s.instance(s.find_instance("t.node1")).value();
        EXPECT_EQ(inst->transform.transform_point(Vec3(1, 0, 0)), Vec3(3, 5, 0));  // local
        EXPECT_EQ(inst->world.transform_point(Vec3(1, 0, 0)), Vec3(13, 5, 100));
        EXPECT_EQ(inst->parent, s.find_group("t.group0"));
        const GroupRecord* top = s.group(s.find_group("t")).value();
        EXPECT_EQ(top->parent, s.find_group("holder"));
    });
}

TEST(AssetBatch, ATreeDeeperThanTheScenesGroupsIsFlattenedToWorldTransforms) {
    // A chain of 80 nodes, each moved by 1 along x; the leaf places the mesh.
    std::string nodes = "[";
    for (int i = 0; i < 80; ++i)
        nodes += std::string(i ? ", " : "") + "{\"translation\": [1, 0, 0]" +
                 (i < 79 ? ", \"children\": [" + std::to_string(i + 1) + "]" : ", \"mesh\": 0") +
                 "}";
    nodes += "]";
    auto asset = import_text(AssetFormat::Gltf, triangle_gltf(nodes));
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"deep", true, {}});
    EXPECT_EQ(b.groups, std::vector<std::string>{"deep"});
    EXPECT_THAT(b.warnings, Contains(HasSubstr("flattened")));
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    engine->read([](const Scene& s) {
        const InstanceRecord* inst = s.instance(s.find_instance("deep.node79")).value();
        EXPECT_EQ(inst->world.transform_point(Vec3(0)), Vec3(80, 0, 0));
    });
}

TEST(AssetBatch, ANodeTheSceneCannotPlaceIsLeftOutWithAWarning) {
    auto asset =
        import_text(AssetFormat::Gltf, triangle_gltf(R"([{"mesh": 0, "scale": [0, 0, 0]}])"));
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"z", true, {}});
    EXPECT_TRUE(b.instances.empty());
    EXPECT_EQ(b.meshes.size(), 1u);
    ASSERT_FALSE(b.warnings.empty());
    EXPECT_THAT(b.warnings.back(), HasSubstr("node 0 left out"));
}

TEST(AssetBatch, ZeroNormalsAreDroppedForTheirMeshWithAWarning) {
    auto asset =
        import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n");
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"zn", true, {}});
    EXPECT_THAT(b.warnings, Contains(HasSubstr("normals dropped")));
    auto engine = make_engine();
    ASSERT_TRUE(engine->apply(std::move(b.batch)).has_value());
}

TEST(AssetBatch, APointCloudBecomesAPointsMeshTheSceneHolds) {
    const std::string ply =
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        "property float z\nproperty float radius\nproperty uchar red\nproperty uchar green\n"
        "property uchar blue\nend_header\n0 0 0 0.5 255 0 0\n1 0 0 0.25 0 255 0\n"
        "0 1 0 2 0 0 255\n";
    auto asset = import_text(AssetFormat::Ply, ply);
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"cloud", true, {}});
    const auto& mesh = std::get<AddMesh>(b.batch.edits.at(0));
    EXPECT_EQ(mesh.kind, MeshKind::Points);
    EXPECT_EQ(mesh.radii, (std::vector<float>{0.5f, 0.25f, 2.0f}));
    EXPECT_TRUE(mesh.triangles.empty());
    EXPECT_TRUE(mesh.strands.empty());
    // Vertex colours go as they do for triangle meshes.
    EXPECT_THAT(b.warnings, Contains(HasSubstr("vertex colours dropped")));
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    ASSERT_TRUE(engine->commit().has_value());
    engine->read([](const Scene& s) {
        const MeshRecord* m = s.mesh(s.find_mesh("cloud.mesh0")).value();
        EXPECT_EQ(m->kind, MeshKind::Points);
        EXPECT_EQ(m->radii, (std::vector<float>{0.5f, 0.25f, 2.0f}));
        EXPECT_EQ(s.counts().instances, 1u);
    });
}

TEST(AssetBatch, GltfLinesBecomeALinearRoundCurveMeshWithItsMaterial) {
    // A LINE_STRIP over the four corners of a 3 by 4 rectangle, in a green material.
    const std::vector<float> corners = {0, 0, 0, 3, 0, 0, 3, 4, 0, 0, 4, 0};
    const std::string buffer(reinterpret_cast<const char*>(corners.data()), corners.size() * 4);
    const std::string gltf =
        R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0, 1, 0, 1]}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 3, "material": 0}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"}],
        "bufferViews": [{"buffer": 0, "byteLength": 48}],
        "buffers": [{"byteLength": 48, "uri": "data:application/octet-stream;base64,)" +
        protocol::encode_base64(buffer) + R"("}]})";
    auto asset = import_text(AssetFormat::Gltf, gltf);
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"wire", true, {}});
    const AddMesh* mesh = nullptr;
    for (const Edit& e : b.batch.edits)
        if (const auto* m = std::get_if<AddMesh>(&e)) mesh = m;
    ASSERT_NE(mesh, nullptr);
    EXPECT_EQ(mesh->kind, MeshKind::Curves);
    EXPECT_EQ(mesh->basis, CurveBasis::Linear);
    EXPECT_EQ(mesh->style, CurveStyle::Round);
    EXPECT_EQ(mesh->strands, std::vector<uint32_t>{4});
    EXPECT_EQ(mesh->radii, std::vector<float>(4, 0.01f));  // 0.002 * the diagonal, 5
    EXPECT_EQ(mesh->material, "wire.material0");
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    ASSERT_TRUE(engine->commit().has_value());
    engine->read([](const Scene& s) {
        const MeshRecord* m = s.mesh(s.find_mesh("wire.mesh0")).value();
        EXPECT_EQ(m->kind, MeshKind::Curves);
        EXPECT_EQ(m->strands, std::vector<uint32_t>{4});
        EXPECT_EQ(m->primitive_count(), 3u);
    });
}

TEST(AssetBatch, WithoutInstancingOnlyMeshesMaterialsAndTheEmptyAssetGroupAreCreated) {
    auto asset = import_text(AssetFormat::Gltf, triangle_gltf(R"([{"mesh": 0}])"));
    ASSERT_TRUE(asset.has_value());
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"m", false, {}, "m.gltf"});
    EXPECT_EQ(b.meshes, std::vector<std::string>{"m.mesh0"});
    EXPECT_TRUE(b.instances.empty());
    EXPECT_EQ(b.groups, std::vector<std::string>{"m"});
    ASSERT_EQ(b.batch.edits.size(), 2u);
    ASSERT_EQ(b.root_edit, 1u);
    EXPECT_EQ(std::get<AddGroup>(b.batch.edits[1]).asset, "m.gltf");
}

TEST(AssetBatch, ImportingTwiceUnderOnePrefixIsRefusedAndChangesNothing) {
    auto engine = make_engine();
    for (int round = 0; round < 2; ++round) {
        auto asset = import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        ASSERT_TRUE(asset.has_value());
        AssetBatch b = asset_to_batch(std::move(asset.value()), {"dup", true, {}});
        auto applied = engine->apply(std::move(b.batch));
        if (round == 0) {
            ASSERT_TRUE(applied.has_value());
            continue;
        }
        ASSERT_FALSE(applied.has_value());
        EXPECT_EQ(applied.error().code, ErrorCode::DuplicateId);
        engine->read([](const Scene& s) {
            EXPECT_EQ(s.version(), 1u);
            EXPECT_EQ(s.counts().meshes, 1u);
            EXPECT_EQ(s.counts().instances, 1u);
        });
    }
}

TEST(AssetBatch, NormalsUvsAndTheEmbeddedTextureReachTheScene) {
    const std::string glb = read_file(std::string(STRATA_ASSIMP_MODELS_DIR) +
                                      "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    if (glb.empty()) GTEST_SKIP() << "assimp-testmodels missing";
    auto asset = import_asset(AssetFormat::Glb, bytes_of(glb), "box.glb", {});
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"box", true, {}});
    EXPECT_EQ(b.textures, std::vector<std::string>{"box.texture0"});
    // Normals, uvs and the texture reach the scene; the material names the texture.
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    engine->read([](const Scene& s) {
        const MeshRecord* m = s.mesh(s.find_mesh("box.mesh0")).value();
        EXPECT_EQ(m->normals.size(), m->positions.size());
        EXPECT_EQ(m->uvs.size(), m->positions.size());
        const TextureRecord* t = s.texture(s.find_texture("box.texture0")).value();
        EXPECT_EQ(t->image->width, 211u);  // CesiumLogoFlat.png, a palette PNG
        const MaterialRecord* mat = s.material(m->material).value();
        EXPECT_EQ(mat->textures[0], s.find_texture("box.texture0"));
    });
}

TEST(AssetBatch, TexturesWithoutBytesOrInAnotherFormatAreLeftOutWithAWarning) {
    Asset asset;
    asset.textures.push_back(AssetTexture{"logo", "image/png", {}, "logo.png"});
    asset.textures.push_back(AssetTexture{"web", "image/webp", {'R', 'I', 'F', 'F'}, ""});
    asset.materials.push_back(AssetMaterial{"a", Material{}, 0});
    asset.materials.push_back(AssetMaterial{"b", Material{}, 1});
    AssetBatch b = asset_to_batch(std::move(asset), {"t", false, {}});
    EXPECT_TRUE(b.textures.empty());
    EXPECT_THAT(b.warnings, Contains(HasSubstr("not part of the upload ('logo.png')")));
    EXPECT_THAT(b.warnings,
                Contains(HasSubstr("only PNG and JPEG images are decoded (it is image/webp)")));
    auto engine = make_engine();
    ASSERT_TRUE(engine->apply(std::move(b.batch)).has_value());
    engine->read([](const Scene& s) {
        const MaterialRecord* m = s.material(s.find_material("t.material0")).value();
        EXPECT_TRUE(m->textures[0].is_null());
    });
}

TEST(AssetBatch, ADamagedEmbeddedImageRefusesTheWholeImportNamingTheTexture) {
    Asset asset;
    const std::string png = "\x89PNG\r\n\x1a\n-not-really";
    asset.textures.push_back(AssetTexture{"logo", "image/png", {png.begin(), png.end()}, ""});
    asset.materials.push_back(AssetMaterial{"a", Material{}, 0});
    AssetBatch b = asset_to_batch(std::move(asset), {"t", false, {}});
    ASSERT_EQ(b.textures.size(), 1u);
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_FALSE(applied.has_value());
    EXPECT_THAT(applied.error().message, HasSubstr("texture 't.texture0': corrupt PNG"));
    EXPECT_EQ(engine->read([](const Scene& s) { return s.materials().size(); }), 0u);
}

}  // namespace
}  // namespace strata::assets::test

namespace strata::assets::test {
namespace {

TEST(AssetBatch, NamesFromTheFileBecomeDisplayNamesTheSceneAccepts) {
    Asset a;
    AssetMesh mesh;
    mesh.name = "Wheel\x01mesh";  // a control character
    mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    mesh.triangles = {{0, 1, 2}};
    mesh.material = 0;
    a.meshes.push_back(mesh);
    AssetMaterial material;
    material.name = "Paint \xff\xfe";  // not UTF-8
    a.materials.push_back(material);
    AssetNode root;
    root.name = "Car";
    AssetNode leaf;
    leaf.name = std::string(3000, 'x');  // longer than a display name may be
    leaf.parent = 0;
    leaf.meshes = {0};
    a.nodes = {root, leaf};
    AssetBatch b = asset_to_batch(std::move(a), {"car", true, {}});
    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    engine->read([&](const Scene& s) {
        EXPECT_EQ(s.mesh(s.find_mesh("car.mesh0")).value()->name, "Wheel mesh");
        EXPECT_EQ(s.material(s.find_material("car.material0")).value()->material.name,
                  "Paint \xEF\xBF\xBD\xEF\xBF\xBD");
        EXPECT_EQ(s.group(s.find_group("car.group0")).value()->name, "Car");
        const std::string& leaf_name = s.instance(s.find_instance("car.node1")).value()->rare->name;
        EXPECT_EQ(leaf_name, std::string(MAX_NAME_BYTES, 'x'));
    });
}

}  // namespace
}  // namespace strata::assets::test
