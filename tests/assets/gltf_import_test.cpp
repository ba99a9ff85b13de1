// The glTF importer: a real multi-node model whose meshes are shared, node transforms (TRS and
// matrices, composed down the tree), points and lines as points and curve meshes, node
// animations as keyframes, and refusals: triangle strips and fans, external files, bad indices,
// cycles, bad animation channels.

#include <cmath>
#include <cstring>
#include <functional>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "engine/engine.h"
#include "engine/image/png.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/base64.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::Not;

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

TEST(GltfImport, TriangleStripsAndFansAreRefusedNamingThePrimitive) {
    for (const auto& [mode, name] :
         {std::pair{5, "TRIANGLE_STRIP"}, std::pair{6, "TRIANGLE_FAN"}}) {
        auto a =
            import_text(AssetFormat::Gltf,
                        triangle_gltf(R"([{"mesh": 0}])", ", \"mode\": " + std::to_string(mode)));
        ASSERT_FALSE(a.has_value());
        EXPECT_EQ(a.error().type, protocol::ProblemType::InvalidAsset);
        EXPECT_EQ(a.error().element, "meshes[0].primitives[0]");
        EXPECT_THAT(a.error().detail, HasSubstr(name));
    }
}

/// Adds an accessor over `bytes`, in a buffer and buffer view of its own, to `doc`; returns
/// its index.
std::size_t add_accessor(nlohmann::json& doc, const std::string& bytes, int component,
                         std::size_t count, const char* type) {
    doc["buffers"].push_back(
        {{"byteLength", bytes.size()},
         {"uri", "data:application/octet-stream;base64," + protocol::encode_base64(bytes)}});
    doc["bufferViews"].push_back(
        {{"buffer", doc["buffers"].size() - 1}, {"byteLength", bytes.size()}});
    doc["accessors"].push_back({{"bufferView", doc["bufferViews"].size() - 1},
                                {"componentType", component},
                                {"count", count},
                                {"type", type}});
    return doc["accessors"].size() - 1;
}

template <class T>
std::string bytes_of_vector(const std::vector<T>& v) {
    return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

/// Adds float attribute `name` (`type` VEC2 or VEC3) to the first primitive of `doc`.
void add_attribute(nlohmann::json& doc, const char* name, const std::vector<float>& values,
                   const char* type) {
    const std::size_t width = std::string_view(type) == "VEC2" ? 2 : 3;
    doc["meshes"][0]["primitives"][0]["attributes"][name] =
        add_accessor(doc, bytes_of_vector(values), 5126, values.size() / width, type);
}

/// A .gltf of one node placing one primitive of `mode` over `positions` (x y z each), with
/// uint16 `indices` when given and material 0 (a green one).
nlohmann::json primitive_gltf(int mode, const std::vector<float>& positions,
                              const std::vector<uint16_t>& indices = {}) {
    nlohmann::json doc = nlohmann::json::parse(R"({"asset": {"version": "2.0"}, "scene": 0,
      "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
      "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0, 1, 0, 1]}}],
      "meshes": [{"name": "wire", "primitives": [{"attributes": {}, "material": 0}]}],
      "accessors": [], "bufferViews": [], "buffers": []})");
    doc["meshes"][0]["primitives"][0]["mode"] = mode;
    add_attribute(doc, "POSITION", positions, "VEC3");
    if (!indices.empty())
        doc["meshes"][0]["primitives"][0]["indices"] =
            add_accessor(doc, bytes_of_vector(indices), 5123, indices.size(), "SCALAR");
    return doc;
}

/// Four corners of a 3 by 4 rectangle: their bounds' diagonal is 5.
const std::vector<float> RECTANGLE = {0, 0, 0, 3, 0, 0, 3, 4, 0, 0, 4, 0};
const Vec3 CORNERS[4] = {{0, 0, 0}, {3, 0, 0}, {3, 4, 0}, {0, 4, 0}};

/// The one mesh of a glTF document, which must import.
AssetMesh only_mesh(const nlohmann::json& doc, std::vector<std::string>* warnings = nullptr) {
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    EXPECT_TRUE(a.has_value()) << a.error().detail;
    if (!a.has_value() || a.value().meshes.size() != 1) return {};
    if (warnings) *warnings = a.value().warnings;
    return a.value().meshes[0];
}

TEST(GltfImport, PointsBecomeAPointsMeshWithTheDefaultRadiusAndTheirMaterial) {
    std::vector<std::string> warnings;
    const AssetMesh m = only_mesh(primitive_gltf(0, RECTANGLE), &warnings);
    EXPECT_EQ(m.kind, MeshKind::Points);
    ASSERT_EQ(m.positions.size(), 4u);
    EXPECT_EQ(m.positions[2], CORNERS[2]);
    EXPECT_TRUE(m.triangles.empty());
    EXPECT_TRUE(m.strands.empty());
    EXPECT_EQ(m.material, 0);
    // 0.5 * D / sqrt(N) with D = 5 and N = 4.
    EXPECT_EQ(m.radii, std::vector<float>(4, 1.25f));
    EXPECT_THAT(warnings, Contains(HasSubstr("POINTS have no size in glTF: each point has "
                                             "radius 1.25")));
    // With indices: the points they list, in their order.
    const AssetMesh listed = only_mesh(primitive_gltf(0, RECTANGLE, {2, 0}));
    EXPECT_EQ(listed.positions, (std::vector<Vec3>{CORNERS[2], CORNERS[0]}));
    EXPECT_FLOAT_EQ(listed.radii.at(1), 2.5f / std::sqrt(2.0f));
}

TEST(GltfImport, LinesBecomeOneTwoVertexStrandPerLine) {
    const AssetMesh m = only_mesh(primitive_gltf(1, RECTANGLE, {0, 1, 1, 2, 2, 3}));
    EXPECT_EQ(m.kind, MeshKind::Curves);
    EXPECT_EQ(m.strands, (std::vector<uint32_t>{2, 2, 2}));
    EXPECT_EQ(m.positions, (std::vector<Vec3>{CORNERS[0], CORNERS[1], CORNERS[1], CORNERS[2],
                                              CORNERS[2], CORNERS[3]}));
    EXPECT_EQ(m.radii, std::vector<float>(6, 0.01f));  // 0.002 * D
    EXPECT_EQ(m.material, 0);
    // Without indices: the vertices in pairs.
    const AssetMesh bare = only_mesh(primitive_gltf(1, RECTANGLE));
    EXPECT_EQ(bare.strands, (std::vector<uint32_t>{2, 2}));
    EXPECT_EQ(bare.positions, std::vector<Vec3>(CORNERS, CORNERS + 4));
}

TEST(GltfImport, ALineStripIsOneStrandAndALoopRepeatsItsFirstVertex) {
    const AssetMesh strip = only_mesh(primitive_gltf(3, RECTANGLE));
    EXPECT_EQ(strip.kind, MeshKind::Curves);
    EXPECT_EQ(strip.strands, std::vector<uint32_t>{4});
    EXPECT_EQ(strip.positions, std::vector<Vec3>(CORNERS, CORNERS + 4));
    EXPECT_EQ(strip.radii.size(), 4u);

    auto doc = primitive_gltf(2, RECTANGLE, {3, 1, 2});
    add_attribute(doc, "COLOR_0", {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1}, "VEC3");
    const AssetMesh loop = only_mesh(doc);
    EXPECT_EQ(loop.strands, std::vector<uint32_t>{4});
    EXPECT_EQ(loop.positions, (std::vector<Vec3>{CORNERS[3], CORNERS[1], CORNERS[2], CORNERS[3]}));
    // Colours follow their vertices.
    EXPECT_EQ(loop.colors, (std::vector<Vec3>{{1, 1, 1}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}}));
}

TEST(GltfImport, PointsAndLinesDropNormalsAndTextureCoordinatesSayingSo) {
    auto doc = primitive_gltf(1, RECTANGLE);
    add_attribute(doc, "NORMAL", {0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3");
    add_attribute(doc, "TEXCOORD_0", {0, 0, 1, 0, 1, 1, 0, 1}, "VEC2");
    std::vector<std::string> warnings;
    const AssetMesh m = only_mesh(doc, &warnings);
    EXPECT_EQ(m.kind, MeshKind::Curves);
    EXPECT_TRUE(m.normals.empty());
    EXPECT_TRUE(m.uvs.empty());
    EXPECT_THAT(warnings, Contains(HasSubstr("NORMAL, TEXCOORD_0 dropped")));
}

TEST(GltfImport, LinesThatDoNotCloseOrIndexOutsideTheVerticesAreRefused) {
    auto odd = import_text(AssetFormat::Gltf, primitive_gltf(1, RECTANGLE, {0, 1, 2}).dump());
    ASSERT_FALSE(odd.has_value());
    EXPECT_EQ(odd.error().element, "meshes[0].primitives[0]");
    EXPECT_THAT(odd.error().detail, HasSubstr("3 vertices do not make whole lines"));
    auto alone = import_text(AssetFormat::Gltf, primitive_gltf(3, RECTANGLE, {1}).dump());
    ASSERT_FALSE(alone.has_value());
    EXPECT_THAT(alone.error().detail, HasSubstr("LINE_STRIP of 1 vertices"));
    auto outside = import_text(AssetFormat::Gltf, primitive_gltf(1, RECTANGLE, {0, 4}).dump());
    ASSERT_FALSE(outside.has_value());
    EXPECT_EQ(outside.error().element, "meshes[0].primitives[0].indices");
    EXPECT_THAT(outside.error().detail, HasSubstr("outside the 4 vertices"));
    // A loop's closing vertex counts against the budget.
    ImportLimits limits;
    limits.max_vertices = 4;
    auto loop = import_text(AssetFormat::Gltf, primitive_gltf(2, RECTANGLE).dump(), {}, limits);
    ASSERT_FALSE(loop.has_value());
    EXPECT_EQ(loop.error().type, protocol::ProblemType::TooLarge);
    EXPECT_TRUE(import_text(AssetFormat::Gltf, primitive_gltf(3, RECTANGLE).dump(), {}, limits)
                    .has_value());
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

TEST(GltfImport, ATextureTransformIsBakedIntoTheTextureCoordinates) {
    // The triangle with uvs (0,0) (1,0) (0,1) and a material whose base-colour texture is
    // offset by (0.5, 0.25), turned a quarter turn and scaled by 2: T * R * S of the extension.
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    doc["extensionsUsed"] = {"KHR_texture_transform"};
    doc["extensionsRequired"] = {"KHR_texture_transform"};
    const float uvs[] = {0, 0, 1, 0, 0, 1};
    std::string bytes(reinterpret_cast<const char*>(uvs), sizeof uvs);
    const uint8_t rgb[] = {200, 100, 50};
    const std::string png = protocol::encode_base64(encode_png(rgb, 1, 1, 3).value());
    doc["buffers"].push_back({{"byteLength", bytes.size()},
                              {"uri", "data:application/octet-stream;base64," +
                                          protocol::encode_base64(bytes)}});
    doc["bufferViews"].push_back({{"buffer", 1}, {"byteLength", bytes.size()}});
    doc["accessors"].push_back(
        {{"bufferView", 2}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}});
    doc["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = 2;
    doc["images"] = {{{"uri", "data:image/png;base64," + png}}};
    doc["textures"] = {{{"source", 0}}};
    doc["materials"] = {
        {{"pbrMetallicRoughness",
          {{"baseColorTexture",
            {{"index", 0},
             {"extensions",
              {{"KHR_texture_transform",
                {{"offset", {0.5, 0.25}}, {"rotation", 1.5707963267948966}, {"scale", {2, 2}}}}}}}}}}}};
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const std::vector<glm::vec2>& got = a.value().meshes.at(0).uvs;
    ASSERT_EQ(got.size(), 3u);
    // u' = cos*2u + sin*2v + 0.5, v' = -sin*2u + cos*2v + 0.25
    const glm::vec2 expected[] = {{0.5f, 0.25f}, {0.5f, -1.75f}, {2.5f, 0.25f}};
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(got[i].x, expected[i].x, 1e-5f) << i;
        EXPECT_NEAR(got[i].y, expected[i].y, 1e-5f) << i;
    }
    for (const std::string& w : a.value().warnings)
        EXPECT_EQ(w.find("KHR_texture_transform"), std::string::npos) << w;
    // A transform that is not numbers is refused, naming it.
    doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]
       ["KHR_texture_transform"]["scale"] = {"big", 2};
    auto bad = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_FALSE(bad.has_value());
    EXPECT_THAT(bad.error().element.value_or(""), HasSubstr("KHR_texture_transform"));
}

TEST(GltfImport, TangentsAreReadAndKeptWithTheNormalsTheyGoWith) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_float_attribute(doc, "NORMAL", {0, 0, 1, 0, 0, 1, 0, 0, 1}, "VEC3");
    add_float_attribute(doc, "TEXCOORD_0", {0, 0, 1, 0, 0, 1}, "VEC2");
    // Exporters write w as 0.99999 now and then: it stands for +1.
    add_float_attribute(doc, "TANGENT", {1, 0, 0, 1, 1, 0, 0, 0.99999f, 0, 1, 0, -1}, "VEC4");
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().meshes.at(0).tangents.size(), 3u);
    for (const std::string& w : a.value().warnings) EXPECT_THAT(w, Not(HasSubstr("TANGENT")));
    AssetBatch b = asset_to_batch(std::move(a.value()), {"t", true, {}});
    const auto& mesh = std::get<AddMesh>(b.batch.edits.at(0));
    const std::vector<Vec4> want = {{1, 0, 0, 1}, {1, 0, 0, 1}, {0, 1, 0, -1}};
    EXPECT_EQ(mesh.tangents, want);

    // Without normals they are dropped, saying so (glTF has no TANGENT without NORMAL).
    auto bare = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_float_attribute(bare, "TANGENT", {1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}, "VEC4");
    auto without = import_text(AssetFormat::Gltf, bare.dump());
    ASSERT_TRUE(without.has_value()) << without.error().detail;
    AssetBatch dropped = asset_to_batch(std::move(without.value()), {"t", true, {}});
    EXPECT_TRUE(std::get<AddMesh>(dropped.batch.edits.at(0)).tangents.empty());
    EXPECT_THAT(dropped.warnings, Contains(HasSubstr("tangents without normals dropped")));

    // A tangent that is not a VEC4 of floats is refused, naming the attribute.
    auto vec3 = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_float_attribute(vec3, "TANGENT", {1, 0, 0, 1, 0, 0, 1, 0, 0}, "VEC3");
    auto bad = import_text(AssetFormat::Gltf, vec3.dump());
    ASSERT_FALSE(bad.has_value());
    EXPECT_THAT(bad.error().element.value_or(""), HasSubstr("TANGENT"));
}

TEST(GltfImport, EachTextureReadsItsOwnCoordinateSetZeroOrOne) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    add_float_attribute(doc, "TEXCOORD_0", {0, 0, 1, 0, 0, 1}, "VEC2");
    add_float_attribute(doc, "TEXCOORD_1", {0.5f, 0.5f, 0.25f, 0.5f, 0.5f, 0.25f}, "VEC2");
    const uint8_t rgb[] = {200, 100, 50};
    doc["images"] = {
        {{"uri", "data:image/png;base64," +
                     protocol::encode_base64(encode_png(rgb, 1, 1, 3).value())}}};
    doc["textures"] = {{{"source", 0}}};
    // Colour through set 0, occlusion (a light map, as exporters write it) through set 1.
    doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}},
                         {"occlusionTexture", {{"index", 0}, {"texCoord", 1}}}}};
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_TRUE(a.value().warnings.empty()) << a.value().warnings.front();
    const AssetMesh& mesh = a.value().meshes.at(0);
    EXPECT_EQ(mesh.uvs, (std::vector<glm::vec2>{{0, 0}, {1, 0}, {0, 1}}));
    EXPECT_EQ(mesh.uvs1, (std::vector<glm::vec2>{{0.5f, 0.5f}, {0.25f, 0.5f}, {0.5f, 0.25f}}));
    const Material& m = a.value().materials.at(0).material;
    EXPECT_EQ(m.base_color_uv_set, 0u);
    EXPECT_EQ(m.occlusion_uv_set, 1u);

    // Without a texture that reads it, the second set is not kept.
    doc["materials"][0]["occlusionTexture"]["texCoord"] = 0;
    auto one = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(one.has_value()) << one.error().detail;
    EXPECT_TRUE(one.value().meshes.at(0).uvs1.empty());

    // A set beyond 1 reads set 0, and a warning says so.
    doc["materials"][0]["occlusionTexture"]["texCoord"] = 3;
    auto beyond = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(beyond.has_value()) << beyond.error().detail;
    EXPECT_EQ(beyond.value().materials.at(0).material.occlusion_uv_set, 0u);
    ASSERT_EQ(beyond.value().warnings.size(), 1u);
    EXPECT_THAT(beyond.value().warnings[0], HasSubstr("occlusionTexture reads TEXCOORD_3"));
}

TEST(GltfImport, AnEmissiveStrengthMultipliesTheEmissiveFactor) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
    doc["materials"] = {{{"emissiveFactor", {1.0, 0.5, 0.0}},
                         {"extensions", {{"KHR_materials_emissive_strength",
                                          {{"emissiveStrength", 4.0}}}}}}};
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_EQ(a.value().materials.at(0).material.emission, Vec3(4.0f, 2.0f, 0.0f));
    EXPECT_TRUE(a.value().warnings.empty()) << a.value().warnings.front();
    doc["materials"][0]["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = -1;
    auto bad = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_FALSE(bad.has_value());
    EXPECT_THAT(bad.error().detail, HasSubstr("emissiveStrength"));
}

TEST(GltfImport, AMaterialsMapsAlphaAndUnlitAreRead) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    const uint8_t rgb[] = {128, 128, 255};
    const std::string png = "data:image/png;base64," +
                            protocol::encode_base64(encode_png(rgb, 1, 1, 3).value());
    doc["images"] = {{{"uri", png}}, {{"uri", png}}};
    doc["textures"] = {{{"source", 0}}, {{"source", 1}}};
    doc["extensionsUsed"] = {"KHR_materials_unlit"};
    doc["materials"] = {
        {{"alphaMode", "MASK"},
         {"alphaCutoff", 0.3},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {1.0, 1.0, 1.0, 0.5}},
           {"baseColorTexture", {{"index", 0}}},
           {"metallicRoughnessTexture", {{"index", 1}}}}},
         {"normalTexture", {{"index", 0}, {"scale", 2.0}}},
         {"occlusionTexture", {{"index", 1}, {"strength", 0.25}}},
         {"emissiveTexture", {{"index", 1}}},
         {"emissiveFactor", {1.0, 0.5, 0.25}},
         {"extensions", {{"KHR_materials_unlit", nlohmann::json::object()}}}}};
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_TRUE(a.value().warnings.empty()) << a.value().warnings.front();
    const AssetMaterial& m = a.value().materials.at(0);
    EXPECT_EQ(m.material.alpha_mode, AlphaMode::Mask);
    EXPECT_FLOAT_EQ(m.material.alpha_cutoff, 0.3f);
    EXPECT_FLOAT_EQ(m.material.alpha, 0.5f);
    EXPECT_FLOAT_EQ(m.material.normal_scale, 2.0f);
    EXPECT_FLOAT_EQ(m.material.occlusion_strength, 0.25f);
    EXPECT_TRUE(m.material.unlit);
    EXPECT_EQ(m.material.emission, Vec3(1.0f, 0.5f, 0.25f));  // kept with its texture
    // Image 0 as colour (base colour) and as data (normals): two textures. Image 1 only as data
    // (metallic-roughness, occlusion) and as colour (emissive): two as well.
    const auto& t = a.value().textures;
    ASSERT_EQ(t.size(), 4u);
    for (const TextureSlotInfo& slot : TEXTURE_SLOTS) {
        const int i = m.texture(slot.slot);
        ASSERT_GE(i, 0) << slot.field;
        EXPECT_EQ(t.at(std::size_t(i)).color_space, slot.space) << slot.field;
    }
    EXPECT_EQ(m.texture(TextureSlot::MetallicRoughness), m.texture(TextureSlot::Occlusion));
    EXPECT_NE(m.texture(TextureSlot::BaseColor), m.texture(TextureSlot::Normal));

    doc["materials"][0]["alphaMode"] = "SOMETIMES";
    auto bad = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_FALSE(bad.has_value());
    EXPECT_THAT(bad.error().detail, HasSubstr("alphaMode 'SOMETIMES'"));
}

TEST(GltfImport, ASecondSetThePrimitiveLacksAndASecondTransformOfOneSetAreNamedInWarnings) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    const uint8_t rgb[] = {128, 128, 255};
    doc["images"] = {{{"uri", "data:image/png;base64," +
                                  protocol::encode_base64(encode_png(rgb, 1, 1, 3).value())}}};
    doc["textures"] = {{{"source", 0}}};
    doc["extensionsUsed"] = {"KHR_texture_transform"};
    const nlohmann::json turned = {{"KHR_texture_transform", {{"rotation", 1.0}}}};
    doc["materials"] = {{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}},
                         {"emissiveTexture", {{"index", 0}, {"extensions", turned}}},
                         {"normalTexture", {{"index", 0}, {"texCoord", 1}}}}};
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const std::vector<std::string>& w = a.value().warnings;
    ASSERT_EQ(w.size(), 2u);
    EXPECT_THAT(w, Contains(HasSubstr("materials[0].emissiveTexture transforms TEXCOORD_0 "
                                      "otherwise")));
    EXPECT_THAT(w, Contains(HasSubstr("read TEXCOORD_1, which it lacks")));
    // The normal map still reads set 1: the scene reads set 0 on a mesh without it.
    EXPECT_EQ(a.value().materials.at(0).material.normal_uv_set, 1u);

    // A texture with another sampler than the first's is read through the first's, saying so.
    doc["samplers"] = {{{"wrapS", 33071}, {"wrapT", 33071}}};  // clamp to edge
    doc["textures"].push_back({{"source", 0}, {"sampler", 0}});
    doc["materials"][0]["normalTexture"] = {{"index", 1}};
    auto sampled = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(sampled.has_value()) << sampled.error().detail;
    EXPECT_THAT(sampled.value().warnings,
                Contains(HasSubstr(
                    "materials[0].normalTexture's sampler (wrap or filter) differs")));
}

TEST(GltfImport, ThousandsOfUnreadFeaturesGiveABoundedListOfWarnings) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    for (int i = 0; i < 200; ++i)
        doc["materials"].push_back({{"extensions", {{"KHR_materials_sheen", nlohmann::json::object()}}}});
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const std::vector<std::string>& w = a.value().warnings;
    ASSERT_EQ(w.size(), 65u);
    EXPECT_EQ(w[0], "materials[0].extensions.KHR_materials_sheen not imported");
    EXPECT_EQ(w.back(), "136 more warnings not listed");
}

TEST(GltfImport, GltfOneAndUnknownRequiredExtensionsAreRefusedSayingSo) {
    REQUIRE_TESTMODELS();
    auto one = import_path("glTF/TwoBoxes/TwoBoxes.gltf");
    ASSERT_FALSE(one.has_value());
    EXPECT_EQ(one.error().element, "asset.version");
    EXPECT_THAT(one.error().detail, HasSubstr("glTF 1.0 is not supported; only glTF 2.0"));
    // Draco is read; any other required extension is refused by name, Draco or not beside it.
    std::string doc = triangle_gltf(R"([{"mesh": 0}])");
    doc.insert(1, R"("extensionsRequired": ["KHR_draco_mesh_compression", "EXT_meshopt_compression"],)");
    auto other = import_text(AssetFormat::Gltf, doc);
    ASSERT_FALSE(other.has_value());
    EXPECT_EQ(other.error().element, "extensionsRequired");
    EXPECT_THAT(other.error().detail, HasSubstr("requires EXT_meshopt_compression,"));
    EXPECT_THAT(other.error().detail, Not(HasSubstr("draco")));
}

double area(const AssetMesh& m) {
    double sum = 0.0;
    for (const Triangle& t : m.triangles)
        sum += 0.5 * double(glm::length(glm::cross(m.positions[t.y] - m.positions[t.x],
                                                   m.positions[t.z] - m.positions[t.x])));
    return sum;
}

TEST(GltfImport, ADracoTetrahedronDecodesWithItsNormals) {
    // data/draco-tetrahedron.glb: four faces written by draco::Encoder as a triangle soup (12
    // points, positions quantised to 14 bits), the one file of this suite that needs nothing
    // beside the repository.
    const std::string glb =
        read_file(std::string(STRATA_ASSET_TEST_DATA_DIR) + "/draco-tetrahedron.glb");
    ASSERT_FALSE(glb.empty());
    auto a = import_asset(AssetFormat::Glb, bytes_of(glb), "tet.glb", {});
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a->meshes.size(), 1u);
    const AssetMesh& m = a->meshes[0];
    EXPECT_EQ(m.name, "tetrahedron");
    ASSERT_EQ(m.triangles.size(), 4u);
    ASSERT_EQ(m.positions.size(), 12u);
    ASSERT_EQ(m.normals.size(), 12u);
    for (const Vec3& p : m.positions) {
        const bool corner = glm::length(p) < 1e-3f || glm::length(p - Vec3(1, 0, 0)) < 1e-3f ||
                            glm::length(p - Vec3(0, 1, 0)) < 1e-3f ||
                            glm::length(p - Vec3(0, 0, 1)) < 1e-3f;
        EXPECT_TRUE(corner) << p.x << " " << p.y << " " << p.z;
    }
    // Each face's normals are its own geometric normal (outward, as the encoder wrote them).
    for (const Triangle& t : m.triangles) {
        const Vec3 n = glm::cross(m.positions[t.y] - m.positions[t.x],
                                  m.positions[t.z] - m.positions[t.x]);
        for (int k = 0; k < 3; ++k)
            EXPECT_GT(glm::dot(glm::normalize(n), glm::normalize(m.normals[t[k]])), 0.99f);
    }
    EXPECT_NEAR(area(m), 1.5 + std::sqrt(3.0) / 2.0, 1e-3);
    // Every truncation of the file is refused with an answer, never a crash.
    for (std::size_t n = 0; n < glb.size(); n += 7)
        EXPECT_FALSE(import_asset(AssetFormat::Glb, bytes_of(glb.substr(0, n)), "t.glb", {})) << n;
}

TEST(GltfImport, AGlbWhoseChunksRunPastItsEndIsRefusedBeforeTinygltfReadsIt) {
    std::string glb = read_file(std::string(STRATA_ASSET_TEST_DATA_DIR) + "/draco-tetrahedron.glb");
    ASSERT_FALSE(glb.empty());
    ASSERT_TRUE(import_asset(AssetFormat::Glb, bytes_of(glb), "t.glb", {}).has_value());
    uint32_t json_length = 0;
    std::memcpy(&json_length, glb.data() + 12, 4);
    const std::size_t bin_header = 20 + json_length;
    uint32_t bin_length = 0;
    std::memcpy(&bin_length, glb.data() + bin_header, 4);
    // The BIN chunk claiming 4 and 8 bytes more than there are (tinygltf's own check lets
    // these through and reads past the end), then the header claiming more than the file.
    for (uint32_t more : {4u, 8u}) {
        std::string bad = glb;
        const uint32_t claimed = bin_length + more;
        std::memcpy(bad.data() + bin_header, &claimed, 4);
        auto a = import_asset(AssetFormat::Glb, bytes_of(bad), "t.glb", {});
        ASSERT_FALSE(a.has_value()) << more;
        EXPECT_THAT(a.error().detail, HasSubstr("its BIN chunk of " + std::to_string(claimed) +
                                                " bytes runs past the length in its header"));
    }
    auto cut = import_asset(AssetFormat::Glb, bytes_of(glb.substr(0, glb.size() - 1)), "t.glb", {});
    ASSERT_FALSE(cut.has_value());
    EXPECT_THAT(cut.error().detail, HasSubstr("its header says " + std::to_string(glb.size()) +
                                              " bytes; the file has " +
                                              std::to_string(glb.size() - 1)));
}

/// The Draco-compressed 2CylinderEngine (.gltf) with its .bin, `edit` applied to both.
Imported<Asset> import_draco(const std::function<void(std::string&, std::string&)>& edit = {}) {
    const std::string dir = MODELS + "/glTF2/draco/";
    std::string gltf = read_file(dir + "2CylinderEngine.gltf");
    std::string bin = read_file(dir + "2CylinderEngine.bin");
    if (edit) edit(gltf, bin);
    return import_asset(AssetFormat::Gltf, bytes_of(gltf), "draco.gltf", {},
                        SideFiles{{"2CylinderEngine.bin", bin}});
}

TEST(GltfImport, DracoCompressedPrimitivesDecodeToTheUncompressedFilesMeshes) {
    REQUIRE_TESTMODELS();
    auto draco = import_draco();
    ASSERT_TRUE(draco.has_value()) << draco.error().element.value_or("") << ": "
                                   << draco.error().detail;
    auto plain = import_path("glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    ASSERT_TRUE(plain.has_value());
    const Asset& a = draco.value();
    const Asset& b = plain.value();
    EXPECT_EQ(a.nodes.size(), b.nodes.size());
    ASSERT_EQ(a.meshes.size(), 34u);
    ASSERT_EQ(a.meshes.size(), b.meshes.size());
    for (std::size_t i = 0; i < a.meshes.size(); ++i) {
        const AssetMesh& m = a.meshes[i];
        // Draco reorders vertices and drops degenerate triangles, so each mesh is compared by
        // what neither changes: surface area, bounds (within the quantisation), unit normals.
        EXPECT_LE(m.triangles.size(), b.meshes[i].triangles.size()) << i;
        EXPECT_NEAR(area(m), area(b.meshes[i]), 5e-3 * area(b.meshes[i])) << i;
        EXPECT_EQ(m.positions.size(), m.normals.size()) << i;
        EXPECT_TRUE(m.uvs.empty()) << i;
        Bounds3 ba, bb;
        for (const Vec3& p : m.positions) ba.extend(p);
        for (const Vec3& p : b.meshes[i].positions) bb.extend(p);
        const float tolerance = 1e-3f * glm::length(bb.extent()) + 1e-5f;
        EXPECT_LE(glm::length(ba.lower - bb.lower), tolerance) << i;
        EXPECT_LE(glm::length(ba.upper - bb.upper), tolerance) << i;
        for (const Vec3& n : m.normals) ASSERT_NEAR(glm::length(n), 1.0f, 0.02f) << i;
        for (const Triangle& t : m.triangles)
            ASSERT_TRUE(t.x < m.positions.size() && t.y < m.positions.size() &&
                        t.z < m.positions.size());
    }
    for (const std::string& w : a.warnings) EXPECT_THAT(w, Not(HasSubstr("draco"))) << w;
}

TEST(GltfImport, BrokenDracoDataIsRefusedNamingThePrimitive) {
    REQUIRE_TESTMODELS();
    // Garbage where the first primitive's compressed bytes are (bufferView 0 starts the .bin).
    auto garbage = import_draco([](std::string&, std::string& bin) {
        for (std::size_t i = 0; i < 64; ++i) bin[i] = char(0x5A ^ i);
    });
    ASSERT_FALSE(garbage.has_value());
    EXPECT_EQ(garbage.error().type, protocol::ProblemType::InvalidAsset);
    EXPECT_EQ(garbage.error().element,
              "meshes[0].primitives[0].extensions.KHR_draco_mesh_compression");
    EXPECT_THAT(garbage.error().detail, HasSubstr("Draco"));
    // Declared counts the data does not have.
    auto counts = import_draco([](std::string& gltf, std::string&) {
        nlohmann::json doc = nlohmann::json::parse(gltf);
        const int position = doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"];
        doc["accessors"][position]["count"] = 2018;
        gltf = doc.dump();
    });
    ASSERT_FALSE(counts.has_value());
    EXPECT_THAT(counts.error().detail,
                HasSubstr("decodes to 2019 vertices where its POSITION accessor declares 2018"));
    // A buffer view that does not exist.
    auto view = import_draco([](std::string& gltf, std::string&) {
        nlohmann::json doc = nlohmann::json::parse(gltf);
        doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]
           ["bufferView"] = 999;
        gltf = doc.dump();
    });
    ASSERT_FALSE(view.has_value());
    EXPECT_THAT(view.error().detail, HasSubstr("bufferView 999 does not exist"));
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
        EXPECT_EQ(a.value().materials[0].textures[0], 0) << path;
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
    for (const AssetMaterial& m : a.value().materials) EXPECT_EQ(m.textures[0], 0);
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

/// Animation 0 channel: node `node`'s `path` over `times`, `values` flat.
void add_channel(nlohmann::json& doc, int node, const char* path, const std::vector<float>& times,
                 const std::vector<float>& values, const char* interpolation = "LINEAR") {
    const std::size_t width = std::string(path) == "rotation" ? 4 : 3;
    const std::size_t input =
        add_accessor(doc, bytes_of_vector(times), 5126, times.size(), "SCALAR");
    const std::size_t output = add_accessor(doc, bytes_of_vector(values), 5126,
                                            values.size() / width, width == 4 ? "VEC4" : "VEC3");
    if (!doc.contains("animations")) doc["animations"] = {{{"channels", nlohmann::json::array()},
                                                           {"samplers", nlohmann::json::array()}}};
    nlohmann::json& anim = doc["animations"][0];
    anim["samplers"].push_back(
        {{"input", input}, {"output", output}, {"interpolation", interpolation}});
    anim["channels"].push_back(
        {{"sampler", anim["samplers"].size() - 1}, {"target", {{"node", node}, {"path", path}}}});
}

TEST(GltfAnimation, NodeChannelsBecomeKeyframesAtTheUnionOfTheirTimes) {
    // Node 1 (a leaf under node 0) slides along x then y and turns 90 degrees about z over 2 s;
    // node 0 scales in steps. Keys at every time any channel has one; the others interpolated.
    auto doc = nlohmann::json::parse(triangle_gltf(
        R"([{"children": [1], "translation": [0, 5, 0]}, {"mesh": 0, "scale": [2, 2, 2]}])"));
    add_channel(doc, 1, "translation", {0, 1, 2}, {0, 0, 0, 1, 0, 0, 1, 2, 0});
    add_channel(doc, 1, "rotation", {0, 2}, {0, 0, 0, 1, 0, 0, 0.7071068f, 0.7071068f});
    add_channel(doc, 0, "scale", {0, 1}, {1, 1, 1, 3, 3, 3}, "STEP");
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const AssetNode& leaf = a->nodes[1];
    ASSERT_EQ(leaf.animation.size(), 3u);
    EXPECT_EQ(leaf.animation[1].time, 1.0f);
    // At 1 s: at (1, 0, 0), turned 45 degrees, the node's own scale of 2 kept.
    const Vec3 p = leaf.animation[1].transform.transform_point(Vec3(1, 0, 0));
    EXPECT_NEAR(p.x, 1.0f + 2.0f * 0.7071068f, 1e-4f);
    EXPECT_NEAR(p.y, 2.0f * 0.7071068f, 1e-4f);
    const AssetNode& root = a->nodes[0];
    ASSERT_EQ(root.animation.size(), 2u);  // STEP: scale 1 until 1 s, then 3
    EXPECT_EQ(root.animation[0].transform.transform_point(Vec3(1, 0, 0)), Vec3(1, 5, 0));
    EXPECT_EQ(root.animation[1].transform.transform_point(Vec3(1, 0, 0)), Vec3(3, 5, 0));

    // Into the scene: the group and the leaf's instance carry them, interpolated by SRT, and
    // the scene's clock places them.
    AssetBatch b = asset_to_batch(std::move(a.value()), {"anim", true, {}});
    auto engine = std::move(Engine::create().value());
    ASSERT_TRUE(engine->apply(std::move(b.batch)).has_value());
    EditBatch at_one;
    at_one.edits.emplace_back(SetTime{1.0f, std::nullopt});
    ASSERT_TRUE(engine->apply(std::move(at_one)).has_value());
    engine->read([&](const Scene& s) {
        const InstanceRecord& inst = s.instances().at(s.find_instance("anim.node1"));
        EXPECT_EQ(inst.rare->animation.size(), 3u);
        EXPECT_EQ(inst.rare->motion_interpolation, MotionInterpolation::Srt);
        // The group's scale steps to 3 at 1 s: the leaf's point lands at 3 * p + (0, 5, 0).
        const Vec3 w = inst.world.transform_point(Vec3(1, 0, 0));
        EXPECT_NEAR(w.x, 3.0f * p.x, 1e-3f);
        EXPECT_NEAR(w.y, 3.0f * p.y + 5.0f, 1e-3f);
    });
}

TEST(GltfAnimation, WeightsAndLaterAnimationsAreNamedAndBadChannelsRefused) {
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_channel(doc, 0, "translation", {0, 1}, {0, 0, 0, 0, 1, 0}, "CUBICSPLINE");
    auto a = import_text(AssetFormat::Gltf, doc.dump());
    EXPECT_FALSE(a.has_value());  // CUBICSPLINE needs 3 values a key: 6 for 2 keys
    doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_channel(doc, 0, "translation", {0, 1},
                {9, 9, 9, 0, 0, 0, 9, 9, 9, 9, 9, 9, 0, 1, 0, 9, 9, 9}, "CUBICSPLINE");
    doc["animations"][0]["channels"].push_back(
        {{"sampler", 0}, {"target", {{"node", 0}, {"path", "weights"}}}});
    doc["animations"].push_back(doc["animations"][0]);
    a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_EQ(a->nodes[0].animation[1].transform.transform_point(Vec3(0)), Vec3(0, 1, 0));
    EXPECT_THAT(a->warnings, Contains(HasSubstr("CUBICSPLINE tangents ignored")));
    EXPECT_THAT(a->warnings, Contains(HasSubstr("morph target weights not imported")));
    EXPECT_THAT(a->warnings, Contains("1 animation after the first not imported"));

    const auto refused = [](nlohmann::json d, const std::string& element) {
        auto r = import_text(AssetFormat::Gltf, d.dump());
        ASSERT_FALSE(r.has_value()) << element;
        EXPECT_EQ(r.error().element, element) << r.error().detail;
    };
    doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_channel(doc, 0, "translation", {1, 0.5f}, {0, 0, 0, 0, 1, 0});
    refused(doc, "animations[0].channels[0]");  // times out of order
    doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_channel(doc, 0, "rotation", {0}, {0, 0, 0, 0});
    refused(doc, "animations[0].channels[0]");  // a zero quaternion
    doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0, "matrix": [1,0,0,0, 0,1,0,0,
                                                  0,0,1,0, 0,0,0,1]}])"));
    add_channel(doc, 0, "scale", {0}, {1, 1, 1});
    refused(doc, "nodes[0]");  // animated nodes take TRS only
    // A key the scene cannot use (scale 0): the node stays still, saying so.
    doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])"));
    add_channel(doc, 0, "scale", {0, 1}, {1, 1, 1, 0, 0, 0});
    a = import_text(AssetFormat::Gltf, doc.dump());
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_TRUE(a->nodes[0].animation.empty());
    EXPECT_THAT(a->warnings, Contains(HasSubstr("its animation is not imported")));
}

}  // namespace
}  // namespace strata::assets::test
