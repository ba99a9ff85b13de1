// Imports as units over real HTTP: GET /v1/assets lists them, DELETE /v1/assets/{id} removes all
// an import made in one batch (and nothing else), PUT /v1/assets/{id} re-imports in place with the
// same ids, keeping what did not change so that the commit rebuilds only what did.

#include <gmock/gmock.h>

#include "engine/image/png.h"
#include "tests/assets/tar_test_util.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

using ::testing::HasSubstr;
using ::testing::UnorderedElementsAre;
using assets::test::tar_end;
using assets::test::tar_file;

/// Two objects: `left` with a textured material, `right` with a plain one, placed at `right_x`.
std::string kit_obj(int right_x = 2, bool with_right = true) {
    std::string obj =
        "mtllib kit.mtl\no left\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
        "usemtl painted\nf 1/1 2/2 3/3\n";
    if (with_right) {
        const std::string x = std::to_string(right_x), x1 = std::to_string(right_x + 1);
        obj += "o right\nv " + x + " 0 0\nv " + x1 + " 0 0\nv " + x +
               " 1 0\nusemtl plain\nf 4 5 6\n";
    }
    return obj;
}

/// The OBJ, its MTL and its texture as one tar archive.
std::string kit_tar(const std::string& obj) {
    const uint8_t rgb[] = {200, 100, 50, 10, 20, 30, 40, 50, 60, 70, 80, 90};
    const std::string png = encode_png(rgb, 2, 2, 3).value();
    const std::string mtl =
        "newmtl painted\nKd 0.8 0.4 0.2\nmap_Kd kit.png\nnewmtl plain\nKd 0.1 0.9 0.1\n";
    return tar_file("kit.obj", obj) + tar_file("kit.mtl", mtl) + tar_file("kit.png", png) +
           tar_end();
}

std::vector<std::string> strings(const Json& array) {
    return array.get<std::vector<std::string>>();
}

class AssetUnits : public ::testing::Test {
protected:
    Reply import(const std::string& query, const std::string& body,
                 const std::string& type = "application/x-tar") {
        auto c = srv.client();
        return to_reply(c.Post(("/v1/assets" + query).c_str(), body, type.c_str()));
    }
    Reply put(const std::string& id, const std::string& query, const std::string& body,
              const httplib::Headers& h = {}) {
        auto c = srv.client();
        return to_reply(
            c.Put(("/v1/assets/" + id + query).c_str(), h, body, "application/x-tar"));
    }
    Reply remove(const std::string& id, const httplib::Headers& h = {}) {
        auto c = srv.client();
        return to_reply(c.Delete(("/v1/assets/" + id).c_str(), h));
    }
    Json counts() { return srv.get("/v1/scene").json()["counts"]; }
    Json commit() { return srv.post("/v1/commit", std::string()).json(); }

    TestServer srv;
};

TEST_F(AssetUnits, AnImportIsListedWithWhatItMadeAndItsBounds) {
    const Reply made = import("?name=kit.tar", kit_tar(kit_obj()));
    ASSERT_EQ(made.status, 200) << made.body;
    const Reply list = srv.get("/v1/assets");
    ASSERT_EQ(list.status, 200) << list.body;
    EXPECT_EQ(list.header("ETag"), "\"1\"");
    const Json assets = list.json()["assets"];
    ASSERT_EQ(assets.size(), 1u) << list.body;
    EXPECT_EQ(assets[0]["id"], "kit");
    EXPECT_EQ(assets[0]["file"], "kit.tar");
    EXPECT_EQ(assets[0]["counts"]["textures"], 1);
    EXPECT_EQ(assets[0]["counts"]["materials"], 2);
    EXPECT_EQ(assets[0]["counts"]["meshes"], 2);
    EXPECT_EQ(assets[0]["counts"]["instances"], made.json()["instances"].size());
    EXPECT_EQ(assets[0]["bounds"]["min"], Json::array({0, 0, 0}));
    EXPECT_EQ(assets[0]["bounds"]["max"], Json::array({3, 1, 0}));
    EXPECT_EQ(srv.get("/v1/scene/groups/kit").json()["asset"], "kit.tar");

    const Json one = srv.get("/v1/assets/kit").json();
    for (const char* kind : {"textures", "materials", "meshes", "groups", "instances"})
        EXPECT_EQ(one[kind], made.json()[kind]) << kind;
    expect_problem(srv.get("/v1/assets/nothing"), 404, "not-found");
}

TEST_F(AssetUnits, DeleteRemovesEverythingTheImportMadeAndNothingElse) {
    ASSERT_EQ(srv.edits({triangle_mesh("mine"),
                         {{"op", "add_instance"}, {"id", "mine-1"}, {"mesh", "mine"}}})
                  .status,
              200);
    const Json before = counts();
    commit();
    const Json memory_before = srv.get("/v1/stats").json()["memory_bytes"];
    ASSERT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
    commit();

    const Reply gone = remove("kit");
    ASSERT_EQ(gone.status, 200) << gone.body;
    EXPECT_EQ(gone.json()["version"], 3);
    EXPECT_EQ(strings(gone.json()["removed"]["meshes"]),
              (std::vector<std::string>{"kit.mesh0", "kit.mesh1"}));
    EXPECT_EQ(strings(gone.json()["removed"]["textures"]),
              std::vector<std::string>{"kit.texture0"});
    EXPECT_EQ(counts(), before);
    const Json report = commit();
    EXPECT_EQ(report["released"], Json::array({"kit.mesh0", "kit.mesh1"})) << report.dump();
    const Json memory_after = srv.get("/v1/stats").json()["memory_bytes"];
    EXPECT_EQ(memory_after["blas"], memory_before["blas"]);
    EXPECT_EQ(srv.get("/v1/assets").json()["assets"], Json::array());
    expect_problem(remove("kit"), 404, "not-found");
    // The ids are free again: the same import lands.
    EXPECT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
}

TEST_F(AssetUnits, DeleteIsRefusedWhileAnObjectOutsideTheAssetUsesItAndChangesNothing) {
    ASSERT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
    ASSERT_EQ(srv.edits({{{"op", "add_instance"}, {"id", "borrowed"}, {"mesh", "kit.mesh1"}}})
                  .status,
              200);
    const Json before = counts();
    const Reply refused = remove("kit");
    expect_problem(refused, 422, "in-use");
    EXPECT_THAT(refused.json()["detail"].get<std::string>(), HasSubstr("'kit.mesh1'"));
    EXPECT_THAT(refused.json()["detail"].get<std::string>(), HasSubstr("outside the asset"));
    EXPECT_EQ(counts(), before);
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 2);
    EXPECT_EQ(srv.get("/v1/assets").json()["assets"].size(), 1u);
}

TEST_F(AssetUnits, DeleteHonoursIfMatch) {
    ASSERT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
    const Reply stale = remove("kit", {{"If-Match", "\"7\""}});
    expect_problem(stale, 412, "version-mismatch");
    EXPECT_EQ(stale.header("ETag"), "\"1\"");
    EXPECT_EQ(remove("kit", {{"If-Match", "\"1\""}}).status, 200);
}

TEST_F(AssetUnits, ReimportingTheSameFileKeepsItsPlaceAndRebuildsNoBlas) {
    ASSERT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
    ASSERT_EQ(srv.edits({{{"op", "add_group"}, {"id", "shelf"}},
                         {{"op", "update_group"},
                          {"group", "kit"},
                          {"parent", "shelf"},
                          {"name", "my kit"},
                          {"transform", {{"translate", {0, 5, 0}}}}}})
                  .status,
              200);
    commit();
    const Json placed = srv.get("/v1/scene/groups/kit").json();

    const Reply again = put("kit", "?name=kit.tar", kit_tar(kit_obj()));
    ASSERT_EQ(again.status, 200) << again.body;
    const Json j = again.json();
    EXPECT_EQ(j["replaced"], true);
    EXPECT_EQ(strings(j["kept"]["meshes"]), (std::vector<std::string>{"kit.mesh0", "kit.mesh1"}));
    EXPECT_EQ(strings(j["kept"]["materials"]),
              (std::vector<std::string>{"kit.material0", "kit.material1"}));
    EXPECT_EQ(strings(j["kept"]["textures"]), std::vector<std::string>{"kit.texture0"});
    EXPECT_EQ(j["removed"], Json::array());
    EXPECT_EQ(j["bounds"]["min"], Json::array({0, 5, 0}));
    const Json group = srv.get("/v1/scene/groups/kit").json();
    EXPECT_EQ(group["transform"], placed["transform"]);
    EXPECT_EQ(group["parent"], "shelf");
    EXPECT_EQ(group["name"], "my kit");
    const Json report = commit();
    EXPECT_EQ(report["blas_rebuilds"], 0) << report.dump();
    EXPECT_EQ(report["released"], Json::array()) << report.dump();
    EXPECT_EQ(srv.get("/v1/assets").json()["assets"].size(), 1u);
}

TEST_F(AssetUnits, ReimportingAChangedFileRebuildsWhatChangedAndDropsWhatIsGone) {
    ASSERT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
    commit();
    const Reply moved = put("kit", "?name=kit.tar", kit_tar(kit_obj(5)));
    ASSERT_EQ(moved.status, 200) << moved.body;
    EXPECT_EQ(strings(moved.json()["kept"]["meshes"]), std::vector<std::string>{"kit.mesh0"});
    Json report = commit();
    EXPECT_EQ(report["blas_rebuilds"], 1) << report.dump();
    ASSERT_EQ(report["rebuilt"].size(), 1u);
    EXPECT_EQ(report["rebuilt"][0]["mesh"], "kit.mesh1");
    EXPECT_EQ(srv.get("/v1/assets/kit").json()["bounds"]["max"], Json::array({6, 1, 0}));

    const Reply fewer = put("kit", "?name=kit.tar", kit_tar(kit_obj(5, false)));
    ASSERT_EQ(fewer.status, 200) << fewer.body;
    // The MTL still defines the plain material: only the mesh that used it goes, and the node's
    // one remaining instance is named as a node with one mesh is (kit.node0, not kit.node0.0).
    EXPECT_THAT(strings(fewer.json()["removed"]),
                UnorderedElementsAre("kit.mesh1", "kit.node0.0", "kit.node0.1"));
    EXPECT_EQ(fewer.json()["instances"], Json::array({"kit.node0"}));
    EXPECT_EQ(srv.get("/v1/scene/meshes/kit.mesh1").status, 404);
    EXPECT_EQ(srv.get("/v1/assets").json()["assets"][0]["counts"]["meshes"], 1);
    report = commit();
    EXPECT_EQ(report["blas_rebuilds"], 0) << report.dump();
    EXPECT_EQ(report["released"], Json::array({"kit.mesh1"})) << report.dump();
}

TEST_F(AssetUnits, PutOfANewIdImportsItAndABrokenFileChangesNothing) {
    const Reply made = put("fresh", "?name=kit.tar", kit_tar(kit_obj()));
    ASSERT_EQ(made.status, 201) << made.body;
    EXPECT_EQ(made.json()["replaced"], false);
    EXPECT_EQ(made.json()["groups"][0], "fresh");
    const Json before = counts();
    const Reply broken = put("fresh", "?name=kit.tar", kit_tar("v 0 0 0\nf 1 2 3\n"));
    expect_problem(broken, 422, "invalid-asset");
    EXPECT_EQ(counts(), before);
    expect_problem(put("fresh", "?name=kit.tar&prefix=other", kit_tar(kit_obj())), 400,
                   "invalid-request", "/prefix");
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 1);
}

TEST_F(AssetUnits, TheLongerOfTwoNestedAssetIdsOwnsItsObjects) {
    ASSERT_EQ(import("?name=kit.tar&prefix=city", kit_tar(kit_obj())).status, 200);
    ASSERT_EQ(import("?name=kit.tar&prefix=city.park", kit_tar(kit_obj())).status, 200);
    const Json assets = srv.get("/v1/assets").json()["assets"];
    ASSERT_EQ(assets.size(), 2u);
    EXPECT_EQ(assets[0]["counts"]["meshes"], 2);
    EXPECT_EQ(assets[1]["counts"]["meshes"], 2);
    const Json city = srv.get("/v1/assets/city").json();
    EXPECT_THAT(strings(city["meshes"]), UnorderedElementsAre("city.mesh0", "city.mesh1"));
    ASSERT_EQ(remove("city").status, 200);
    EXPECT_EQ(srv.get("/v1/assets").json()["assets"][0]["id"], "city.park");
    EXPECT_EQ(srv.get("/v1/scene/meshes/city.park.mesh0").status, 200);
}

TEST_F(AssetUnits, UndoOfADeleteBringsTheAssetBack) {
    ASSERT_EQ(import("?name=kit.tar", kit_tar(kit_obj())).status, 200);
    const Json made = counts();
    ASSERT_EQ(remove("kit").status, 200);
    EXPECT_EQ(srv.get("/v1/assets").json()["assets"].size(), 0u);
    const Reply undone = srv.post("/v1/undo", std::string());
    ASSERT_EQ(undone.status, 200) << undone.body;
    EXPECT_EQ(counts(), made);
    EXPECT_EQ(srv.get("/v1/assets/kit").json()["file"], "kit.tar");
    EXPECT_EQ(srv.get("/v1/render?width=16&height=16").status, 200);
}

}  // namespace
}  // namespace strata::server::test
