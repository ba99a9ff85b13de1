// POST /v1/assets over real HTTP: formats from Content-Type or ?format=, the ids it answers,
// atomicity, If-Match, the budget, and problems that name the file and the element.

#include <fstream>
#include <sstream>

#include <gmock/gmock.h>

#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

using ::testing::HasSubstr;

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
    if (bunny.empty()) GTEST_SKIP() << STRATA_MODELS_DIR "/stanford-bunny.obj missing";
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
    expect_problem(upload("?format=fbx", TRIANGLE_OBJ, "model/obj"), 400, "invalid-request",
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

}  // namespace
}  // namespace strata::server::test
