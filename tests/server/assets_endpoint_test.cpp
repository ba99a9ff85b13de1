// POST /v1/assets over real HTTP: formats from Content-Type or ?format=, the ids it answers,
// atomicity, If-Match, the budget, and problems that name the file and the element; tar archives
// of a model and its side files (written by GNU tar at test time).

#include <fstream>
#include <sstream>

#include <gmock/gmock.h>

#include "engine/image/png.h"
#include "tests/assets/tar_test_util.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

using ::testing::HasSubstr;
using assets::test::run_tar;
using assets::test::ScratchDir;
using assets::test::tar_end;
using assets::test::tar_file;

const std::string TRIANGLE_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

class Assets : public ::testing::Test {
protected:
    Reply upload(const std::string& query, const std::string& body,
                 const std::string& content_type, const httplib::Headers& h = {}) {
        auto c = srv.client();
        return to_reply(c.Post(("/v1/assets" + query).c_str(), h, body, content_type.c_str()));
    }
    TestServer srv;
};

TEST_F(Assets, AnObjUploadAnswersItsIdsAndTheNewVersion) {
    const Reply r = upload("?prefix=tri", TRIANGLE_OBJ, "model/obj");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.header("ETag"), "\"1\"");
    const Json j = r.json();
    EXPECT_EQ(j["version"], 1);
    EXPECT_EQ(j["applied"], 3);  // the asset's group, its mesh, its instance
    EXPECT_EQ(j["format"], "obj");
    EXPECT_EQ(j["groups"], Json::array({"tri"}));
    EXPECT_EQ(j["meshes"], Json::array({"tri.mesh0"}));
    EXPECT_EQ(j["instances"], Json::array({"tri.node0"}));
    EXPECT_EQ(srv.get("/v1/scene/meshes/tri.mesh0").json()["triangles"], 1);
}

TEST_F(Assets, TheStanfordBunnyImportsAndRendersAsOneBatch) {
    const std::string bunny = read_file(STRATA_MODELS_DIR "/stanford-bunny.obj");
    ASSERT_FALSE(bunny.empty()) << STRATA_MODELS_DIR "/stanford-bunny.obj missing";
    const Reply r = upload("?name=stanford-bunny.obj", bunny, "application/octet-stream");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json()["meshes"], Json::array({"stanford-bunny.mesh0"}));
    const Json scene = srv.get("/v1/scene").json();
    EXPECT_EQ(scene["version"], 1);
    EXPECT_EQ(srv.get("/v1/scene/meshes/stanford-bunny.mesh0").json()["triangles"], 69451);
    EXPECT_EQ(srv.get("/v1/render?width=32&height=32").status, 200);
    EXPECT_EQ(srv.get("/v1/stats").json()["counters"]["batches_applied"], 1);
}

TEST_F(Assets, AGlbUploadSharesMeshesBetweenItsNodes) {
    const std::string glb = read_file(
        STRATA_ASSIMP_MODELS_DIR "/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
    if (glb.empty()) GTEST_SKIP() << "assimp-testmodels missing";
    const Reply r = upload("?prefix=engine", glb, "model/gltf-binary");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json()["meshes"].size(), 34u);
    EXPECT_EQ(r.json()["instances"].size(), 115u);
    const Json scene = srv.get("/v1/scene").json();
    EXPECT_EQ(scene["counts"]["meshes"], 34) << scene.dump();
    EXPECT_EQ(scene["counts"]["instances"], 115) << scene.dump();
}

TEST_F(Assets, FbxAndColladaFilesImportThroughAssimp) {
    const std::string fbx = read_file(STRATA_ASSIMP_MODELS_DIR "/FBX/spider.fbx");
    const std::string dae = read_file(STRATA_ASSIMP_MODELS_DIR "/Collada/duck.dae");
    if (fbx.empty() || dae.empty()) GTEST_SKIP() << "assimp-testmodels missing";
    const Reply spider = upload("?name=spider.fbx", fbx, "application/octet-stream");
    ASSERT_EQ(spider.status, 200) << spider.body;
    EXPECT_EQ(spider.json()["format"], "fbx");
    EXPECT_FALSE(spider.json()["meshes"].empty());
    EXPECT_TRUE(spider.json()["bounds"].is_object());
    const Reply duck = upload("?prefix=duck", dae, "model/vnd.collada+xml");
    ASSERT_EQ(duck.status, 200) << duck.body;
    EXPECT_EQ(duck.json()["format"], "dae");
    EXPECT_THAT(duck.json()["warnings"].dump(), HasSubstr("duckCM.tga"));
    EXPECT_EQ(srv.get("/v1/render?width=32&height=32&frame_group=duck").status, 200);
}

TEST_F(Assets, AnAsciiPlyIsReadWithTheFormatInTheQuery) {
    const std::string ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                            "property float y\nproperty float z\nelement face 1\n"
                            "property list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    const Reply r = upload("?format=ply&instance=false", ply, "text/plain");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json()["meshes"], Json::array({"upload.mesh0"}));
    EXPECT_EQ(r.json()["instances"], Json::array());
}

TEST_F(Assets, ABrokenFileIsA422NamingTheFileAndTheElementAndChangesNothing) {
    const Reply r = upload("?name=bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
                           "application/octet-stream");
    expect_problem(r, 422, "invalid-asset");
    const Json j = r.json();
    EXPECT_EQ(j["file"], "bad.obj");
    EXPECT_EQ(j["element"], "shape 0 face 0");
    EXPECT_THAT(j["detail"].get<std::string>(), HasSubstr("vertex index 7"));
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
    EXPECT_EQ(srv.get("/v1/stats").json()["counters"]["batches_applied"], 0);
}

TEST_F(Assets, AnUnknownFormatOrQueryIsA400) {
    expect_problem(upload("", TRIANGLE_OBJ, "application/octet-stream"), 400, "invalid-request");
    expect_problem(upload("?format=c4d", TRIANGLE_OBJ, "model/obj"), 400, "invalid-request",
                   "/format");
    expect_problem(upload("?format=obj&colour=red", TRIANGLE_OBJ, "model/obj"), 400,
                   "invalid-request", "/colour");
    expect_problem(upload("?format=obj&instance=maybe", TRIANGLE_OBJ, "model/obj"), 400,
                   "invalid-request", "/instance");
}

TEST_F(Assets, ASecondImportUnderTheSamePrefixIsRefusedAsADuplicate) {
    ASSERT_EQ(upload("?prefix=a", TRIANGLE_OBJ, "model/obj").status, 200);
    const Reply again = upload("?prefix=a", TRIANGLE_OBJ, "model/obj");
    expect_problem(again, 422, "duplicate-id");
    EXPECT_THAT(again.json()["detail"].get<std::string>(), HasSubstr("'a.mesh0'"));
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 1);
}

TEST_F(Assets, TheAssetsGroupJoinsTheGroupNamedByParent) {
    ASSERT_EQ(srv.edits({{{"op", "add_group"}, {"id", "shelf"}}}).status, 200);
    const Reply r = upload("?prefix=tri&parent=shelf", TRIANGLE_OBJ, "model/obj");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json()["groups"], Json::array({"tri"}));
    EXPECT_EQ(srv.get("/v1/scene/instances/tri.node0").json()["parent"], "tri");
    const Reply missing = upload("?prefix=b&parent=nowhere", TRIANGLE_OBJ, "model/obj");
    expect_problem(missing, 422, "unknown-id");
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 2);
}

TEST_F(Assets, IfMatchIsHonouredLikeEdits) {
    const Reply stale = upload("?format=obj", TRIANGLE_OBJ, "model/obj", {{"If-Match", "\"5\""}});
    expect_problem(stale, 412, "version-mismatch");
    EXPECT_EQ(stale.header("ETag"), "\"0\"");
    EXPECT_EQ(upload("?format=obj", TRIANGLE_OBJ, "model/obj", {{"If-Match", "\"0\""}}).status,
              200);
}

TEST_F(Assets, AnExternalBufferIsRefusedWithoutReadingTheServersFiles) {
    const std::string gltf =
        R"({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 4, "uri": "/etc/hostname"}]})";
    const Reply r = upload("", gltf, "model/gltf+json");
    expect_problem(r, 422, "invalid-asset");
    EXPECT_THAT(r.json()["detail"].get<std::string>(), HasSubstr("external file"));
}

/// An OBJ quad, its MTL (Kd, Ks/Ns, map_Kd) and a 2x2 PNG, as `tar` writes them.
std::string painted_quad_tar() {
    ScratchDir dir;
    dir.write("quad/quad.obj", "mtllib quad.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                               "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl painted\n"
                               "f 1/1 2/2 3/3 4/4\n");
    dir.write("quad/quad.mtl", "newmtl painted\nKd 0.8 0.4 0.2\nKs 0.5 0.5 0.5\nNs 100\n"
                               "map_Kd textures/paint.png\n");
    const uint8_t rgb[] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255};
    dir.write("quad/textures/paint.png", encode_png(rgb, 2, 2, 3).value());
    return run_tar(dir.path(), "", "quad");
}

TEST_F(Assets, AnObjMtlAndPngArchiveImportsWithTheTextureBoundToTheMaterial) {
    const std::string archive = painted_quad_tar();
    ASSERT_FALSE(archive.empty()) << "tar failed";
    const Reply r = upload("?name=quad.tar", archive, "application/x-tar");
    ASSERT_EQ(r.status, 200) << r.body;
    const Json j = r.json();
    EXPECT_EQ(j["format"], "obj");
    EXPECT_EQ(j["model"], "quad/quad.obj");
    EXPECT_EQ(j["textures"], Json::array({"quad.texture0"}));
    EXPECT_EQ(j["materials"], Json::array({"quad.material0"}));
    EXPECT_EQ(j["warnings"], Json::array());
    const Json list = srv.get("/v1/scene/textures").json();
    ASSERT_EQ(list["items"].size(), 1u);
    EXPECT_EQ(list["items"][0]["id"], "quad.texture0");
    const Json m = srv.get("/v1/scene/materials/quad.material0").json();
    EXPECT_EQ(m["base_color_texture"], "quad.texture0");
    EXPECT_LT(m["roughness"].get<double>(), 1.0);  // from Ks and Ns
    EXPECT_EQ(srv.get("/v1/stats").json()["counters"]["batches_applied"], 1);
}

TEST_F(Assets, AGltfWithItsExternalBinAndPngImportsAsATarAndRenders) {
    const std::string folder = STRATA_ASSIMP_MODELS_DIR "/glTF2/BoxTextured-glTF";
    const std::string archive =
        run_tar(folder, "", "BoxTextured.gltf BoxTextured0.bin CesiumLogoFlat.png");
    if (archive.empty()) GTEST_SKIP() << folder << " missing";
    const Reply r = upload("?format=tar", archive, "application/octet-stream");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json()["format"], "gltf");
    EXPECT_EQ(r.json()["textures"], Json::array({"BoxTextured.texture0"}));
    const Json material =
        srv.get("/v1/scene/materials/" + r.json()["materials"][0].get<std::string>()).json();
    EXPECT_EQ(material["base_color_texture"], "BoxTextured.texture0");
    EXPECT_EQ(srv.get("/v1/scene/textures/BoxTextured.texture0").json()["format"], "png");
    EXPECT_EQ(srv.get("/v1/render?width=32&height=32").status, 200);
}

TEST_F(Assets, ABrokenArchiveIsA422NamingTheArchiveAndTheEntryAndChangesNothing) {
    const Reply link = upload("?name=evil.tar",
                              tar_file("quad.obj", TRIANGLE_OBJ) +
                                  tar_file("../../etc/passwd", "root") + tar_end(),
                              "application/x-tar");
    expect_problem(link, 422, "invalid-asset");
    EXPECT_EQ(link.json()["file"], "evil.tar");
    EXPECT_EQ(link.json()["element"], "entry '../../etc/passwd'");
    const Reply two = upload("?format=tar",
                             tar_file("a.obj", TRIANGLE_OBJ) + tar_file("b.obj", TRIANGLE_OBJ) +
                                 tar_end(),
                             "application/x-tar");
    expect_problem(two, 422, "invalid-asset");
    EXPECT_THAT(two.json()["detail"].get<std::string>(),
                HasSubstr("upload.tar: the archive holds 2 models ('a.obj', 'b.obj')"));
    const Reply bad_model =
        upload("?format=tar", tar_file("m/bad.obj", "v 0 0 0\nf 1 2 7\n") + tar_end(), "");
    expect_problem(bad_model, 422, "invalid-asset");
    EXPECT_EQ(bad_model.json()["file"], "upload.tar: m/bad.obj");
    expect_problem(upload("?format=tar", "not a tar archive", ""), 422, "invalid-asset");
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
    EXPECT_EQ(srv.get("/v1/stats").json()["counters"]["batches_applied"], 0);
}

TEST_F(Assets, AnArchivesPrefixDefaultsToItsModelsStem) {
    const Reply r = upload("", tar_file("dir/tri.obj", TRIANGLE_OBJ) + tar_end(),
                           "application/x-tar; charset=binary");
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json()["meshes"], Json::array({"tri.mesh0"}));
    const Reply named = upload("?prefix=other&name=x.tar",
                               tar_file("tri.obj", TRIANGLE_OBJ) + tar_end(), "");
    ASSERT_EQ(named.status, 200) << named.body;
    EXPECT_EQ(named.json()["meshes"], Json::array({"other.mesh0"}));
}

}  // namespace
}  // namespace strata::server::test
