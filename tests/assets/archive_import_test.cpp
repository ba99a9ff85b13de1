// A model and its side files in one tar archive (protocol/assets/archive_import.h): side files
// are found relative to the model's folder, a .gltf's external buffer and image are read from
// the archive, and an archive with no model or with two is refused naming them. The archives are
// written by GNU tar at test time.

#include <gmock/gmock.h>

#include "protocol/assets/archive_import.h"
#include "protocol/assets/asset_batch.h"
#include "tests/assets/asset_test_util.h"
#include "tests/assets/tar_test_util.h"

namespace strata::assets::test {
namespace {

using ::testing::HasSubstr;

const std::string QUAD_OBJ =
    "mtllib ../materials/quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\n"
    "v 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl painted\n"
    "f 1/1 2/2 3/3 4/4\n";
const std::string QUAD_MTL =
    "newmtl painted\nKd 0.8 0.4 0.2\nKs 0.5 0.5 0.5\nNs 100\n"
    "map_Kd ./textures/paint.png\n";

Imported<ArchiveAsset> import(const std::string& archive) {
    return import_archive(bytes_of(archive), "quad.tar", {});
}

TEST(ArchiveImport, AnObjFindsItsMtlAndTextureRelativeToItsFolder) {
    ScratchDir dir;
    dir.write("quad/models/quad.obj", QUAD_OBJ);
    dir.write("quad/materials/quad.mtl", QUAD_MTL);
    dir.write("quad/materials/textures/paint.png", "PNG bytes");
    dir.write("quad/README", "not a model");
    const std::string archive = run_tar(dir.path(), "", "quad");
    ASSERT_FALSE(archive.empty());
    auto r = import(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    EXPECT_EQ(r.value().model, "quad/models/quad.obj");
    EXPECT_EQ(r.value().format, AssetFormat::Obj);
    const Asset& a = r.value().asset;
    ASSERT_EQ(a.materials.size(), 1u);
    EXPECT_NEAR(a.materials[0].material.base_color.x, 0.8f, 1e-6f);
    EXPECT_LT(a.materials[0].material.roughness, 1.0f);  // Ks and Ns were read
    ASSERT_EQ(a.textures.size(), 1u);
    EXPECT_EQ(std::string(a.textures[0].bytes.begin(), a.textures[0].bytes.end()), "PNG bytes");
    EXPECT_TRUE(a.warnings.empty());
}

TEST(ArchiveImport, AMissingSideFileIsAWarningNotAFailure) {
    const std::string archive = tar_file("quad.obj", QUAD_OBJ) + tar_end();
    auto r = import(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    ASSERT_EQ(r.value().asset.warnings.size(), 1u);
    EXPECT_THAT(r.value().asset.warnings[0], HasSubstr("'../materials/quad.mtl'"));
}

TEST(ArchiveImport, AReferenceCannotClimbOutOfTheArchive) {
    // The model at the root names ../quad.mtl: no entry can be above the root.
    const std::string archive = tar_file("quad.obj",
                                         "mtllib ../quad.mtl\nv 0 0 0\nv 1 0 0\n"
                                         "v 0 1 0\nf 1 2 3\n") +
                                tar_file("quad.mtl", "newmtl a\nKd 1 0 0\n") + tar_end();
    auto r = import(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    EXPECT_TRUE(r.value().asset.materials.empty());
    EXPECT_EQ(r.value().asset.warnings.size(), 1u);
}

TEST(ArchiveImport, AGltfReadsItsExternalBufferAndImageFromTheArchive) {
    const std::string folder = STRATA_ASSIMP_MODELS_DIR "/glTF2/BoxTextured-glTF";
    if (read_file(folder + "/BoxTextured.gltf").empty()) GTEST_SKIP() << folder << " missing";
    const std::string archive = run_tar(folder, "--transform=s,^,box/,",
                                        "BoxTextured.gltf BoxTextured0.bin "
                                        "CesiumLogoFlat.png");
    ASSERT_FALSE(archive.empty());
    auto r = import(archive);
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    EXPECT_EQ(r.value().model, "box/BoxTextured.gltf");
    EXPECT_EQ(r.value().format, AssetFormat::Gltf);
    const Asset& a = r.value().asset;
    ASSERT_EQ(a.meshes.size(), 1u);
    EXPECT_EQ(a.meshes[0].triangles.size(), 12u);
    ASSERT_EQ(a.textures.size(), 1u);
    EXPECT_EQ(a.textures[0].bytes.size(), read_file(folder + "/CesiumLogoFlat.png").size());
    // The same model as the .glb, texture and all.
    auto glb = import_asset(AssetFormat::Glb,
                            bytes_of(read_file(STRATA_ASSIMP_MODELS_DIR
                                               "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb")),
                            "BoxTextured.glb", {});
    ASSERT_TRUE(glb.has_value());
    EXPECT_EQ(glb.value().meshes[0].positions, a.meshes[0].positions);
    EXPECT_EQ(glb.value().textures[0].bytes, a.textures[0].bytes);
}

TEST(ArchiveImport, AGltfWithoutItsBufferNamesTheArchiveTheModelAndTheFile) {
    const std::string folder = STRATA_ASSIMP_MODELS_DIR "/glTF2/BoxTextured-glTF";
    const std::string gltf = read_file(folder + "/BoxTextured.gltf");
    if (gltf.empty()) GTEST_SKIP() << folder << " missing";
    auto r = import(tar_file("BoxTextured.gltf", gltf) + tar_end());
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().file, "quad.tar: BoxTextured.gltf");
    EXPECT_THAT(r.error().detail,
                HasSubstr("'BoxTextured0.bin' refused: it is not part of the upload"));
}

TEST(ArchiveImport, AnArchiveWithoutAModelIsRefused) {
    auto r = import(tar_file("a.png", "x") + tar_file("b.mtl", "y") + tar_end());
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().file, "quad.tar");
    EXPECT_THAT(r.error().detail, HasSubstr("holds no model"));
    EXPECT_THAT(import(tar_end()).error().detail, HasSubstr("it is empty"));
}

TEST(ArchiveImport, AnArchiveWithTwoModelsIsRefusedNamingBoth) {
    auto r =
        import(tar_file("a/one.obj", "v 0 0 0\n") + tar_file("b/two.PLY", "ply\n") + tar_end());
    ASSERT_FALSE(r.has_value());
    EXPECT_THAT(r.error().detail, HasSubstr("holds 2 models ('a/one.obj', 'b/two.PLY')"));
}

TEST(ArchiveImport, AnImporterErrorNamesTheArchiveAndTheModel) {
    auto r = import(tar_file("m/bad.obj", "v 0 0 0\nf 1 2 9\n") + tar_end());
    ASSERT_FALSE(r.has_value());
    EXPECT_EQ(r.error().file, "quad.tar: m/bad.obj");
    EXPECT_EQ(r.error().element, "shape 0 face 0");
}

TEST(SideFiles, ReferencesAreNormalisedBeforeTheLookup) {
    const SideFiles files = {{"tex/a.png", "a"}, {"../up.png", "up"}};
    ASSERT_NE(find_side_file(files, "./tex//a.png"), nullptr);
    EXPECT_EQ(*find_side_file(files, "tex\\a.png"), "a");
    EXPECT_EQ(*find_side_file(files, "x/../tex/a.png"), "a");
    EXPECT_EQ(*find_side_file(files, "../up.png"), "up");
    EXPECT_EQ(find_side_file(files, "/tex/a.png"), nullptr);
    EXPECT_EQ(find_side_file(files, "C:/tex/a.png"), nullptr);
    EXPECT_EQ(find_side_file(files, ""), nullptr);
}

TEST(SideFiles, AReferenceNotFoundByItsPathFindsTheFileOfItsNameAtTheTop) {
    const SideFiles files = {{"tex/a.png", "a"}, {"SpiderTex.jpg", "spider"}};
    // An exporter's absolute Windows path (assimp's spider.fbx has these).
    ASSERT_NE(find_side_file(files, "D:\\projects\\models\\OBJ\\SpiderTex.jpg"), nullptr);
    EXPECT_EQ(*find_side_file(files, "D:\\projects\\models\\OBJ\\SpiderTex.jpg"), "spider");
    EXPECT_EQ(*find_side_file(files, "/home/artist/SpiderTex.jpg"), "spider");
    EXPECT_EQ(*find_side_file(files, "textures/SpiderTex.jpg"), "spider");
    // Only at the top, only by the whole name.
    EXPECT_EQ(find_side_file(files, "/elsewhere/a.png"), nullptr);
    EXPECT_EQ(find_side_file(files, "Tex.jpg"), nullptr);
    EXPECT_EQ(find_side_file(files, "dir/.."), nullptr);
    EXPECT_EQ(find_side_file(files, "../SpiderTex.jpg"), nullptr);
}

}  // namespace
}  // namespace strata::assets::test

namespace strata::assets::test {
namespace {

/// The first warning that contains `text`, or "" when none does.
std::string warning_with(const Asset& a, const std::string& text) {
    for (const std::string& w : a.warnings)
        if (w.find(text) != std::string::npos) return w;
    return {};
}

TEST(ArchiveImport, WhatAGltfHoldsAndStrataCannotCarryIsNamedNeverDropped) {
    const std::string folder = STRATA_ASSIMP_MODELS_DIR "/glTF2/ClearCoat-glTF";
    if (read_file(folder + "/ClearCoatTest.gltf").empty()) GTEST_SKIP() << folder << " missing";
    auto r = import(run_tar(folder, "", "."));
    ASSERT_TRUE(r.has_value()) << r.error().detail;
    const Asset& a = r.value().asset;
    EXPECT_NE(warning_with(a, "extensionsUsed: KHR_materials_clearcoat not imported"), "");
    EXPECT_NE(warning_with(a, "materials[1].extensions.KHR_materials_clearcoat not imported"), "");
    // Normal maps, alpha blending and emissive textures are imported, so nothing warns of them.
    EXPECT_EQ(warning_with(a, "normalTexture"), "");
    EXPECT_EQ(warning_with(a, "alphaMode"), "");
    EXPECT_EQ(warning_with(a, "emissiveTexture"), "");
    ASSERT_GT(a.materials.size(), 18u);
    EXPECT_GE(a.materials[9].texture(TextureSlot::Normal), 0);
    EXPECT_EQ(a.textures.at(std::size_t(a.materials[9].texture(TextureSlot::Normal))).color_space,
              TextureColorSpace::Linear);
    EXPECT_EQ(a.materials[5].material.alpha_mode, AlphaMode::Blend);
    EXPECT_GE(a.materials[5].texture(TextureSlot::BaseColor), 0);
    EXPECT_GE(a.materials[8].texture(TextureSlot::MetallicRoughness), 0);
    // The label plates: a white emissive factor times a texture of the label.
    EXPECT_EQ(a.materials[18].material.emission, Vec3(1.0f));
    EXPECT_GE(a.materials[18].texture(TextureSlot::Emissive), 0);
    EXPECT_EQ(a.textures.at(std::size_t(a.materials[18].texture(TextureSlot::Emissive))).color_space,
              TextureColorSpace::Srgb);

    const std::string transform = STRATA_ASSIMP_MODELS_DIR "/glTF2/textureTransform";
    auto t = import(run_tar(transform, "", "."));
    ASSERT_TRUE(t.has_value()) << t.error().detail;
    // KHR_texture_transform is read (baked into the texture coordinates): no warning of it.
    EXPECT_EQ(warning_with(t.value().asset, "KHR_texture_transform"), "");
}

}  // namespace
}  // namespace strata::assets::test
