// The one-shot subcommands against a real server: what they print, what they write, their exit
// codes, and problem details shown as fields, never as raw JSON.

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "clients/cli/asset_pack.h"
#include "clients/cli/commands.h"
#include "clients/cli/http_transport.h"
#include "engine/image/png.h"
#include "tests/cli/fake_transport.h"
#include "tests/cli/server_transport.h"
#include "tests/server/test_server.h"

namespace strata::cli {
namespace {

using server::test::TestServer;

class Commands : public ::testing::Test {
protected:
    void SetUp() override {
        auto t = HttpTransport::create(test::options_for(srv));
        ASSERT_TRUE(t.has_value());
        transport = std::move(t.value());
        file = std::filesystem::temp_directory_path() /
               ("strata-commands-" +
                std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    }
    void TearDown() override { std::filesystem::remove(file); }

    Console console(bool json = false) { return Console{out, err, json}; }
    void write(const std::string& text) { std::ofstream(file) << text; }

    TestServer srv;
    std::unique_ptr<HttpTransport> transport;
    std::ostringstream out, err;
    std::filesystem::path file;
};

TEST_F(Commands, EditAppliesAFileAndPrintsTheVersion) {
    write(R"([{"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 8}},
              {"op": "add_instance", "id": "b0", "mesh": "ball"}])");
    EXPECT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    EXPECT_EQ(out.str(), "v1: 2 edits applied\n");
    write(R"({"edits": [{"op": "set_camera", "eye": [1, 2, 3]}]})");
    EXPECT_EQ(run_edit(*transport, console(true), file.string(), std::string("1")), 0);
    EXPECT_EQ(Json::parse(out.str().substr(out.str().find('\n') + 1)),
              (Json{{"version", 2}, {"applied", 1}}));
}

TEST_F(Commands, UndoRedoAndHistoryWalkTheVersions) {
    write(R"({"message": "a ball", "edits": [
              {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 8}},
              {"op": "add_instance", "id": "b0", "mesh": "ball"}]})");
    ASSERT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    write(R"([{"op": "remove_instance", "instance": "b0"}])");
    ASSERT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    out.str("");
    EXPECT_EQ(run_undo(*transport, console(), false, std::nullopt), 0);
    EXPECT_EQ(out.str(), "v3: undid v2 (1 edits applied)\n");
    EXPECT_EQ(run_undo(*transport, console(), false, std::string("\"3\"")), 0);
    EXPECT_EQ(run_undo(*transport, console(), true, std::nullopt), 0);
    EXPECT_EQ(transport->scene_object("instances", "b0").status, 200);
    out.str("");
    EXPECT_EQ(run_history(*transport, console(), HistoryArgs{2, std::nullopt}), 0);
    const std::string h = out.str();
    EXPECT_NE(h.find("v5  redo of v1  "), std::string::npos) << h;
    EXPECT_NE(h.find("v4  undo of v1  "), std::string::npos) << h;
    EXPECT_NE(h.find("v1  edit  "), std::string::npos) << h;
    EXPECT_NE(h.find("2 edits: add_instance 1, add_mesh 1  \"a ball\""), std::string::npos) << h;
    EXPECT_EQ(std::count(h.begin(), h.end(), '\n'), 5) << h;
    // Redoing v1 left the undo of v2 to redo.
    EXPECT_NE(err.str().find("version 5, 1 to undo, 1 to redo"), std::string::npos) << err.str();
    EXPECT_EQ(run_undo(*transport, console(), true, std::nullopt), 0);
    EXPECT_EQ(transport->scene_object("instances", "b0").status, 404);
    // Nothing left to redo: a 409 problem, exit code 3.
    EXPECT_EQ(run_undo(*transport, console(), true, std::nullopt), 3);
    EXPECT_NE(err.str().find("nothing-to-undo"), std::string::npos) << err.str();
}

TEST_F(Commands, ScenesAreListedMadeWorkedInAndDeleted) {
    EXPECT_EQ(run_scene_create(*transport, console(), {"lab", std::nullopt, std::nullopt, 5,
                                                        std::nullopt}),
              0);
    EXPECT_EQ(out.str(), "created lab  v0  0 meshes  0 instances  0 triangles\n");
    // --scene: every scene request goes to the named scene.
    HttpOptions in_lab = test::options_for(srv);
    in_lab.scene = "lab";
    auto lab = HttpTransport::create(in_lab);
    ASSERT_TRUE(lab.has_value());
    write(R"([{"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 8}},
              {"op": "add_instance", "id": "b0", "mesh": "ball"}])");
    EXPECT_EQ(run_edit(*lab.value(), console(), file.string(), std::nullopt), 0);
    EXPECT_EQ(transport->scene_object("instances", "b0").status, 404);
    EXPECT_EQ(lab.value()->scene_object("instances", "b0").status, 200);
    out.str("");
    EXPECT_EQ(run_scenes(*transport, console()), 0);
    EXPECT_EQ(out.str(),
              "default  v0  0 meshes  0 instances  0 triangles\n"
              "lab  v1  1 meshes  1 instances  48 triangles\n");
    // Its budget: a sixth instance is refused.
    write(R"([{"op": "add_instances", "mesh": "ball",
               "ids": {"prefix": "x", "first": 0, "count": 5}}])");
    EXPECT_EQ(run_edit(*lab.value(), console(), file.string(), std::nullopt), 3);
    EXPECT_EQ(run_scene_delete(*transport, console(), "default"), 3);
    EXPECT_NE(err.str().find("scene-conflict"), std::string::npos) << err.str();
    out.str("");
    EXPECT_EQ(run_scene_delete(*transport, console(), "lab"), 0);
    EXPECT_EQ(out.str(), "deleted lab\n");
    EXPECT_EQ(run_edit(*lab.value(), console(), file.string(), std::nullopt), 3);
    EXPECT_NE(err.str().find("no scene named 'lab'"), std::string::npos) << err.str();
}

TEST_F(Commands, ARefusedEditShowsTheProblemFieldsAndExitsWithThree) {
    write(R"([{"op": "add_instance", "id": "x", "mesh": "rock"}])");
    EXPECT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 3);
    const std::string e = err.str();
    EXPECT_NE(e.find("edit failed on http://127.0.0.1:"), std::string::npos) << e;
    EXPECT_NE(e.find("422 Unknown id"), std::string::npos) << e;
    EXPECT_NE(e.find("detail:     edit 0 (/edits/0/mesh): unknown mesh 'rock'"), std::string::npos)
        << e;
    EXPECT_NE(e.find("edit index: 0"), std::string::npos) << e;
    EXPECT_NE(e.find("pointer:    /edits/0/mesh"), std::string::npos) << e;
    EXPECT_NE(e.find("type:       https://strata.dev/problems/unknown-id"), std::string::npos);
    EXPECT_EQ(e.find("{\""), std::string::npos) << "raw JSON in: " << e;
}

TEST_F(Commands, AVersionMismatchIsA412Problem) {
    write("[]");
    EXPECT_EQ(run_edit(*transport, console(), file.string(), std::string("\"9\"")), 3);
    EXPECT_NE(err.str().find("412 Scene version mismatch"), std::string::npos) << err.str();
}

TEST_F(Commands, AMissingFileIsBadInput) {
    EXPECT_EQ(run_edit(*transport, console(), "/nonexistent/edits.json", std::nullopt), 2);
    EXPECT_NE(err.str().find("cannot open"), std::string::npos);
}

TEST_F(Commands, CommitAndPlanPrintReportsForPeopleOrAsJson) {
    write(R"([{"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 8}},
              {"op": "add_instance", "id": "b0", "mesh": "ball"}])");
    ASSERT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    out.str("");
    EXPECT_EQ(run_plan(*transport, console()), 0);
    EXPECT_EQ(out.str().rfind("plan for v1: tlas update (1 instances), 1 rebuilds, 0 refits, 48 "
                              "primitives built, 0 refit\n  rebuilt   ball  added  48 prims",
                              0),
              0u)
        << out.str();
    out.str("");
    EXPECT_EQ(run_commit(*transport, console()), 0);
    EXPECT_EQ(out.str().rfind("commit v1: tlas update (1 instances), 1 rebuilds", 0), 0u)
        << out.str();
    out.str("");
    EXPECT_EQ(run_commit(*transport, console(true)), 0);
    const Json report = Json::parse(out.str());
    EXPECT_EQ(report["tlas"]["action"], "none");
    EXPECT_EQ(report["version"], 1);
}

TEST_F(Commands, StatsAndScenePrintTheServersState) {
    EXPECT_EQ(run_stats(*transport, console()), 0);
    EXPECT_NE(out.str().find("version 0\n"), std::string::npos);
    EXPECT_NE(out.str().find("last commit: none yet"), std::string::npos);
    EXPECT_NE(out.str().find("  batches_applied    0\n"), std::string::npos) << out.str();
    out.str("");
    EXPECT_EQ(run_scene(*transport, console()), 0) << err.str();
    EXPECT_EQ(out.str().rfind("version    0\nmeshes     0\n", 0), 0u) << out.str();
    EXPECT_NE(out.str().find("\nlast       no commit yet\n"), std::string::npos) << out.str();
    out.str("");
    EXPECT_EQ(run_scene(*transport, console(true)), 0);
    EXPECT_EQ(Json::parse(out.str())["version"], 0);
}

TEST_F(Commands, StatsSayWhatCompactionSaved) {
    write(R"([{"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 32},
               "build": {"compact": true}}])");
    ASSERT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    EXPECT_EQ(run_stats(*transport, console()), 0);
    EXPECT_EQ(out.str().find("compaction"), std::string::npos) << "before any commit: " << out.str();
    ASSERT_EQ(run_commit(*transport, console()), 0);
    out.str("");
    EXPECT_EQ(run_stats(*transport, console()), 0);
    EXPECT_TRUE(std::regex_search(
        out.str(), std::regex("\ncompaction  1 meshes, blas [0-9]+ bytes at full size, "
                              "[0-9]+ compacted \\([0-9]+ saved\\)\n")))
        << out.str();
}

TEST_F(Commands, RenderWritesTheImageAndSaysWhatItsCommitDid) {
    RenderArgs args;
    args.out = file.string() + ".png";
    args.width = 40;
    args.height = 20;
    args.camera.eye = {0, 2, 6};
    EXPECT_EQ(run_render(*transport, console(), args), 0) << err.str();
    std::ifstream png(args.out, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(png)), {});
    EXPECT_EQ(bytes.substr(1, 3), "PNG");
    EXPECT_NE(out.str().find("wrote " + args.out), std::string::npos);
    EXPECT_NE(out.str().find("commit: v0 tlas=none(0)"), std::string::npos) << out.str();
    std::filesystem::remove(args.out);
}

TEST_F(Commands, ARenderFramesAGroupAndAnUnknownOneIsAProblem) {
    write(R"([{"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 8}},
              {"op": "add_group", "id": "far", "transform": {"translate": [90, 0, 0]}},
              {"op": "add_instance", "id": "b0", "mesh": "ball", "parent": "far"}])");
    ASSERT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    RenderArgs args;
    args.out = file.string() + ".png";
    args.width = 40;
    args.height = 20;
    args.frame_group = "far";
    EXPECT_EQ(run_render(*transport, console(), args), 0) << err.str();
    args.frame_group = "near";
    EXPECT_EQ(run_render(*transport, console(), args), 3);
    EXPECT_NE(err.str().find("422 Unknown id"), std::string::npos) << err.str();
    EXPECT_NE(err.str().find("pointer:    /frame/group"), std::string::npos) << err.str();
    std::filesystem::remove(args.out);
}

TEST_F(Commands, ARenderTheServerCannotMakeIsAProblem) {
    RenderArgs args;
    args.out = file.string() + ".png";
    args.width = 65536;
    args.height = 65536;
    EXPECT_EQ(run_render(*transport, console(), args), 3);
    EXPECT_NE(err.str().find("413 Content too large"), std::string::npos) << err.str();
    EXPECT_NE(err.str().find("pointer:    /width"), std::string::npos) << err.str();
    EXPECT_FALSE(std::filesystem::exists(args.out));
}

TEST(RenderBody, PassesEveryOptionAndTakesTheFormatFromTheFileName) {
    RenderArgs a;
    a.out = "frame.exr";
    a.width = 320;
    a.spp = 16;
    a.aovs = {"depth", "normal"};
    a.compression = "piz";
    a.exposure = -1;
    a.accumulate = true;
    a.filter = "atrous";
    a.split = 3;
    a.camera.eye = {1, 2, 3};
    a.camera.fov_y_deg = 30;
    a.time = 2.5;
    std::string error;
    const auto body = render_body(a, error);
    ASSERT_TRUE(body.has_value()) << error;
    EXPECT_EQ(Json::parse(*body), Json::parse(R"({"width": 320, "spp": 16, "format": "exr",
        "aovs": ["depth", "normal"], "compression": "piz", "exposure": -1, "accumulate": true,
        "filter": "atrous", "split": 3, "camera": {"eye": [1, 2, 3], "fov_y_deg": 30},
        "time": 2.5})"));
    a.format = "png";
    EXPECT_FALSE(render_body(a, error).has_value());
    EXPECT_NE(error.find("does not match"), std::string::npos);
    RenderArgs plain;
    plain.out = "frame.bin";
    EXPECT_EQ(Json::parse(*render_body(plain, error)), Json::object());
    plain.frame_group = "engine";
    EXPECT_EQ(Json::parse(*render_body(plain, error)),
              Json::parse(R"({"frame": {"group": "engine"}})"));
    plain.frame_instance = "engine.node0";
    EXPECT_FALSE(render_body(plain, error).has_value());
    EXPECT_EQ(error, "give --frame-group or --frame-instance, not both");
    plain.frame_group.reset();
    EXPECT_EQ(Json::parse(*render_body(plain, error)),
              Json::parse(R"({"frame": {"instance": "engine.node0"}})"));
}

TEST_F(Commands, SnapshotSaveThenLoadPutsTheSameSceneBackAsANewVersion) {
    write(R"([{"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 8}},
              {"op": "add_instance", "id": "b0", "mesh": "ball"}])");
    ASSERT_EQ(run_edit(*transport, console(), file.string(), std::nullopt), 0);
    const std::string before = srv.get("/v1/scene/instances/b0").json()["transform"].dump();
    EXPECT_EQ(run_snapshot_save(*transport, console(), file.string()), 0);
    EXPECT_NE(out.str().find("saved version 1"), std::string::npos) << out.str();
    EXPECT_FALSE(std::filesystem::exists(file.string() + ".tmp"));
    ASSERT_EQ(srv.edits({{{"op", "clear"}}}).status, 200);
    EXPECT_EQ(run_snapshot_load(*transport, console(), file.string()), 0);
    EXPECT_NE(out.str().find("the scene is now version 3"), std::string::npos) << out.str();
    EXPECT_EQ(srv.get("/v1/scene/instances/b0").json()["transform"].dump(), before);
}

TEST_F(Commands, SnapshotLoadOfAFileThatIsNotOneChangesNothing) {
    write("{\"edits\": []}");
    EXPECT_EQ(run_snapshot_load(*transport, console(), file.string()), 3);
    EXPECT_NE(err.str().find("not a Strata snapshot"), std::string::npos) << err.str();
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
}

}  // namespace
}  // namespace strata::cli

namespace strata::cli {
namespace {

class ImportCommand : public ::testing::Test {
protected:
    void SetUp() override {
        auto t = HttpTransport::create(test::options_for(srv));
        ASSERT_TRUE(t.has_value());
        transport = std::move(t.value());
        dir = std::filesystem::temp_directory_path() /
              ("strata-import-" +
               std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
        std::filesystem::create_directories(dir);
    }
    void TearDown() override { std::filesystem::remove_all(dir); }
    Console console(bool json = false) { return Console{out, err, json}; }

    server::test::TestServer srv;
    std::unique_ptr<HttpTransport> transport;
    std::ostringstream out, err;
    std::filesystem::path dir;
};

TEST_F(ImportCommand, ImportsAFileUnderItsStemOrAPrefixAndPrintsWhatItCreated) {
    const std::filesystem::path obj = dir / "tri.obj";
    std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    ImportArgs args;
    args.file = obj.string();
    EXPECT_EQ(run_import(*transport, console(), args), 0) << err.str();
    EXPECT_EQ(out.str(), "imported " + obj.string() +
                             ": 1 meshes, 0 materials, 1 groups, 1 instances; the scene is now "
                             "version 1\n");
    EXPECT_EQ(srv.get("/v1/scene/instances/tri.node0").status, 200);
    args.prefix = "second";
    args.instance = false;
    EXPECT_EQ(run_import(*transport, console(true), args), 0) << err.str();
    const Json doc = Json::parse(out.str().substr(out.str().find('\n') + 1));
    EXPECT_EQ(doc["meshes"], Json::array({"second.mesh0"}));
    EXPECT_EQ(doc["instances"], Json::array());
}

TEST_F(ImportCommand, AssetsAreListedShownReimportedAndDeleted) {
    const std::filesystem::path obj = dir / "tri.obj";
    std::ofstream(obj) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    ImportArgs args;
    args.file = obj.string();
    ASSERT_EQ(run_import(*transport, console(), args), 0) << err.str();
    out.str("");
    EXPECT_EQ(run_assets(*transport, console()), 0) << err.str();
    EXPECT_EQ(out.str(),
              "tri  tri.obj  1 meshes  0 materials  0 textures  1 groups  1 instances  "
              "[0.0,0.0,0.0]..[1.0,1.0,0.0]\n");
    out.str("");
    EXPECT_EQ(run_asset_show(*transport, console(), "tri"), 0) << err.str();
    EXPECT_NE(out.str().find("\n  meshes  tri.mesh0\n"), std::string::npos) << out.str();
    EXPECT_EQ(run_asset_show(*transport, console(), "nope"), 3);
    EXPECT_NE(err.str().find("404"), std::string::npos) << err.str();

    out.str("");
    ImportArgs again;
    again.file = obj.string();
    EXPECT_EQ(run_asset_reimport(*transport, console(), "tri", again), 0) << err.str();
    EXPECT_EQ(out.str(), "re-imported " + obj.string() +
                             " as asset tri: 1 meshes, 1 groups, 1 instances; kept unchanged 1 "
                             "meshes; removed 0; the scene is now version 2\n");
    out.str("");
    EXPECT_EQ(run_asset_delete(*transport, console(), "tri"), 0) << err.str();
    EXPECT_EQ(out.str(), "deleted asset tri: 1 meshes, 1 groups, 1 instances; the scene is now "
                         "version 3\n");
    EXPECT_EQ(srv.get("/v1/scene").json()["counts"]["meshes"], 0);
    EXPECT_EQ(run_asset_delete(*transport, console(), "tri"), 3);
}

TEST_F(ImportCommand, ARefusedFileShowsTheProblemAndExitsWithThree) {
    const std::filesystem::path ply = dir / "broken.ply";
    std::ofstream(ply) << "ply\nformat ascii 1.0\nelement vertex 1\n";
    ImportArgs args;
    args.file = ply.string();
    EXPECT_EQ(run_import(*transport, console(), args), 3);
    EXPECT_NE(err.str().find("422 Invalid asset"), std::string::npos) << err.str();
    EXPECT_NE(err.str().find("broken.ply: header"), std::string::npos) << err.str();
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
    args.file = (dir / "missing.obj").string();
    EXPECT_EQ(run_import(*transport, console(), args), 2);
}

/// Writes `bytes` to `dir`/`relative`, creating its folders.
void write_file(const std::filesystem::path& dir, const std::string& relative,
                const std::string& bytes) {
    std::filesystem::create_directories((dir / relative).parent_path());
    std::ofstream(dir / relative, std::ios::binary) << bytes;
}

TEST_F(ImportCommand, AnObjIsSentWithItsMtlAndImageAndTheTextureIsBound) {
    // The MTL in a sibling folder, its image relative to the MTL: the archive's root is the
    // folder above both.
    write_file(dir, "models/quad.obj",
               "mtllib ../materials/quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
               "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl painted\nf 1/1 2/2 3/3 4/4\n");
    write_file(dir, "materials/quad.mtl", "newmtl painted\nKd 0.8 0.4 0.2\nmap_Kd tex/p.png\n");
    const uint8_t rgb[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    write_file(dir, "materials/tex/p.png", encode_png(rgb, 2, 2, 3).value());
    ImportArgs args;
    args.file = (dir / "models" / "quad.obj").string();
    ASSERT_EQ(run_import(*transport, console(), args), 0) << err.str();
    EXPECT_NE(err.str().find("packing materials/tex/p.png with models/quad.obj"),
              std::string::npos)
        << err.str();
    EXPECT_EQ(srv.get("/v1/scene/materials/quad.material0").json()["base_color_texture"],
              "quad.texture0");
    EXPECT_EQ(srv.get("/v1/scene/textures").json()["items"].size(), 1u);
}

TEST_F(ImportCommand, AGltfDirectoryIsSentWithItsBufferAndImage) {
    const std::string gltf = STRATA_ASSIMP_MODELS_DIR "/glTF2/BoxTextured-glTF/BoxTextured.gltf";
    if (!std::filesystem::exists(gltf)) GTEST_SKIP() << gltf << " missing";
    ImportArgs args;
    args.file = gltf;
    ASSERT_EQ(run_import(*transport, console(true), args), 0) << err.str();
    const Json doc = Json::parse(out.str());
    EXPECT_EQ(doc["format"], "gltf");
    EXPECT_EQ(doc["model"], "BoxTextured.gltf");
    EXPECT_EQ(doc["textures"], Json::array({"BoxTextured.texture0"}));
    EXPECT_EQ(srv.get("/v1/scene/textures/BoxTextured.texture0").json()["format"], "png");
}

TEST_F(ImportCommand, AMissingSideFileStopsTheImportBeforeAnythingIsSent) {
    write_file(dir, "quad.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    ImportArgs args;
    args.file = (dir / "quad.obj").string();
    EXPECT_EQ(run_import(*transport, console(), args), 2);
    EXPECT_NE(err.str().find("quad.obj (mtllib) names 'gone.mtl', which is not a readable file"),
              std::string::npos)
        << err.str();
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
}

TEST_F(ImportCommand, AModelCannotMakeTheUploadCarryAnyLocalFile) {
    write_file(dir, "secret.txt", "password");
    write_file(dir, "models/quad.obj", "mtllib ../secret.txt\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    ImportArgs args;
    args.file = (dir / "models" / "quad.obj").string();
    EXPECT_EQ(run_import(*transport, console(), args), 2);
    EXPECT_NE(err.str().find("outside the model's folder only .mtl, .bin, .png and .jpg files"),
              std::string::npos)
        << err.str();
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
}

TEST(AssetPack, LongNamesWrittenByOurTarWriterAreReadBackByGnuTar) {
    const std::string long_name = std::string(120, 'd') + "/" + std::string(90, 'f') + ".png";
    const std::string longer = std::string(300, 'e') + ".bin";
    const std::string archive =
        write_tar({{"a.obj", "v"}, {long_name, "png"}, {longer, "bin"}});
    const auto scratch = std::filesystem::temp_directory_path() / "strata-asset-pack-test.tar";
    std::ofstream(scratch, std::ios::binary) << archive;
    FILE* pipe = popen(("tar tf '" + scratch.string() + "'").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string listing;
    char buffer[4096];
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;)
        listing.append(buffer, n);
    EXPECT_EQ(pclose(pipe), 0);
    std::filesystem::remove(scratch);
    EXPECT_EQ(listing, "a.obj\n" + long_name + "\n" + longer + "\n");
}

}  // namespace
}  // namespace strata::cli

namespace strata::cli {
namespace {

/// The subcommands against the fake transport: the exact requests they send and lines they print.
class FakeCommands : public ::testing::Test {
protected:
    Console console(bool json = false) { return Console{out, err, json}; }

    test::FakeTransport fake;
    std::ostringstream out, err;
};

TEST_F(FakeCommands, RenderSendsFilterAndSplit) {
    RenderArgs args;
    args.out = (std::filesystem::temp_directory_path() / "strata-fake-render.png").string();
    args.height = 90;
    args.filter = "none";
    args.split = 2;
    ASSERT_EQ(run_render(fake, console(), args), 0) << err.str();
    std::filesystem::remove(args.out);
    ASSERT_EQ(fake.render_bodies.size(), 1u);
    EXPECT_EQ(fake.render_bodies[0],
              Json::parse(R"({"height": 90, "format": "png", "filter": "none", "split": 2})"));
}

TEST_F(FakeCommands, PickSendsTheCameraOverrideAndTimeOnlyWhenGiven) {
    PickArgs args;
    args.x = 3;
    args.y = 4;
    args.width = 64;
    args.height = 48;
    ASSERT_EQ(run_pick(fake, console(), args), 0) << err.str();
    args.camera.target = {0, 1, 0};
    args.camera.fov_y_deg = 20;
    args.time = 0.5;
    ASSERT_EQ(run_pick(fake, console(), args), 0) << err.str();
    ASSERT_EQ(fake.pick_bodies.size(), 2u);
    EXPECT_EQ(fake.pick_bodies[0],
              Json::parse(R"({"width": 64, "height": 48, "pixels": [[3, 4]]})"));
    EXPECT_EQ(fake.pick_bodies[1]["camera"],
              Json::parse(R"({"target": [0, 1, 0], "fov_y_deg": 20})"));
    EXPECT_EQ(fake.pick_bodies[1]["time"], 0.5);
    EXPECT_EQ(out.str(), "nothing at (3, 4) at version 0\nnothing at (3, 4) at version 0\n");
}

TEST_F(FakeCommands, SceneSummarisesTheSceneAndStatsDocumentsInElevenLines) {
    fake.scene_doc = Json::parse(R"({"version": 7,
        "counts": {"meshes": 6, "instances": 19, "materials": 8, "groups": 1, "lights": 2,
                   "textures": 1, "triangles": 39388, "instanced_triangles": 94852},
        "bounds": {"min": [-200, 0, -200], "max": [200, 4.8, 200]},
        "camera": {"eye": [0, 4, 11], "target": [0, 1, 0.5], "up": [0, 1, 0], "fov_y_deg": 45},
        "lighting": {"sun_direction": [0.55, 0.6, 0.4], "sky_intensity": 0.9}})");
    fake.memory_bytes = {{"blas", 5077468}, {"tlas", 4480}};
    fake.last = Json::parse(R"({"version": 7, "planned": false,
        "tlas": {"action": "update", "instances": 19}, "blas_rebuilds": 6, "blas_refits": 0,
        "primitives_built": 39388, "primitives_refit": 0, "ms": 26.021661,
        "rebuilt": [{"mesh": "ball", "reason": "added", "primitives": 25280}]})");
    ASSERT_EQ(run_scene(fake, console()), 0) << err.str();
    const std::string printed =
        "version    7\n"
        "meshes     6\n"
        "instances  19\n"
        "materials  8\n"
        "groups     1\n"
        "lights     2\n"
        "textures   1\n"
        "triangles  39388 in meshes, 94852 in visible instances\n"
        "memory     blas 4.8 MiB, tlas 4.4 KiB\n"
        "camera     eye 0,4,11  target 0,1,0.5  fov 45\n"
        "last       commit v7: tlas update (19 instances), 6 rebuilds, 0 refits, 39388 "
        "primitives built, 0 refit, 26.022 ms\n";
    EXPECT_EQ(out.str(), printed);
    // clients/cli/README.md shows these lines as what `strata scene` prints.
    std::ifstream readme(STRATA_SOURCE_DIR "/clients/cli/README.md");
    const std::string text((std::istreambuf_iterator<char>(readme)), {});
    EXPECT_NE(text.find("```\n" + printed + "```\n"), std::string::npos)
        << "clients/cli/README.md does not show:\n"
        << printed;
}

TEST_F(FakeCommands, SceneWithJsonPrintsTheWholeDocumentAndAsksForNoStats) {
    fake.scene_doc = {{"version", 3}, {"counts", {{"meshes", 1}}}, {"bounds", nullptr}};
    ASSERT_EQ(run_scene(fake, console(true)), 0) << err.str();
    EXPECT_EQ(Json::parse(out.str()), fake.scene_doc);
    EXPECT_EQ(fake.stats_calls, 0);
}

}  // namespace
}  // namespace strata::cli
