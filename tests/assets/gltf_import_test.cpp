// The glTF importer: a real multi-node model whose meshes are shared, node transforms (TRS and
// matrices, composed down the tree), and refusals: other primitive modes, external files, bad
// indices, cycles.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "engine/image/png.h"
#include "protocol/base64.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::HasSubstr;

const std::string MODELS = STRATA_ASSIMP_MODELS_DIR;

/// Skips the test without Debian's assimp-testmodels.
#define REQUIRE_TESTMODELS()                                                          \
    if (read_file(MODELS + "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb").empty()) \
    GTEST_SKIP() << MODELS << " missing: install assimp-testmodels"

Imported<Asset> import_path(const std::string& relative) {
    const std::string text = read_file(MODELS + "/" + relative);
    if (text.empty()) return ErrorSink(relative).invalid("", "cannot read");
    const auto format = relative.ends_with(".glb") ? AssetFormat::Glb : AssetFormat::Gltf;
    return import_asset(format, bytes_of(text), relative, {});
}

TEST(GltfImport, TwoCylinderEngineSharesEachMeshBetweenTheNodesThatUseIt) {
    REQUIRE_TESTMODELS();
    auto a = import_path("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const Asset& asset = a.value();
    // Counted independently from the file's JSON: 82 nodes reachable from the scene, 67 of them
    // with a mesh, 29 distinct meshes of 34 primitives in all, 34 materials.
    EXPECT_EQ(asset.nodes.size(), 82u);
    EXPECT_EQ(asset.meshes.size(), 34u);
    EXPECT_EQ(asset.materials.size(), 34u);
    std::size_t placements = 0;
    std::map<int, int> users;
    for (const AssetNode& n : asset.nodes) {
        placements += n.meshes.size();
        for (int m : n.meshes) ++users[m];
    }
    EXPECT_EQ(placements, 115u);
    int most = 0;
    for (const auto& [mesh, count] : users) most = std::max(most, count);
    EXPECT_EQ(most, 20);  // glTF mesh 6 is placed by 20 nodes
}

TEST(GltfImport, NodeTransformsAreReadAsTrsOrColumnMajorMatrices) {
    const std::string nodes = R"([
      {"children": [1], "translation": [1, 2, 3], "scale": [2, 2, 2]},
      {"mesh": 0, "rotation": [0, 0, 0.7071068, 0.7071068]},
      {"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 5,6,7,1]}])";
    auto a = import_text(AssetFormat::Gltf, triangle_gltf(nodes, "", R"([{"nodes": [0, 2]}])"));
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const Asset& asset = a.value();
    ASSERT_EQ(asset.meshes.size(), 1u);  // one glTF mesh, used twice
    ASSERT_EQ(asset.nodes.size(), 3u);
    EXPECT_EQ(asset.nodes[1].parent, 0);
    const Vec3 p =
        asset.nodes[0].local.transform_point(asset.nodes[1].local.transform_point(Vec3(1, 0, 0)));
    EXPECT_NEAR(p.x, 1.0f, 1e-5f);  // rotated 90 degrees about z, scaled by 2, moved
    EXPECT_NEAR(p.y, 4.0f, 1e-5f);
    EXPECT_NEAR(p.z, 3.0f, 1e-5f);
    EXPECT_EQ(asset.nodes[2].local.transform_point(Vec3(0)), Vec3(5, 6, 7));
    EXPECT_EQ(asset.nodes[2].meshes, std::vector<int>{0});
}

TEST(GltfImport, ModesOtherThanTrianglesAreRefusedNamingThePrimitive) {
    auto a = import_text(AssetFormat::Gltf, triangle_gltf(R"([{"mesh": 0}])", R"(, "mode": 1)"));
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(a.error().element, "meshes[0].primitives[0]");
    EXPECT_THAT(a.error().detail, HasSubstr("LINES"));
}

TEST(GltfImport, RequiredExtensionsAreRefusedByNameBeforeTheFileIsRead) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    doc["extensionsUsed"] = {"EXT_meshopt_compression", "KHR_mesh_quantization"};
    doc["extensionsRequired"] = {"EXT_meshopt_compression", "KHR_mesh_quantization"};
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(a.error().element, "extensionsRequired");
    EXPECT_THAT(a.error().detail,
                HasSubstr("requires EXT_meshopt_compression, KHR_mesh_quantization, which Strata "
                          "does not import"));
    // Only used, not required: imported.
    doc.erase("extensionsRequired");
    EXPECT_TRUE(import_text(AssetFormat::Gltf, doc.dump()).has_value());
}

TEST(GltfImport, ThousandsOfUnreadFeaturesGiveABoundedListOfWarnings) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    for (int i = 0; i < 200; ++i) doc["materials"].push_back({{"alphaMode", "BLEND"}});
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const std::vector<std::string>& w = a.value().warnings;
    ASSERT_EQ(w.size(), 65u);
    EXPECT_EQ(w[0], "materials[0].alphaMode BLEND not imported: the surface is opaque");
    EXPECT_EQ(w.back(), "136 more warnings not listed");
}

TEST(GltfImport, GltfOneAndDracoCompressionAreRefusedSayingSo) {
    REQUIRE_TESTMODELS();
    auto one = import_path("glTF/TwoBoxes/TwoBoxes.gltf");
    ASSERT_FALSE(one.has_value());
    EXPECT_EQ(one.error().element, "asset.version");
    EXPECT_THAT(one.error().detail, HasSubstr("glTF 1.0 is not supported; only glTF 2.0"));
    // Its buffer is an external file, so the version must be what is refused first.
    auto draco = import_path("glTF2/draco/2CylinderEngine.gltf");
    ASSERT_FALSE(draco.has_value());
    EXPECT_EQ(draco.error().element, "extensionsRequired");
    EXPECT_THAT(draco.error().detail, HasSubstr("requires KHR_draco_mesh_compression"));
}

TEST(GltfImport, AnExternalBufferIsRefusedAndNeverRead) {
    REQUIRE_TESTMODELS();
    auto a = import_path("glTF2/BoxTextured-glTF/BoxTextured.gltf");
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::InvalidAsset);
    EXPECT_THAT(a.error().detail, HasSubstr("external file"));
    // Even a path that exists on this machine is not read.
    std::string doc = triangle_gltf(R"([{"mesh": 0}])");
    doc.replace(doc.find("data:"), doc.find('"', doc.find("data:")) - doc.find("data:"),
                "/etc/hostname");
    auto b = import_text(AssetFormat::Gltf, doc);
    ASSERT_FALSE(b.has_value());
    EXPECT_THAT(b.error().detail, HasSubstr("refused"));
}

TEST(GltfImport, EmbeddedAndBinaryBoxesImportWithTheirTexture) {
    REQUIRE_TESTMODELS();
    for (const char* path : {"glTF2/BoxTextured-glTF-Embedded/BoxTextured.gltf",
                             "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"}) {
        auto a = import_path(path);
        ASSERT_TRUE(a.has_value()) << a.error().detail;
        ASSERT_EQ(a.value().meshes.size(), 1u) << path;
        EXPECT_EQ(a.value().meshes[0].triangles.size(), 12u) << path;
        ASSERT_EQ(a.value().textures.size(), 1u) << path;
        EXPECT_FALSE(a.value().textures[0].bytes.empty()) << path;
        EXPECT_EQ(a.value().materials[0].base_color_texture, 0) << path;
        EXPECT_EQ(a.value().meshes[0].uvs.size(), a.value().meshes[0].positions.size()) << path;
    }
}

TEST(GltfImport, ImagesThatShareABufferViewShareOneTexture) {
    // Fifty images naming one buffer view used to hold fifty copies of its bytes.
    const uint8_t rgb[] = {200, 100, 50};
    const std::string png = encode_png(rgb, 1, 1, 3).value();
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    doc["buffers"].push_back(
        {{"byteLength", png.size()},
         {"uri", "data:application/octet-stream;base64," + protocol::encode_base64(png)}});
    doc["bufferViews"].push_back({{"buffer", 1}, {"byteOffset", 0}, {"byteLength", png.size()}});
    for (int i = 0; i < 50; ++i) {
        doc["images"].push_back({{"bufferView", 2}, {"mimeType", "image/png"}});
        doc["textures"].push_back({{"source", i}});
        doc["materials"].push_back(
            {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", i}}}}}});
    }
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().textures.size(), 1u);
    EXPECT_EQ(a.value().textures[0].bytes.size(), png.size());
    ASSERT_EQ(a.value().materials.size(), 50u);
    for (const AssetMaterial& m : a.value().materials) EXPECT_EQ(m.base_color_texture, 0);
}

TEST(GltfImport, TooManyPrimitivesForTheBudgetAreRefusedBeforeTinygltfReadsThem) {
    // 1,000 primitives count 128 triangles each at least: a budget of 10,000 cannot hold them.
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    const nlohmann::json primitive = doc["meshes"][0]["primitives"][0];
    for (int i = 1; i < 1000; ++i) doc["meshes"][0]["primitives"].push_back(primitive);
    doc["extras"] = {{"note", "primitives"}, {"list", {"primitives", 1}}};  // not primitives
    ImportLimits limits;
    limits.max_triangles = 10000;
    auto a = import_text(AssetFormat::Gltf, doc.dump(), {}, limits);
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::TooLarge);
    EXPECT_THAT(a.error().detail, HasSubstr("declares 1000 primitives"));
    // Within the budget, the same file imports, one mesh per primitive.
    limits.max_triangles = 1000 * (1 + 128);
    auto b = import_text(AssetFormat::Gltf, doc.dump(), {}, limits);
    ASSERT_TRUE(b.has_value()) << b.error().detail;
    EXPECT_EQ(b.value().meshes.size(), 1000u);
}

TEST(GltfImport, AnIndexOutsideTheVerticesIsRefusedNamingTheAccessor) {
    std::string doc = triangle_gltf(R"([{"mesh": 0}])");
    // The index buffer view is 6 bytes; a count of 6 runs past it.
    doc.replace(doc.find(R"("count": 3, "type": "SCALAR")"), 10, R"("count": 6)");
    auto a = import_text(AssetFormat::Gltf, doc);
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().element, "meshes[0].primitives[0].indices (accessors[1])");
    EXPECT_THAT(a.error().detail, HasSubstr("run past its buffer view"));
}

TEST(GltfImport, CyclesAndNodesWithTwoParentsAreRefused) {
    auto cycle = import_text(AssetFormat::Gltf,
                             triangle_gltf(R"([{"children": [1]}, {"children": [0], "mesh": 0}])"));
    ASSERT_FALSE(cycle.has_value());
    EXPECT_THAT(cycle.error().detail, HasSubstr("reached twice"));
    auto shared = import_text(
        AssetFormat::Gltf, triangle_gltf(R"([{"children": [2]}, {"children": [2]}, {"mesh": 0}])",
                                         "", R"([{"nodes": [0, 1]}])"));
    ASSERT_FALSE(shared.has_value());
    EXPECT_EQ(shared.error().element, "nodes[2]");
}

TEST(GltfImport, DeeplyNestedJsonIsRefusedBeforeParsing) {
    const std::string deep = R"({"asset": {"version": "2.0"}, "extras": )" +
                             std::string(5000, '[') + std::string(5000, ']') + "}";
    auto a = import_text(AssetFormat::Gltf, deep);
    ASSERT_FALSE(a.has_value());
    EXPECT_THAT(a.error().detail, HasSubstr("nested deeper"));
}

TEST(GltfImport, AssimpsBrokenFilesAreRefusedWithTheirReason) {
    REQUIRE_TESTMODELS();
    const std::pair<const char*, const char*> cases[] = {
        {"glTF2/IndexOutOfRange/IndexOutOfRange.gltf", ""},
        {"glTF2/RecursiveNodes/RecursiveNodes.gltf", ""},
        {"glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb", "not finite"},
        {"glTF2/glTF-Asset-Generator/Mesh_PrimitiveMode/Mesh_PrimitiveMode_00.gltf", ""},
    };
    for (const auto& [path, words] : cases) {
        auto a = import_path(path);
        ASSERT_FALSE(a.has_value()) << path;
        EXPECT_EQ(a.error().file, path);
        EXPECT_FALSE(a.error().detail.empty());
        EXPECT_THAT(a.error().detail, HasSubstr(words)) << a.error().detail;
    }
}

}  // namespace
}  // namespace strata::assets::test
