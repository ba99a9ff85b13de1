// The formats read through assimp (protocol/assets/assimp_import.h): small files written here and
// real ones from assimp-testmodels. What is kept, what is warned about, the budget, and that
// assimp sees only the upload and its side files.

#include <cstring>

#include <gmock/gmock.h>

#include "engine/image/png.h"
#include "protocol/assets/assimp_import.h"
#include "protocol/base64.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

const std::string TRIANGLE_STL = R"(solid t
facet normal 0 0 1
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 1 0
 endloop
endfacet
endsolid t
)";

const std::string QUAD_OFF = "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

Imported<Asset> import_model(const std::string& relative, AssetFormat format,
                             const SideFiles& side = {}) {
    const std::string bytes = read_file(std::string(STRATA_ASSIMP_MODELS_DIR) + "/" + relative);
    if (bytes.empty()) return ErrorSink(relative).invalid("", "missing");
    return import_asset(format, bytes_of(bytes), relative, {}, side);
}

bool any_warning(const Asset& a, const std::string& part) {
    for (const std::string& w : a.warnings)
        if (w.find(part) != std::string::npos) return true;
    return false;
}

TEST(AssimpImport, TheFormatsAreNamedByTheirExtensions) {
    EXPECT_EQ(format_from_name("FBX"), AssetFormat::Fbx);
    EXPECT_EQ(format_from_name("dae"), AssetFormat::Dae);
    EXPECT_EQ(format_from_name("3ds"), AssetFormat::ThreeDs);
    EXPECT_EQ(format_from_name("zgl"), AssetFormat::Xgl);
    EXPECT_EQ(format_name(AssetFormat::ThreeMf), std::string("3mf"));
    EXPECT_EQ(format_from_media_type("model/vnd.collada+xml; charset=utf-8"), AssetFormat::Dae);
    EXPECT_FALSE(format_from_name("c4d").has_value());
    EXPECT_TRUE(format_is_assimp(AssetFormat::Stl));
    EXPECT_FALSE(format_is_assimp(AssetFormat::Ply));
}

TEST(AssimpImport, AnAsciiStlIsOneMeshWithItsNormals) {
    auto a = import_text(AssetFormat::Stl, TRIANGLE_STL);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().meshes.size(), 1u);
    EXPECT_EQ(a.value().meshes[0].triangles.size(), 1u);
    EXPECT_EQ(a.value().meshes[0].positions.size(), 3u);
    EXPECT_THAT(a.value().meshes[0].normals, Contains(Vec3(0, 0, 1)));
    std::size_t placed = 0;
    for (const AssetNode& n : a.value().nodes)
        for (int m : n.meshes) placed += m == 0 ? 1 : 0;
    EXPECT_EQ(placed, 1u);
}

TEST(AssimpImport, AnOffQuadIsTriangulated) {
    auto a = import_text(AssetFormat::Off, QUAD_OFF);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().meshes.size(), 1u);
    EXPECT_EQ(a.value().meshes[0].triangles.size(), 2u);
}

TEST(AssimpImport, TheBudgetIsCheckedBeforeTheMeshesAreCopied) {
    ImportLimits limits;
    limits.max_triangles = 1;
    auto a = import_text(AssetFormat::Off, QUAD_OFF, {}, limits);
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::TooLarge);
    EXPECT_THAT(a.error().detail, HasSubstr("2 triangles"));
}

TEST(AssimpImport, AFileThatIsNotItsFormatIsRefusedNamingIt) {
    auto a = import_text(AssetFormat::Fbx, "this is not an FBX file at all");
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::InvalidAsset);
    EXPECT_THAT(a.error().detail, HasSubstr("not a readable fbx file"));
}

TEST(AssimpImport, AnFbxKeepsItsNodeTreeMaterialsAndNames) {
    auto a = import_model("FBX/cubes_with_names.fbx", AssetFormat::Fbx);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_GE(a.value().meshes.size(), 2u);
    EXPECT_FALSE(a.value().materials.empty());
    std::size_t named = 0;
    for (const AssetNode& n : a.value().nodes) named += n.name.empty() ? 0 : 1;
    EXPECT_GE(named, 2u);
}

TEST(AssimpImport, WhatIsNotImportedIsNamedInTheWarnings) {
    auto a = import_model("FBX/animation_with_skeleton.fbx", AssetFormat::Fbx);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_TRUE(any_warning(a.value(), "animations left out"));
    EXPECT_TRUE(any_warning(a.value(), "bones left out"));
    auto cameras = import_model("Collada/duck.dae", AssetFormat::Dae);
    ASSERT_TRUE(cameras.has_value()) << cameras.error().detail;
    EXPECT_TRUE(any_warning(cameras.value(), "cameras left out"));
}

TEST(AssimpImport, AColladaTextureComesFromTheUploadOrIsOnlyNamed) {
    auto alone = import_model("Collada/duck.dae", AssetFormat::Dae);
    ASSERT_TRUE(alone.has_value()) << alone.error().detail;
    ASSERT_EQ(alone.value().textures.size(), 1u);
    EXPECT_EQ(alone.value().textures[0].uri, "./duckCM.tga");
    EXPECT_TRUE(alone.value().textures[0].bytes.empty());
    ASSERT_EQ(alone.value().materials.size(), 1u);
    EXPECT_EQ(alone.value().materials[0].textures[0], 0);
    const SideFiles side{{"duckCM.tga", "not really a tga"}};
    auto with = import_model("Collada/duck.dae", AssetFormat::Dae, side);
    ASSERT_TRUE(with.has_value()) << with.error().detail;
    EXPECT_EQ(with.value().textures[0].bytes.size(), side.at("duckCM.tga").size());
}

TEST(AssimpImport, TwoUvChannelsBecomeTheMeshsTwoTextureCoordinateSets) {
    auto a = import_model("Collada/cube_with_2UVs.DAE", AssetFormat::Dae);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_FALSE(a.value().meshes.empty());
    const AssetMesh& m = a.value().meshes[0];
    EXPECT_EQ(m.uvs.size(), m.positions.size());
    EXPECT_EQ(m.uvs1.size(), m.positions.size());
    EXPECT_NE(m.uvs, m.uvs1);
    EXPECT_FALSE(any_warning(a.value(), "texture coordinate sets"));
}

TEST(AssimpImport, AMapReadsTheUvChannelItsMaterialNames) {
    // A glTF through assimp's own reader: its texCoord becomes assimp's uv channel.
    auto doc = nlohmann::json::parse(triangle_gltf(R"([{"mesh": 0}])", R"(, "material": 0)"));
    add_float_attribute(doc, "TEXCOORD_0", {0, 0, 1, 0, 0, 1}, "VEC2");
    add_float_attribute(doc, "TEXCOORD_1", {0.5f, 0.5f, 0.25f, 0.5f, 0.5f, 0.25f}, "VEC2");
    const uint8_t rgb[] = {200, 100, 50};
    doc["images"] = {{{"uri", "data:image/png;base64," +
                                  protocol::encode_base64(encode_png(rgb, 1, 1, 3).value())}}};
    doc["textures"] = {{{"source", 0}}};
    doc["materials"] = {
        {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}, {"texCoord", 1}}}}}}};
    const std::string text = doc.dump();
    auto a = import_assimp(bytes_of(text), AssetFormat::Gltf, "t.gltf", {}, {});
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const AssetMesh& mesh = a.value().meshes.at(0);
    ASSERT_GE(mesh.material, 0);  // assimp adds a default material of its own
    const AssetMaterial& m = a.value().materials.at(std::size_t(mesh.material));
    EXPECT_GE(m.texture(TextureSlot::BaseColor), 0);
    EXPECT_EQ(m.material.base_color_uv_set, 1u);
    EXPECT_EQ(mesh.uvs1.size(), 3u);
}

TEST(AssimpImport, AFileNamingAServerPathGetsNothingFromIt) {
    // An image named by an absolute path is only named: assimp reads through the upload's files
    // alone, and the side-file lookup refuses absolute paths.
    const std::string dae = read_file(std::string(STRATA_ASSIMP_MODELS_DIR) + "/Collada/duck.dae");
    ASSERT_FALSE(dae.empty());
    std::string hostile = dae;
    const std::size_t at = hostile.find("./duckCM.tga");
    ASSERT_NE(at, std::string::npos);
    hostile.replace(at, std::strlen("./duckCM.tga"), "/etc/hostname");
    auto a = import_text(AssetFormat::Dae, hostile);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().textures.size(), 1u);
    EXPECT_EQ(a.value().textures[0].uri, "/etc/hostname");
    EXPECT_TRUE(a.value().textures[0].bytes.empty());
}

}  // namespace
}  // namespace strata::assets::test
