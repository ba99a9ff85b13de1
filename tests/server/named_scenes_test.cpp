// Named scenes over real HTTP (GET /v1/scenes, PUT and DELETE /v1/scenes/{scene}, and every
// route under /v1/scenes/{scene}/): isolation of ids, versions, budgets and histories, the
// directory's answers and problems, and deletion while requests run.

#include <atomic>
#include <mutex>
#include <thread>

#include <gmock/gmock.h>

#include "server/named_scenes.h"
#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

/// PUT /v1/scenes/{name} with `body`.
Reply put_scene(const TestServer& srv, const std::string& name, const std::string& body = "") {
    auto c = srv.client();
    return to_reply(c.Put(("/v1/scenes/" + name).c_str(), body, "application/json"));
}

Reply delete_scene(const TestServer& srv, const std::string& name) {
    auto c = srv.client();
    return to_reply(c.Delete(("/v1/scenes/" + name).c_str()));
}

Json instance(const std::string& id, const std::string& mesh) {
    return {{"op", "add_instance"}, {"id", id}, {"mesh", mesh}};
}

class NamedScenes : public ::testing::Test {
protected:
    Reply edits_in(const std::string& scene, std::initializer_list<Json> edits) {
        Json list = Json::array();
        for (const Json& e : edits) list.push_back(e);
        return srv.post("/v1/scenes/" + scene + "/edits", Json{{"edits", list}});
    }
    TestServer srv;
};

TEST_F(NamedScenes, PutCreatesOnceThenFindsTheScene) {
    const Reply made = put_scene(srv, "city");
    ASSERT_EQ(made.status, 201) << made.body;
    EXPECT_EQ(made.header("ETag"), "\"0\"");
    const Json summary = made.json();
    EXPECT_EQ(summary["name"], "city");
    EXPECT_EQ(summary["version"], 0);
    EXPECT_EQ(summary["durable"], false);  // this server has no --data
    EXPECT_EQ(summary["budget"]["max_instances"], ServerConfig{}.max_scene_instances);
    const Reply again = put_scene(srv, "city");
    EXPECT_EQ(again.status, 200) << again.body;
    EXPECT_EQ(again.json(), summary);
    EXPECT_EQ(srv.get("/v1/scenes/city").json(), summary);

    const Json list = srv.get("/v1/scenes").json()["scenes"];
    ASSERT_EQ(list.size(), 2u);
    EXPECT_EQ(list[0]["name"], "default");
    EXPECT_EQ(list[1]["name"], "city");
}

TEST_F(NamedScenes, IdsVersionsAndHistoriesAreTheScenesOwn) {
    ASSERT_EQ(put_scene(srv, "a").status, 201);
    // The same ids in both scenes, at different versions.
    ASSERT_EQ(srv.edits({triangle_mesh("m"), instance("i", "m")}).status, 200);
    ASSERT_EQ(srv.edits({instance("j", "m")}).status, 200);
    const Reply in_a = edits_in("a", {triangle_mesh("m"), instance("i", "m")});
    ASSERT_EQ(in_a.status, 200) << in_a.body;
    EXPECT_EQ(in_a.json()["version"], 1);
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 2);
    EXPECT_EQ(srv.get("/v1/scenes/a/scene").json()["version"], 1);
    EXPECT_EQ(srv.get("/v1/scenes/a/scene/instances/j").status, 404);
    EXPECT_EQ(srv.get("/v1/scene/instances/j").status, 200);

    // Undo in a takes back a's batch only.
    const Reply undo = srv.post("/v1/scenes/a/undo", std::string());
    ASSERT_EQ(undo.status, 200) << undo.body;
    EXPECT_EQ(undo.json()["undone"], 1);
    EXPECT_EQ(srv.get("/v1/scenes/a/scene/meshes/m").status, 404);
    EXPECT_EQ(srv.get("/v1/scene/meshes/m").status, 200);
    EXPECT_EQ(srv.get("/v1/scenes/a/history").json()["entries"].size(), 2u);
    EXPECT_EQ(srv.get("/v1/history").json()["entries"].size(), 2u);

    // "default" under the prefix is the unprefixed scene.
    EXPECT_EQ(srv.get("/v1/scenes/default/scene").json(), srv.get("/v1/scene").json());
}

TEST_F(NamedScenes, RendersAndCommitsTraceTheirOwnScene) {
    ASSERT_EQ(put_scene(srv, "b").status, 201);
    ASSERT_EQ(edits_in("b", {{{"op", "add_mesh"}, {"id", "ball"}, {"shape", {{"type", "sphere"}}}},
                             instance("x", "ball")})
                  .status,
              200);
    const Reply b = srv.get("/v1/scenes/b/render?width=32&height=32");
    const Reply d = srv.get("/v1/render?width=32&height=32");
    ASSERT_EQ(b.status, 200) << b.body;
    ASSERT_EQ(d.status, 200) << d.body;
    EXPECT_EQ(b.header("ETag"), "\"1\"");
    EXPECT_EQ(d.header("ETag"), "\"0\"");
    EXPECT_NE(b.body, d.body);  // a sphere against an empty scene
    const Json stats = srv.get("/v1/scenes/b/stats").json();
    EXPECT_EQ(stats["version"], 1);
    EXPECT_GT(stats["memory_bytes"]["blas"].get<int64_t>(), 0);
    EXPECT_EQ(srv.get("/v1/stats").json()["memory_bytes"]["blas"], 0);
    // /metrics: the default scene's series, and each named scene's under its label.
    const std::string metrics = srv.get("/metrics").body;
    EXPECT_NE(metrics.find("\nstrata_scene_version 0\n"), std::string::npos) << metrics;
    EXPECT_NE(metrics.find("\nstrata_named_scenes 1\n"), std::string::npos);
    EXPECT_NE(metrics.find("\nstrata_named_scene_version{scene=\"b\"} 1\n"), std::string::npos);
    EXPECT_NE(metrics.find("\nstrata_named_scene_instances{scene=\"b\"} 1\n"), std::string::npos);
}

TEST_F(NamedScenes, ABudgetOfItsOwnIsCheckedInThatSceneOnly) {
    const Reply made = put_scene(srv, "small", R"({"budget": {"max_instances": 1}})");
    ASSERT_EQ(made.status, 201) << made.body;
    EXPECT_EQ(made.json()["budget"]["max_instances"], 1);
    expect_problem(edits_in("small", {triangle_mesh("m"), instance("i", "m"), instance("j", "m")}),
                   413, "too-large");
    EXPECT_EQ(srv.get("/v1/scenes/small/scene").json()["version"], 0);
    EXPECT_EQ(srv.edits({triangle_mesh("m"), instance("i", "m"), instance("j", "m")}).status, 200);
    // The same name with another budget is a conflict; without a body it is another budget too.
    expect_problem(put_scene(srv, "small", R"({"budget": {"max_instances": 2}})"), 409,
                   "scene-conflict");
    expect_problem(put_scene(srv, "small"), 409, "scene-conflict");
    EXPECT_EQ(put_scene(srv, "small", R"({"budget": {"max_instances": 1}})").status, 200);
}

TEST_F(NamedScenes, BadNamesAndBodiesAreRefusedWithoutAScene) {
    for (const char* name : {"City", "-a", "_a", "a.b", "%2e%2e", "a%2Fb", "caf%C3%A9",
                             "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa"})
        expect_problem(put_scene(srv, name), 400, "invalid-request", "/scene");
    expect_problem(put_scene(srv, "a", "{"), 400, "malformed-json");
    expect_problem(put_scene(srv, "a", R"({"budget": {"max_cats": 1}})"), 400, "invalid-request");
    expect_problem(put_scene(srv, "a", R"({"budget": {"max_instances": -1}})"), 400);
    expect_problem(put_scene(srv, "a", R"({"budget": {"max_instances": 1e30}})"), 400);
    expect_problem(put_scene(srv, "a", R"({"budget": {"max_triangles": 4294967296000}})"), 422,
                   "invalid-value", "/budget/max_triangles");
    expect_problem(put_scene(srv, "a", "{\"budget\": \"\xff\"}"), 400);
    EXPECT_EQ(srv.get("/v1/scenes").json()["scenes"].size(), 1u);
}

TEST_F(NamedScenes, UnknownScenesAndRoutesAre404) {
    expect_problem(srv.get("/v1/scenes/nope"), 404, "not-found", "/scene");
    expect_problem(srv.get("/v1/scenes/nope/scene"), 404, "not-found", "/scene");
    expect_problem(srv.post("/v1/scenes/nope/edits", Json{{"edits", Json::array()}}), 404);
    expect_problem(delete_scene(srv, "nope"), 404, "not-found");
    ASSERT_EQ(put_scene(srv, "c").status, 201);
    // What only the unprefixed paths serve.
    expect_problem(srv.get("/v1/scenes/c/openapi.json"), 404);
    expect_problem(srv.get("/v1/scenes/c/scenes"), 404);
    expect_problem(srv.get("/v1/scenes/c/scenes/c"), 404);
    expect_problem(srv.get("/v1/scenes/c/nothing"), 404);
    // Methods: 405 with Allow, under the prefix as without it.
    const Reply wrong = srv.get("/v1/scenes/c/edits");
    expect_problem(wrong, 405);
    EXPECT_EQ(wrong.header("Allow"), "POST");
}

TEST_F(NamedScenes, DeletingFreesTheNameAndTheDefaultSceneStays) {
    expect_problem(delete_scene(srv, "default"), 409, "scene-conflict");
    ASSERT_EQ(put_scene(srv, "d").status, 201);
    ASSERT_EQ(edits_in("d", {triangle_mesh("m")}).status, 200);
    const Reply gone = delete_scene(srv, "d");
    EXPECT_EQ(gone.status, 204) << gone.body;
    expect_problem(srv.get("/v1/scenes/d/scene"), 404);
    expect_problem(delete_scene(srv, "d"), 404);
    // A new scene of that name starts empty, at version 0.
    ASSERT_EQ(put_scene(srv, "d").status, 201);
    EXPECT_EQ(srv.get("/v1/scenes/d/scene").json()["version"], 0);
    EXPECT_EQ(srv.get("/v1/scenes/d/scene/meshes/m").status, 404);
}

TEST(NamedSceneLimits, MaxScenesIs413) {
    ServerConfig config;
    config.max_scenes = 2;
    TestServer srv(config);
    EXPECT_EQ(put_scene(srv, "a").status, 201);
    EXPECT_EQ(put_scene(srv, "b").status, 201);
    expect_problem(put_scene(srv, "c"), 413, "too-large");
    EXPECT_EQ(put_scene(srv, "a").status, 200);  // finding one is not making one
    EXPECT_EQ(delete_scene(srv, "a").status, 204);
    EXPECT_EQ(put_scene(srv, "c").status, 201);
}

TEST(NamedSceneLimits, TheScenesBudgetsFitInTheServersTotal) {
    ServerConfig config;
    config.max_scene_instances = 1000;
    config.max_total_instances = 3000;  // the default scene reserves 1000 of it
    TestServer srv(config);
    EXPECT_EQ(put_scene(srv, "a").status, 201);
    EXPECT_EQ(put_scene(srv, "b", R"({"budget": {"max_instances": 600}})").status, 201);
    const Reply over = put_scene(srv, "c", R"({"budget": {"max_instances": 401}})");
    expect_problem(over, 413, "too-large", "/budget");
    EXPECT_NE(over.json()["detail"].get<std::string>().find("3001 instances"), std::string::npos)
        << over.body;
    EXPECT_EQ(put_scene(srv, "c", R"({"budget": {"max_instances": 400}})").status, 201);
    expect_problem(put_scene(srv, "d", R"({"budget": {"max_instances": 1}})"), 413);
    ASSERT_EQ(delete_scene(srv, "a").status, 204);
    EXPECT_EQ(put_scene(srv, "d").status, 201);  // a's share is free again
}

TEST(NamedSceneLimits, ADeletedSceneStillHeldKeepsItsShareAndItsName) {
    ServerConfig config;
    config.max_scene_instances = 1000;
    config.max_total_instances = 2000;  // the default scene's 1000 and one more scene's
    ServerMetrics metrics;
    SceneDirectory scenes(SceneShared{config, metrics, nullptr, {}});
    ASSERT_TRUE(scenes.create("a", scenes.default_budget()).has_value());
    std::shared_ptr<HostedScene> held = scenes.find("a");  // as a running request holds it
    ASSERT_TRUE(scenes.remove("a").value());
    EXPECT_EQ(scenes.find("a"), nullptr);
    auto refused = scenes.create("b", scenes.default_budget());
    ASSERT_FALSE(refused.has_value());
    EXPECT_EQ(refused.error().status, 413);
    auto again = scenes.create("a", scenes.default_budget());
    ASSERT_FALSE(again.has_value());
    EXPECT_EQ(again.error().status, 409);
    held.reset();  // the request ends: the scene goes, with its share and its name
    EXPECT_TRUE(scenes.create("b", scenes.default_budget()).has_value());
    ASSERT_TRUE(scenes.remove("b").value());
    EXPECT_TRUE(scenes.create("a", scenes.default_budget()).has_value());
}

TEST(NamedSceneLimits, PutsRacingForOneNameMakeOneScene) {
    TestServer srv;
    for (int round = 0; round < 5; ++round) {
        const std::string name = "race" + std::to_string(round);
        std::vector<int> statuses(6);
        std::vector<std::thread> putters;
        for (std::size_t i = 0; i < statuses.size(); ++i)
            putters.emplace_back([&, i] { statuses[i] = put_scene(srv, name).status; });
        for (auto& t : putters) t.join();
        EXPECT_EQ(std::count(statuses.begin(), statuses.end(), 201), 1) << name;
        EXPECT_EQ(std::count(statuses.begin(), statuses.end(), 200), 5) << name;
    }
    EXPECT_EQ(srv.get("/v1/scenes").json()["scenes"].size(), 6u);
}

TEST(NamedSceneLimits, DeletingWhileRequestsRunAnswersEachOneWholly) {
    TestServer srv;
    std::atomic<bool> stop{false};
    std::atomic<int> ok{0}, missing{0}, other{0};
    std::mutex odd_mutex;
    std::string odd;  // the first answer that is neither 200 nor 404
    std::vector<std::thread> clients;
    for (int t = 0; t < 3; ++t) {
        clients.emplace_back([&, t] {
            int n = 0;
            while (!stop) {
                const std::string id = "i" + std::to_string(t) + "-" + std::to_string(n++);
                const Reply r =
                    t == 0 ? srv.get("/v1/scenes/busy/render?width=32&height=32")
                           : srv.post("/v1/scenes/busy/edits",
                                      Json{{"edits", {{{"op", "add_mesh"},
                                                       {"id", id},
                                                       {"shape", {{"type", "sphere"}}}}}}});
                (r.status == 200 ? ok : r.status == 404 ? missing : other)++;
                if (r.status != 200 && r.status != 404) {
                    std::lock_guard<std::mutex> lock(odd_mutex);
                    if (odd.empty())
                        odd = (t == 0 ? "render: " : "edits: ") + std::to_string(r.status) + " " +
                              r.body;
                }
            }
        });
    }
    // A PUT racing the last request of the scene just deleted finds the name still going (409)
    // until that request ends.
    int conflicts = 0;
    for (int round = 0; round < 20; ++round) {
        Reply made = put_scene(srv, "busy");
        for (int wait = 0; made.status == 409 && wait < 400; ++wait) {
            ++conflicts;
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
            made = put_scene(srv, "busy");
        }
        EXPECT_EQ(made.status, 201) << made.body;
        std::this_thread::sleep_for(std::chrono::milliseconds(15));
        const Reply gone = delete_scene(srv, "busy");
        EXPECT_EQ(gone.status, 204) << gone.body;
    }
    std::printf("deleted 20 scenes under load; %d PUTs found the name still going\n", conflicts);
    stop = true;
    for (auto& c : clients) c.join();
    EXPECT_GT(ok.load(), 0);
    EXPECT_GT(missing.load(), 0);
    EXPECT_EQ(other.load(), 0) << odd << "\n" << srv.get("/metrics").body;
    EXPECT_EQ(srv.get("/v1/scenes").json()["scenes"].size(), 1u);
}

TEST(NamedSceneDescription, EveryV1RouteIsListedUnderTheScenePrefix) {
    TestServer srv;
    const Json paths = srv.get("/v1/openapi.json").json()["paths"];
    for (const char* path : {"/v1/scenes", "/v1/scenes/{scene}", "/v1/scenes/{scene}/edits",
                             "/v1/scenes/{scene}/render", "/v1/scenes/{scene}/stream",
                             "/v1/scenes/{scene}/scene/instances/{id}",
                             "/v1/scenes/{scene}/history"})
        EXPECT_TRUE(paths.contains(path)) << path;
    EXPECT_FALSE(paths.contains("/v1/scenes/{scene}/openapi.json"));
    EXPECT_FALSE(paths.contains("/v1/scenes/{scene}/scenes"));
    EXPECT_TRUE(paths["/v1/scenes/{scene}"].contains("put"));
    EXPECT_TRUE(paths["/v1/scenes/{scene}"].contains("delete"));
    std::size_t plain = 0, scoped = 0;
    for (const auto& [path, item] : paths.items()) {
        if (path.rfind("/v1/scenes", 0) == 0) {
            ++scoped;
        } else if (path.rfind("/v1/", 0) == 0 && path != "/v1/openapi.json") {
            ++plain;
        }
    }
    EXPECT_EQ(scoped, plain + 2);  // and the directory's two paths
}

}  // namespace
}  // namespace strata::server::test
