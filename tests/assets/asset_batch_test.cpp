// The asset as one engine batch: shared meshes stay shared in the scene (one BLAS, many
// instances), world transforms are composed, the batch is atomic, and what the scene cannot hold
// yet is named.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "engine/engine.h"
#include "protocol/assets/asset_batch.h"
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
    ASSERT_TRUE(asset.has_value()) << asset.error().describe();
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"engine", true});
    EXPECT_EQ(b.meshes.size(), 34u);
    EXPECT_EQ(b.instances.size(), 115u);
    EXPECT_EQ(b.materials.size(), 34u);

    auto engine = make_engine();
    auto applied = engine->apply(std::move(b.batch));
    ASSERT_TRUE(applied.has_value()) << applied.error().describe();
    auto report = engine->commit();
    ASSERT_TRUE(report.has_value()) << report.error().describe();
    EXPECT_EQ(report.value().rebuilt.size(), 34u);  // one BLAS per mesh, not per instance
    engine->read([](const Scene& s) {
        const SceneCounts c = s.counts();
        EXPECT_EQ(c.meshes, 34u);
        EXPECT_EQ(c.instances, 115u);
        std::size_t most = 0;
        s.meshes().for_each([&](auto, const MeshRecord& m) { most = std::max(most, m.users.size()); });
        EXPECT_EQ(most, 20u);
        EXPECT_GT(c.instanced_triangles, c.triangles);
    });
}

TEST(AssetBatch, InstancesCarryTheComposedWorldTransform) {
    const std::string nodes = R"([
      {"children": [1], "translation": [10, 0, 0]},
      {"mesh": 0, "translation": [0, 5, 0], "scale": [3, 3, 3]}])";
    auto asset = import_text(AssetFormat::Gltf, triangle_gltf(nodes));
    ASSERT_TRUE(asset.has_value()) << asset.error().describe();
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"t", true});
    ASSERT_EQ(b.instances, std::vector<std::string>{"t.node1"});
    auto engine = make_engine();
    ASSERT_TRUE(engine->apply(std::move(b.batch)).has_value());
    engine->read([](const Scene& s) {
        const InstanceRecord* inst = s.instance(s.find_instance("t.node1")).value();
        EXPECT_EQ(inst->transform.transform_point(Vec3(1, 0, 0)), Vec3(13, 5, 0));
    });
}

TEST(AssetBatch, ANodeTheSceneCannotPlaceIsLeftOutWithAWarning) {
    auto asset = import_text(AssetFormat::Gltf,
                             triangle_gltf(R"([{"mesh": 0, "scale": [0, 0, 0]}])"));
    ASSERT_TRUE(asset.has_value()) << asset.error().describe();
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"z", true});
    EXPECT_TRUE(b.instances.empty());
    EXPECT_EQ(b.meshes.size(), 1u);
    ASSERT_FALSE(b.warnings.empty());
    EXPECT_THAT(b.warnings.back(), HasSubstr("node 0 not placed"));
}

TEST(AssetBatch, WithoutInstancingOnlyMeshesAndMaterialsAreCreated) {
    auto asset = import_text(AssetFormat::Gltf, triangle_gltf(R"([{"mesh": 0}])"));
    ASSERT_TRUE(asset.has_value());
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"m", false});
    EXPECT_EQ(b.meshes, std::vector<std::string>{"m.mesh0"});
    EXPECT_TRUE(b.instances.empty());
    EXPECT_EQ(b.batch.edits.size(), 1u);
}

TEST(AssetBatch, ImportingTwiceUnderOnePrefixIsRefusedAndChangesNothing) {
    auto engine = make_engine();
    for (int round = 0; round < 2; ++round) {
        auto asset = import_text(AssetFormat::Obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        ASSERT_TRUE(asset.has_value());
        AssetBatch b = asset_to_batch(std::move(asset.value()), {"dup", true});
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

TEST(AssetBatch, AttributesTheSceneCannotHoldYetAreNamedInTheWarnings) {
    const std::string glb = read_file(std::string(STRATA_ASSIMP_MODELS_DIR) +
                                      "/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb");
    if (glb.empty()) GTEST_SKIP() << "assimp-testmodels missing";
    auto asset = import_asset(AssetFormat::Glb, bytes_of(glb), "box.glb", {});
    ASSERT_TRUE(asset.has_value()) << asset.error().describe();
    AssetBatch b = asset_to_batch(std::move(asset.value()), {"box", true});
    EXPECT_THAT(b.warnings, Contains(HasSubstr("vertex normals dropped")));
    EXPECT_THAT(b.warnings, Contains(HasSubstr("texture coordinates dropped")));
    EXPECT_THAT(b.warnings, Contains(HasSubstr("texture reference(s) dropped")));
}

}  // namespace
}  // namespace strata::assets::test
