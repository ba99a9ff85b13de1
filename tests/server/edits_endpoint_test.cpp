// POST /v1/edits over real HTTP: every op, atomicity, If-Match and every error status.

#include <gmock/gmock.h>

#include "protocol/base64.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

class Edits : public ::testing::Test {
protected:
    TestServer srv;
};

TEST_F(Edits, ABatchAnswersTheNewVersionAndTheCountWithAnETag) {
    const Reply r =
        srv.edits({triangle_mesh("tri"), {{"op", "add_instance"}, {"id", "a"}, {"mesh", "tri"}}});
    ASSERT_EQ(r.status, 200) << r.body;
    EXPECT_EQ(r.json(), (Json{{"version", 1}, {"applied", 2}}));
    EXPECT_EQ(r.header("ETag"), "\"1\"");
    EXPECT_EQ(r.header("Content-Type"), "application/json");
}

TEST_F(Edits, AnswersAndProblemsAreOneLineOfJsonEndingWithANewline) {
    // What curl prints then ends its line, and JSON Lines tools read the body as one record.
    const Reply ok = srv.edits({triangle_mesh("tri")});
    const Reply refused = srv.edits({{{"op", "remove_mesh"}, {"mesh", "nothing"}}});
    const Reply malformed = srv.post("/v1/edits", std::string("{\"edits\": ["));
    const Reply commit = srv.post("/v1/commit", std::string());
    const Reply stats = srv.get("/v1/stats");
    const Reply missing = srv.get("/v1/no-such-route");
    for (const Reply* r : {&ok, &refused, &malformed, &commit, &stats, &missing}) {
        ASSERT_FALSE(r->body.empty());
        EXPECT_EQ(r->body.back(), '\n') << r->body;
        EXPECT_EQ(r->body.find('\n'), r->body.size() - 1) << r->body;
        EXPECT_FALSE(Json::parse(r->body, nullptr, false).is_discarded()) << r->body;
    }
    EXPECT_EQ(ok.body, "{\"applied\":1,\"version\":1}\n");
    EXPECT_EQ(refused.status, 422);
    EXPECT_EQ(malformed.status, 400);
    EXPECT_EQ(missing.status, 404);
}

TEST_F(Edits, EveryOpLandsInTheScene) {
    const float moved[3] = {0.0f, 0.0f, 2.0f};
    const Json ops = Json::array({
        {{"op", "add_material"},
         {"id", "red"},
         {"base_color", {1, 0, 0}},
         {"roughness", 0.3},
         {"metallic", 0},
         {"emission", {0, 0, 0}}},
        {{"op", "add_mesh"},
         {"id", "ball"},
         {"shape", {{"type", "sphere"}, {"radius", 1}, {"segments", 8}}},
         {"build", {{"prefer", "fast_build"}}}},
        triangle_mesh("tri"),
        {{"op", "update_mesh"},
         {"mesh", "tri"},
         {"positions_b64",
          protocol::encode_base64(std::string_view(reinterpret_cast<const char*>(moved), 12))},
         {"offset", 2}},
        {{"op", "update_material"}, {"material", "red"}, {"roughness", 0.9}},
        {{"op", "add_instance"},
         {"id", "a"},
         {"mesh", "ball"},
         {"material", "red"},
         {"transform", {{"translate", {1, 2, 3}}}},
         {"mask", 3}},
        {{"op", "add_instance"}, {"id", "b"}, {"mesh", "tri"}},
        {{"op", "update_instance"},
         {"instance", "a"},
         {"material", nullptr},
         {"visible", false},
         {"user_id", 4}},
        {{"op", "set_transform"},
         {"instance", "b"},
         {"transform", {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0}}},
        {{"op", "mark_dirty"}, {"target", {{"mesh", "ball"}}}, {"action", "rebuild"}},
        {{"op", "mark_dirty"}, {"target", "tlas"}, {"action", "refit"}},
        {{"op", "set_camera"}, {"eye", {0, 2, 9}}, {"fov_y_deg", 40}},
        {{"op", "set_lighting"}, {"sky_intensity", 0.25}},
        {{"op", "add_mesh"}, {"id", "gone"}, {"shape", {{"type", "box"}}}},
        {{"op", "add_instance"}, {"id", "gone0"}, {"mesh", "gone"}},
        {{"op", "remove_instance"}, {"instance", "gone0"}},
        {{"op", "remove_mesh"}, {"mesh", "gone"}},
    });
    ASSERT_EQ(srv.edits(ops).status, 200);
    const Json a = srv.get("/v1/scene/instances/a").json();
    EXPECT_EQ(a["material"], nullptr);
    EXPECT_EQ(a["visible"], false);
    EXPECT_EQ(a["mask"], 3);
    EXPECT_EQ(a["user_id"], 4);
    EXPECT_EQ(a["transform"], (Json{1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1}));
    EXPECT_EQ(srv.get("/v1/scene/instances/b").json()["transform"][0], 2);
    EXPECT_EQ(srv.get("/v1/scene/materials/red").json()["roughness"], 0.9);
    EXPECT_EQ(srv.get("/v1/scene/meshes/tri").json()["bounds"]["max"], (Json{1, 0, 2}));
    EXPECT_EQ(srv.get("/v1/scene/meshes/ball").json()["build"]["prefer"], "fast_build");
    EXPECT_EQ(srv.get("/v1/scene/meshes/gone").status, 404);
    const Json scene = srv.get("/v1/scene").json();
    EXPECT_EQ(scene["camera"]["eye"], (Json{0, 2, 9}));
    EXPECT_EQ(scene["camera"]["fov_y_deg"], 40);
    EXPECT_EQ(scene["counts"]["instances"], 2);
    // Topology change, then clear.
    ASSERT_EQ(srv.edits({{{"op", "update_mesh"},
                          {"mesh", "tri"},
                          {"positions", {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0}},
                          {"indices", {0, 1, 2, 1, 3, 2}}}})
                  .status,
              200);
    EXPECT_EQ(srv.get("/v1/scene/meshes/tri").json()["triangles"], 2);
    ASSERT_EQ(srv.edits({{{"op", "clear"}}}).status, 200);
    EXPECT_EQ(srv.get("/v1/scene").json()["counts"]["meshes"], 0);
}

TEST_F(Edits, ABadEditAtIndexFiveLeavesZeroToFourUnapplied) {
    Json batch = Json::array();
    for (int i = 0; i < 5; ++i)
        batch.push_back({{"op", "add_material"}, {"id", "m" + std::to_string(i)}});
    batch.push_back({{"op", "add_instance"}, {"id", "x"}, {"mesh", "no-such-mesh"}});
    const Reply r = srv.edits(batch);
    expect_problem(r, 422, "unknown-id", "/edits/5/mesh");
    EXPECT_EQ(r.json()["edit_index"], 5);
    const Json scene = srv.get("/v1/scene").json();
    EXPECT_EQ(scene["version"], 0);
    EXPECT_EQ(scene["counts"]["materials"], 0);
    EXPECT_EQ(srv.get("/v1/scene/materials/m0").status, 404);
}

TEST_F(Edits, IfMatchAppliesOnlyAtThatVersion) {
    ASSERT_EQ(srv.edits({triangle_mesh("a")}).status, 200);
    const Reply stale = srv.edits({triangle_mesh("b")}, {{"If-Match", "\"0\""}});
    expect_problem(stale, 412, "version-mismatch");
    EXPECT_EQ(stale.header("ETag"), "\"1\"");
    EXPECT_EQ(srv.get("/v1/scene/meshes/b").status, 404);
    const Reply fresh = srv.edits({triangle_mesh("b")}, {{"If-Match", "\"1\""}});
    EXPECT_EQ(fresh.status, 200);
    EXPECT_EQ(fresh.header("ETag"), "\"2\"");
    EXPECT_EQ(srv.edits({triangle_mesh("c")}, {{"If-Match", "*"}}).status, 200);
    expect_problem(srv.edits({triangle_mesh("d")}, {{"If-Match", "W/\"3\""}}), 412,
                   "version-mismatch");
    expect_problem(srv.edits({triangle_mesh("d")}, {{"If-Match", "abc"}}), 400, "invalid-request");
}

TEST_F(Edits, ABodyTypeThatCannotCarryJsonIs415AndTheBareTypesCurlSendsAreRead) {
    // 20,000 multipart parts once took the old HTTP stack to a 500.
    std::string parts;
    for (int i = 0; i < 20000; ++i)
        parts += "--x\r\nContent-Disposition: form-data; name=\"a\"\r\n\r\n1\r\n";
    parts += "--x--\r\n";
    for (const char* type : {"multipart/form-data; boundary=x", "image/png", "application/xml"}) {
        SCOPED_TRACE(type);
        for (const char* path : {"/v1/edits", "/v1/render", "/v1/pick"}) {
            const Reply r = srv.post_as(path, parts, type);
            expect_problem(r, 415, "unsupported-media-type");
            EXPECT_THAT(r.body, ::testing::HasSubstr("application/json")) << path;
        }
    }
    const std::string batch = R"({"edits": [{"op": "add_material", "id": "m"}]})";
    for (const char* type : {"application/json; charset=utf-8", "application/x-www-form-urlencoded",
                             "text/plain", "application/merge-patch+json", "APPLICATION/JSON"}) {
        const Reply r = srv.post_as("/v1/edits", batch, type);
        EXPECT_TRUE(r.status == 200 || r.status == 422) << type << ": " << r.body;
        EXPECT_NE(r.status, 415) << type;
    }
}

TEST_F(Edits, MalformedJsonIs400) {
    expect_problem(srv.post("/v1/edits", std::string("{\"edits\": [")), 400, "malformed-json");
    expect_problem(srv.post("/v1/edits", std::string("")), 400, "malformed-json");
}

TEST_F(Edits, SchemaViolationsAre400WithTheirPointer) {
    expect_problem(srv.edits({{{"op", "add_mesh"}, {"id", "x"}, {"postions", {0}}}}), 400,
                   "invalid-request", "/edits/0/postions");
    expect_problem(srv.edits({{{"op", "teleport"}}}), 400, "invalid-request", "/edits/0/op");
    expect_problem(srv.post("/v1/edits", Json{{"edit", Json::array()}}), 400, "invalid-request",
                   "/edit");
    expect_problem(srv.edits({{{"op", "set_transform"}, {"instance", "i"}, {"transform", {1, 2}}}}),
                   400, "invalid-request", "/edits/0/transform");
}

TEST_F(Edits, SemanticErrorsAre422WithTheirTypeAndPointer) {
    ASSERT_EQ(
        srv.edits({triangle_mesh("tri"), {{"op", "add_instance"}, {"id", "i"}, {"mesh", "tri"}}})
            .status,
        200);
    expect_problem(srv.edits({triangle_mesh("tri")}), 422, "duplicate-id", "/edits/0/id");
    expect_problem(
        srv.edits(
            {{{"op", "update_mesh"}, {"mesh", "tri"}, {"positions", {0, 0, 0}}, {"offset", 3}}}),
        422, "out-of-range", "/edits/0/offset");
    expect_problem(srv.edits({{{"op", "update_mesh"}, {"mesh", "tri"}, {"indices", {0, 1, 7}}}}),
                   422, "out-of-range", "/edits/0/indices/2");
    expect_problem(
        srv.post("/v1/edits",
                 std::string(
                     R"({"edits":[{"op":"update_mesh","mesh":"tri","positions":[0,1e999,0]}]})")),
        422, "not-finite", "/edits/0/positions/1");
    expect_problem(
        srv.edits({{{"op", "set_transform"}, {"instance", "i"}, {"transform", {{"scale", 0}}}}}),
        422, "degenerate-transform", "/edits/0/transform");
    expect_problem(srv.edits({{{"op", "remove_mesh"}, {"mesh", "tri"}}}), 422, "in-use",
                   "/edits/0/mesh");
    expect_problem(srv.edits({{{"op", "add_mesh"},
                               {"id", "e"},
                               {"positions", Json::array()},
                               {"indices", Json::array()}}}),
                   422, "empty-mesh");
    expect_problem(srv.edits({{{"op", "add_material"}, {"id", "m"}, {"roughness", 2}}}), 422,
                   "invalid-value", "/edits/0/roughness");
    expect_problem(srv.edits({{{"op", "add_mesh"},
                               {"id", "p"},
                               {"positions", {0, 0, 0, 1}},
                               {"indices", {0, 0, 0}}}}),
                   422, "invalid-value", "/edits/0/positions");
    expect_problem(
        srv.edits({{{"op", "mark_dirty"}, {"target", {{"mesh", "nope"}}}, {"action", "refit"}}}),
        422, "unknown-id", "/edits/0/target/mesh");
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 1);
}

TEST_F(Edits, AMillionVertexUpdateGoesThroughHttp) {
    ASSERT_EQ(srv.edits({{{"op", "add_mesh"},
                          {"id", "big"},
                          {"shape", {{"type", "plane"}, {"subdivisions", {1000, 999}}}}}})
                  .status,
              200);
    std::string body = R"({"edits":[{"op":"update_mesh","mesh":"big","positions":[)";
    for (int v = 0; v < 1001 * 1000; ++v) body += v ? ",0.5,0.25,1" : "0.5,0.25,1";
    body += "]}]}";
    const Reply r = srv.post("/v1/edits", body);
    ASSERT_EQ(r.status, 200) << r.body.substr(0, 300);
    EXPECT_EQ(srv.get("/v1/scene/meshes/big").json()["bounds"]["min"], (Json{0.5, 0.25, 1}));
}

}  // namespace
}  // namespace strata::server::test
