// Imported models against stored reference images, compared with a tolerance (as the demo's
// reference test does): Spot, the bunny and the multi-node 2CylinderEngine, an FBX spider and a
// COLLADA duck read through assimp, each framed by a camera computed from its world bounds;
// glTF's ClearCoat test model with its normal maps, emissive labels and blended coating; and
// BoxTextured, whose embedded PNG must show, also
// when it comes as a .gltf with its external .bin and PNG in a tar archive (that .gltf's sampler
// mirrors the texture where the .glb's repeats it, hence its own reference frame).
//
// Regenerate after an intended change of the renderer or the importers, then look at them:
//   STRATA_UPDATE_REFERENCE=1 ctest --test-dir build -R AssetReferenceImage
// A mismatch writes the frame it got to <name>_actual.png in the working directory.

#include <gtest/gtest.h>

#include "protocol/assets/archive_import.h"
#include "protocol/assets/asset_batch.h"
#include "tests/assets/asset_test_util.h"
#include "tests/assets/tar_test_util.h"
#include "tests/engine/reference_image.h"
#include "tests/engine/render_test_util.h"

namespace strata::assets::test {
namespace {

constexpr uint32_t WIDTH = 240, HEIGHT = 180, SPP = 8;

/// Frames an imported asset and compares the frame with data/<name>.png. Returns the ids of the
/// textures the import created.
std::vector<std::string> check_reference(Imported<Asset> asset, const std::string& name) {
    EXPECT_TRUE(asset.has_value()) << asset.error().detail;
    if (!asset) return {};
    AssetBatch b = asset_to_batch(std::move(asset.value()), {name, true});
    const std::vector<std::string> textures = b.textures;
    auto engine = strata::test::engine_with(std::move(b.batch));
    const Bounds3 box = engine->read([](const Scene& s) { return s.world_bounds(); });
    EXPECT_FALSE(box.empty());
    const float size = glm::length(box.extent());
    SetCamera cam;
    cam.target = box.center();
    cam.eye = box.center() + glm::normalize(Vec3(0.6f, 0.45f, 1.0f)) * (1.4f * size);
    cam.fov_y_deg = 40.0f;
    EditBatch view;
    view.edits.emplace_back(cam);
    EXPECT_TRUE(engine->apply(std::move(view)).has_value());
    const EncodedFrame image = strata::test::render_ok(
        *engine, strata::test::request(WIDTH, HEIGHT, SPP, {}, ImageFormat::Png));
    strata::test::expect_matches_reference(STRATA_ASSET_TEST_DATA_DIR, name, image, WIDTH, HEIGHT);
    return textures;
}

/// Imports `path` as `format` and checks it against data/<name>.png.
std::vector<std::string> check_reference(const std::string& path, AssetFormat format,
                                         const std::string& name) {
    const std::string bytes = read_file(path);
    if (bytes.empty()) {
        ADD_FAILURE() << path << " missing";
        return {};
    }
    return check_reference(import_asset(format, bytes_of(bytes), name, {}), name);
}

TEST(AssetReferenceImage, SpotMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_MODELS_DIR) + "/spot.obj", AssetFormat::Obj, "spot");
}

TEST(AssetReferenceImage, TheBunnyMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_MODELS_DIR) + "/stanford-bunny.obj", AssetFormat::Obj,
                    "bunny");
}

TEST(AssetReferenceImage, TwoCylinderEngineMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_ASSIMP_MODELS_DIR) +
                        "/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
                    AssetFormat::Glb, "engine");
}

TEST(AssetReferenceImage, AnFbxFileReadThroughAssimpMatchesTheStoredFrame) {
    check_reference(std::string(STRATA_ASSIMP_MODELS_DIR) + "/FBX/spider.fbx", AssetFormat::Fbx,
                    "spider-fbx");
}

TEST(AssetReferenceImage, AColladaFileReadThroughAssimpMatchesTheStoredFrame) {
    // Its texture (duckCM.tga) is not part of the upload: the duck shows its material's colour.
    check_reference(std::string(STRATA_ASSIMP_MODELS_DIR) + "/Collada/duck.dae", AssetFormat::Dae,
                    "duck-dae");
}

TEST(AssetReferenceImage, TheDracoCompressedEngineMatchesTheUncompressedOnesFrame) {
    // The same model as above, its 34 primitives compressed with Draco (KHR_draco_mesh_
    // compression, positions and normals quantised): it must look like the uncompressed file.
    const std::string dir = std::string(STRATA_ASSIMP_MODELS_DIR) + "/glTF2/draco/";
    const std::string gltf = read_file(dir + "2CylinderEngine.gltf");
    const SideFiles side{{"2CylinderEngine.bin", read_file(dir + "2CylinderEngine.bin")}};
    ASSERT_FALSE(gltf.empty() || side.begin()->second.empty());
    check_reference(import_asset(AssetFormat::Gltf, bytes_of(gltf), "engine", {}, side), "engine");
}

TEST(AssetReferenceImage, TextureTransformsShowTheCorrectTextures) {
    // KHR_texture_transform's test model: each plane is right when it shows the arrow pattern,
    // and its "not supported" fallback would show otherwise.
    const std::string dir = std::string(STRATA_ASSIMP_MODELS_DIR) + "/glTF2/textureTransform/";
    const std::string gltf = read_file(dir + "TextureTransformTest.gltf");
    SideFiles side;
    for (const char* f : {"TextureTransformTest.bin", "Arrow.png", "UV.png", "Correct.png",
                          "NotSupported.png", "Error.png"})
        side[f] = read_file(dir + f);
    ASSERT_FALSE(gltf.empty()) << dir << " missing";
    auto asset = import_asset(AssetFormat::Gltf, bytes_of(gltf), "transform", {}, side);
    ASSERT_TRUE(asset.has_value()) << asset.error().detail;
    for (const std::string& w : asset.value().warnings)
        EXPECT_EQ(w.find("KHR_texture_transform"), std::string::npos) << w;
    check_reference(std::move(asset), "texture_transform");
}

TEST(AssetReferenceImage, ClearCoatShowsItsNormalMapsLabelsAndBlendedCoating) {
    // KHR_materials_clearcoat's test model, read without its extension (a warning says so): the
    // rows show normal maps (ribs, plastic wrap), a roughness-striped metallic-roughness texture
    // and an alpha-blended partial coating, and the label plates glow only where their emissive
    // texture has letters.
    const std::string folder = std::string(STRATA_ASSIMP_MODELS_DIR) + "/glTF2/ClearCoat-glTF";
    const std::string archive = run_tar(folder, "", ".");
    ASSERT_FALSE(archive.empty()) << folder << " missing, or tar failed";
    auto imported = import_archive(bytes_of(archive), "clearcoat.tar", {});
    ASSERT_TRUE(imported.has_value()) << imported.error().detail;
    for (const std::string& w : imported.value().asset.warnings) {
        EXPECT_EQ(w.find("normalTexture"), std::string::npos) << w;
        EXPECT_EQ(w.find("emissiveTexture"), std::string::npos) << w;
    }
    check_reference(std::move(imported.value().asset), "clearcoat");
}

TEST(AssetReferenceImage, BoxTexturedShowsItsEmbeddedTexture) {
    const auto textures = check_reference(
        std::string(STRATA_ASSIMP_MODELS_DIR) + "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb",
        AssetFormat::Glb, "box_textured");
    EXPECT_EQ(textures, std::vector<std::string>{"box_textured.texture0"});
}

TEST(AssetReferenceImage, BoxTexturedFromATarOfItsGltfBinAndPngShowsItsExternalTexture) {
    const std::string folder = std::string(STRATA_ASSIMP_MODELS_DIR) + "/glTF2/BoxTextured-glTF";
    const std::string archive =
        run_tar(folder, "", "BoxTextured.gltf BoxTextured0.bin CesiumLogoFlat.png");
    ASSERT_FALSE(archive.empty()) << folder << " missing, or tar failed";
    auto imported = import_archive(bytes_of(archive), "box_textured_gltf.tar", {});
    ASSERT_TRUE(imported.has_value()) << imported.error().detail;
    const auto textures = check_reference(std::move(imported.value().asset), "box_textured_gltf");
    EXPECT_EQ(textures, std::vector<std::string>{"box_textured_gltf.texture0"});
}

}  // namespace
}  // namespace strata::assets::test
