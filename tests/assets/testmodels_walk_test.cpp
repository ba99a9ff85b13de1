// Every file of Debian's assimp-testmodels that an importer is pointed at by its extension
// (glb, gltf, obj, ply), the broken ones of invalid/ and the odd ones included: each either
// imports and applies to a scene as one batch, or is refused with a named error. Never a crash,
// never a partial scene. MTL files next to an OBJ are given as its upload, as a client would.

#include <filesystem>

#include <gtest/gtest.h>

#include "engine/engine.h"
#include "protocol/assets/asset_batch.h"
#include "tests/assets/asset_test_util.h"

namespace strata::assets::test {
namespace {

namespace fs = std::filesystem;

TEST(AssimpTestModels, EveryFileImportsOrIsRefusedCleanly) {
    const fs::path root = STRATA_ASSIMP_MODELS_DIR;
    if (!fs::is_directory(root)) GTEST_SKIP() << root << " missing: install assimp-testmodels";
    std::size_t imported = 0, refused = 0;
    for (const auto& entry : fs::recursive_directory_iterator(root)) {
        if (!entry.is_regular_file()) continue;
        std::string ext = entry.path().extension().string();
        if (!ext.empty()) ext.erase(0, 1);
        const auto format = format_from_name(ext);
        if (!format) continue;
        const std::string name = fs::relative(entry.path(), root).string();
        SCOPED_TRACE(name);
        const std::string bytes = read_file(entry.path().string());
        SideFiles side;
        if (*format == AssetFormat::Obj)
            for (const auto& sibling : fs::directory_iterator(entry.path().parent_path()))
                if (sibling.path().extension() == ".mtl")
                    side[sibling.path().filename().string()] = read_file(sibling.path().string());
        auto asset = import_asset(*format, bytes_of(bytes), name, {}, side);
        if (!asset) {
            ++refused;
            EXPECT_EQ(asset.error().file, name);
            EXPECT_FALSE(asset.error().detail.empty());
            continue;
        }
        AssetBatch b = asset_to_batch(std::move(asset.value()), {"t", true});
        auto engine = Engine::create();
        ASSERT_TRUE(engine.has_value());
        auto applied = engine.value()->apply(std::move(b.batch));
        ASSERT_TRUE(applied.has_value()) << applied.error().describe();
        auto report = engine.value()->commit();
        ASSERT_TRUE(report.has_value()) << report.error().describe();
        ++imported;
    }
    std::printf("assimp-testmodels: %zu imported, %zu refused\n", imported, refused);
    EXPECT_GT(imported, 20u);
    EXPECT_GT(refused, 10u);
}

TEST(AssimpTestModels, TheEmptyAndOutOfRangeFilesOfTheInvalidFolderAreRefused) {
    const fs::path dir = fs::path(STRATA_ASSIMP_MODELS_DIR) / "invalid";
    if (!fs::is_directory(dir)) GTEST_SKIP() << dir << " missing";
    // malformed2.obj only has an empty `f` line and an unknown material besides valid faces: the
    // walk above covers it (it imports, with the built-in material).
    for (const char* name : {"empty.obj", "empty.ply", "malformed.obj"}) {
        const std::string bytes = read_file((dir / name).string());
        const auto format =
            std::string(name).ends_with(".ply") ? AssetFormat::Ply : AssetFormat::Obj;
        auto a = import_asset(format, bytes_of(bytes), name, {});
        EXPECT_FALSE(a.has_value()) << name;
        if (!a.has_value()) {
            EXPECT_EQ(a.error().file, name);
        }
    }
}

}  // namespace
}  // namespace strata::assets::test
