// The OBJ importer: the real bunny and Spot, MTL materials from the upload only, polygons,
// attributes, and refusals naming the face.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/engine.h"
#include "engine/image/png.h"
#include "protocol/assets/asset_batch.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::HasSubstr;

/// Imports tests/data/models/<name>. The models are part of the repository: a missing one is a
/// failure naming its path, never a skip.
Imported<Asset> import_model(const std::string& name) {
    const std::string path = std::string(STRATA_MODELS_DIR) + "/" + name;
    const std::string text = read_file(path);
    if (text.empty()) return ErrorSink(path).invalid("", "missing");
    return import_asset(AssetFormat::Obj, bytes_of(text), name, {});
}

TEST(ObjImport, TheStanfordBunnyIsOneMeshOfAllItsTriangles) {
    auto a = import_model("stanford-bunny.obj");
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().meshes.size(), 1u);
    EXPECT_EQ(a.value().meshes[0].triangles.size(), 69451u);  // SOURCES.md
    EXPECT_EQ(a.value().nodes.size(), 1u);
    EXPECT_EQ(a.value().nodes[0].meshes, std::vector<int>{0});
}

TEST(ObjImport, SpotKeepsItsTrianglesAndTextureCoordinates) {
    auto a = import_model("spot.obj");
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().meshes.size(), 1u);
    const AssetMesh& m = a.value().meshes[0];
    EXPECT_EQ(m.triangles.size(), 5856u);
    if (!m.uvs.empty()) {
        EXPECT_EQ(m.uvs.size(), m.positions.size());
    }
}

const std::string CUBE_FACES = R"(mtllib cube.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
vt 0 0
vt 1 0
vt 1 1
vn 0 0 -1
usemtl red
f 1/1/1 2/2/1 3/3/1 4/1/1
usemtl shiny
f 1 2 5
f -5 -3 -1
)";

const std::string CUBE_MTL = R"(newmtl red
Kd 1.5 0.2 0.1
Ks 0 0 0
newmtl shiny
Kd 0.5 0.5 0.5
Ks 1 1 1
Ns 1000
Ke 0.5 0 0
map_Kd shiny.png
)";

TEST(ObjImport, MaterialsComeFromTheUploadedMtlWithKdKsNsAndMapKdMapped) {
    auto a = import_text(AssetFormat::Obj, CUBE_FACES, {{"cube.mtl", CUBE_MTL}});
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const Asset& asset = a.value();
    ASSERT_EQ(asset.materials.size(), 2u);
    EXPECT_EQ(asset.materials[0].name, "red");
    EXPECT_EQ(asset.materials[0].material.base_color, Vec3(1.0f, 0.2f, 0.1f));  // clamped
    EXPECT_EQ(asset.materials[0].material.roughness, 1.0f);   // no specular: fully rough
    EXPECT_LT(asset.materials[1].material.roughness, 0.25f);  // Ns 1000: glossy
    EXPECT_EQ(asset.materials[1].material.emission, Vec3(0.5f, 0, 0));
    ASSERT_EQ(asset.materials[1].textures[0], 0);
    EXPECT_EQ(asset.textures[0].uri, "shiny.png");
    EXPECT_EQ(asset.textures[0].mime_type, "image/png");
    EXPECT_TRUE(asset.textures[0].bytes.empty());  // not uploaded
    // One mesh per material: the quad (two triangles) and the two triangles.
    ASSERT_EQ(asset.meshes.size(), 2u);
    EXPECT_EQ(asset.meshes[0].material, 0);
    EXPECT_EQ(asset.meshes[0].triangles.size(), 2u);
    EXPECT_EQ(asset.meshes[1].material, 1);
    EXPECT_EQ(asset.meshes[1].triangles.size(), 2u);
    // The second triangle used negative (relative) indices: vertices 1, 3 and 5.
    const AssetMesh& m = asset.meshes[1];
    const Triangle t = m.triangles[1];
    EXPECT_EQ(m.positions[t[0]], Vec3(0, 0, 0));
    EXPECT_EQ(m.positions[t[1]], Vec3(1, 1, 0));
    EXPECT_EQ(m.positions[t[2]], Vec3(0, 0, 1));
}

TEST(ObjImport, AMapKdImageThatCameWithTheUploadBecomesTheMaterialsTexture) {
    const uint8_t rgb[] = {200, 100, 50};
    const std::string png = encode_png(rgb, 1, 1, 3).value();
    auto a =
        import_text(AssetFormat::Obj, CUBE_FACES, {{"cube.mtl", CUBE_MTL}, {"shiny.png", png}});
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_EQ(a.value().textures.at(0).bytes.size(), png.size());
    // OBJ's v grows upward: "vt 1 1" is the top-right corner, (1, 0) for the engine.
    EXPECT_EQ(a.value().meshes[0].uvs.size(), a.value().meshes[0].positions.size());
    EXPECT_THAT(a.value().meshes[0].uvs, ::testing::Contains(glm::vec2(1, 0)));
    AssetBatch b = asset_to_batch(std::move(a.value()), {"cube", false});
    EXPECT_EQ(b.textures, std::vector<std::string>{"cube.texture0"});
    auto engine = Engine::create();
    ASSERT_TRUE(engine.has_value());
    auto applied = engine.value()->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    engine.value()->read([](const Scene& s) {
        const MaterialRecord* shiny = s.material(s.find_material("cube.material1")).value();
        EXPECT_EQ(shiny->textures[0], s.find_texture("cube.texture0"));
    });
}

TEST(ObjImport, MaterialsNamingTheSameImageShareOneTexture) {
    // An MTL naming one big image fifty times used to hold fifty copies of it.
    const uint8_t rgb[] = {200, 100, 50};
    const std::string png = encode_png(rgb, 1, 1, 3).value();
    std::string mtl;
    for (int i = 0; i < 50; ++i) mtl += "newmtl m" + std::to_string(i) + "\nmap_Kd shiny.png\n";
    mtl += "newmtl other\nmap_Kd other.png\n";
    auto a = import_text(AssetFormat::Obj, CUBE_FACES,
                         {{"cube.mtl", mtl}, {"shiny.png", png}, {"other.png", png}});
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    ASSERT_EQ(a.value().textures.size(), 2u);
    for (std::size_t i = 0; i < 50; ++i) EXPECT_EQ(a.value().materials[i].textures[0], 0);
    EXPECT_EQ(a.value().materials[50].textures[0], 1);
}

TEST(ObjImport, NormAndMapKeAreReadAsMapsDissolveAsBlendAndOtherMapsAreNamed) {
    const uint8_t rgb[] = {128, 128, 255};
    const std::string png = encode_png(rgb, 1, 1, 3).value();
    const std::string mtl = "newmtl glass\nKd 1 1 1\nd 0.25\nmap_Kd shiny.png\n"
                            "norm shiny.png\nmap_Ke glow.png\nmap_Bump bump.png\n"
                            "newmtl solid\nKd 1 1 1\n";
    auto a = import_text(AssetFormat::Obj, CUBE_FACES,
                         {{"cube.mtl", mtl}, {"shiny.png", png}, {"glow.png", png}});
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    const AssetMaterial& glass = a.value().materials.at(0);
    EXPECT_EQ(glass.material.alpha_mode, AlphaMode::Blend);
    EXPECT_EQ(glass.material.alpha, 0.25f);
    EXPECT_EQ(glass.material.emission, Vec3(1.0f));  // map_Ke without Ke
    // One image read as colour and as data is two textures, one per colour space.
    const int base = glass.texture(TextureSlot::BaseColor);
    const int normal = glass.texture(TextureSlot::Normal);
    ASSERT_GE(base, 0);
    ASSERT_GE(normal, 0);
    EXPECT_NE(base, normal);
    EXPECT_EQ(a.value().textures.at(std::size_t(base)).color_space, TextureColorSpace::Srgb);
    EXPECT_EQ(a.value().textures.at(std::size_t(normal)).color_space, TextureColorSpace::Linear);
    EXPECT_GE(glass.texture(TextureSlot::Emissive), 0);
    EXPECT_EQ(a.value().materials.at(1).material.alpha_mode, AlphaMode::Opaque);
    ASSERT_EQ(a.value().warnings.size(), 1u);
    EXPECT_EQ(a.value().warnings[0],
              "material 'glass': its map_Bump (a height map) map 'bump.png' is not imported");
}

TEST(ObjImport, AnMtllibOutsideTheUploadIsNeverReadAndIsNamedInTheWarnings) {
    std::string obj = CUBE_FACES;
    obj.replace(0, 15, "mtllib /etc/passwd");
    auto a = import_text(AssetFormat::Obj, obj);
    ASSERT_TRUE(a.has_value()) << a.error().detail;
    EXPECT_TRUE(a.value().materials.empty());
    ASSERT_FALSE(a.value().warnings.empty());
    EXPECT_THAT(a.value().warnings[0], HasSubstr("/etc/passwd"));
    EXPECT_THAT(a.value().warnings[0], HasSubstr("not part of the upload"));
}

TEST(ObjImport, AFaceIndexOutsideTheVerticesIsRefusedNamingTheFace) {
    auto a = import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().element, "shape 0 face 1");
    EXPECT_THAT(a.error().detail, HasSubstr("vertex index 9"));
    auto b =
        import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//2 3//1\n");
    ASSERT_FALSE(b.has_value());
    EXPECT_THAT(b.error().detail, HasSubstr("normal index 2"));
}

TEST(ObjImport, PointsAndLinesAloneAreRefusedAsHavingNoFaces) {
    auto a = import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nl 1 2\np 1\n");
    ASSERT_FALSE(a.has_value());
    EXPECT_THAT(a.error().detail, HasSubstr("no faces"));
}

TEST(ObjImport, TooManyTrianglesForTheSceneIsTooLarge) {
    ImportLimits limits;
    limits.max_triangles = 1;
    auto a = import_text(AssetFormat::Obj, CUBE_FACES, {}, limits);
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::TooLarge);
}

TEST(ObjImport, AnIndexThatOverflowsAnIntIsRefusedNamingItsLine) {
    // tinyobjloader reads indices into an int: these would wrap to small, valid-looking ones.
    for (const char* face :
         {"f 1 2 99999999999999999999", "f 1 2 2147483648", "f 1/1/1 2 -2147483649",
          "f 1 2 3/00000000004294967297", "l 1 18446744073709551617"}) {
        auto a = import_text(AssetFormat::Obj,
                             std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\n") + face + "\nf 1 2 3\n");
        ASSERT_FALSE(a.has_value()) << face;
        EXPECT_EQ(a.error().element, "line 4") << face;
        EXPECT_THAT(a.error().detail, HasSubstr("out of range")) << face;
    }
    auto fits = import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0000003\n");
    EXPECT_TRUE(fits.has_value()) << fits.error().detail;
}

TEST(ObjImport, DeclaredElementsOverTheBudgetAreRefusedBeforeParsing) {
    ImportLimits limits;
    limits.max_triangles = 1000;
    limits.max_vertices = 1000;
    // Faces past the budget: refused at the line that passes it, with no vertex anywhere
    // (parsing would have found the indices invalid, after holding every face).
    std::string faces;
    for (int i = 0; i < 1001; ++i) faces += "f 1 2 3\n";
    auto a = import_text(AssetFormat::Obj, faces, {}, limits);
    ASSERT_FALSE(a.has_value());
    EXPECT_EQ(a.error().type, protocol::ProblemType::TooLarge);
    EXPECT_EQ(a.error().element, "line 1001");
    EXPECT_THAT(a.error().detail, HasSubstr("max_scene_triangles"));
    // A quad counts two triangles.
    std::string quads;
    for (int i = 0; i < 501; ++i) quads += "f 1 2 3 4\n";
    auto q = import_text(AssetFormat::Obj, quads, {}, limits);
    ASSERT_FALSE(q.has_value());
    EXPECT_EQ(q.error().element, "line 501");
    // Positions past the vertex budget.
    std::string positions;
    for (int i = 0; i < 1001; ++i) positions += "v 0 0 0\n";
    auto v = import_text(AssetFormat::Obj, positions + "f 1 2 3\n", {}, limits);
    ASSERT_FALSE(v.has_value());
    EXPECT_EQ(v.error().type, protocol::ProblemType::TooLarge);
    EXPECT_EQ(v.error().element, "line 1001");
    EXPECT_THAT(v.error().detail, HasSubstr("max_scene_vertices"));
}

}  // namespace
}  // namespace strata::assets::test
