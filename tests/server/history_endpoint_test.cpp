// POST /v1/undo, POST /v1/redo and GET /v1/history over real HTTP: what they answer, If-Match,
// the 409 of an empty stack, paging, messages, and undo racing other writers.

#include <atomic>
#include <thread>

#include <gmock/gmock.h>

#include "tests/server/test_server.h"

namespace strata::server::test {
namespace {

class History : public ::testing::Test {
protected:
    Json scene_counts() { return srv.get("/v1/scene").json()["counts"]; }
    TestServer srv;
};

TEST_F(History, UndoAndRedoAnswerTheNewVersionAndWhatTheyTookBack) {
    ASSERT_EQ(
        srv.edits({triangle_mesh("tri"), {{"op", "add_instance"}, {"id", "a"}, {"mesh", "tri"}}})
            .status,
        200);
    const Reply undo = srv.post("/v1/undo", std::string());
    ASSERT_EQ(undo.status, 200) << undo.body;
    EXPECT_EQ(undo.json(), (Json{{"version", 2}, {"undone", 1}, {"applied", 2}}));
    EXPECT_EQ(undo.header("ETag"), "\"2\"");
    EXPECT_EQ(srv.get("/v1/scene/meshes/tri").status, 404);
    EXPECT_EQ(srv.get("/v1/scene/instances/a").status, 404);
    const Reply redo = srv.post("/v1/redo", std::string());
    ASSERT_EQ(redo.status, 200) << redo.body;
    EXPECT_EQ(redo.json(), (Json{{"version", 3}, {"redone", 1}, {"applied", 2}}));
    EXPECT_EQ(srv.get("/v1/scene/instances/a").status, 200);
    expect_problem(srv.post("/v1/redo", std::string()), 409, "nothing-to-undo");
}

TEST_F(History, AnEmptyStackIs409AndChangesNothing) {
    const Reply r = srv.post("/v1/undo", std::string());
    expect_problem(r, 409, "nothing-to-undo");
    EXPECT_EQ(r.header("ETag"), "\"0\"");
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
}

TEST_F(History, IfMatchUndoesOnlyAtThatVersion) {
    ASSERT_EQ(srv.edits({triangle_mesh("a")}).status, 200);
    ASSERT_EQ(srv.edits({triangle_mesh("b")}).status, 200);
    const Reply stale = srv.post("/v1/undo", std::string(), {{"If-Match", "\"1\""}});
    expect_problem(stale, 412, "version-mismatch");
    EXPECT_EQ(stale.header("ETag"), "\"2\"");
    EXPECT_EQ(srv.get("/v1/scene/meshes/b").status, 200);
    const Reply fresh = srv.post("/v1/undo", std::string(), {{"If-Match", "\"2\""}});
    ASSERT_EQ(fresh.status, 200) << fresh.body;
    EXPECT_EQ(fresh.json()["undone"], 2);
    EXPECT_EQ(srv.get("/v1/scene/meshes/b").status, 404);
    expect_problem(srv.post("/v1/undo", std::string(), {{"If-Match", "x"}}), 400,
                   "invalid-request");
}

TEST_F(History, ANewEditEmptiesTheRedoStack) {
    ASSERT_EQ(srv.edits({triangle_mesh("a")}).status, 200);
    ASSERT_EQ(srv.post("/v1/undo", std::string()).status, 200);
    ASSERT_EQ(srv.edits({triangle_mesh("b")}).status, 200);
    expect_problem(srv.post("/v1/redo", std::string()), 409, "nothing-to-undo");
    const Json h = srv.get("/v1/history").json();
    EXPECT_EQ(h["redo"], (Json{{"depth", 0}, {"next", nullptr}}));
    EXPECT_EQ(h["undo"], (Json{{"depth", 1}, {"next", 3}}));
}

TEST_F(History, PagesNewestFirstWithMessagesAndOpCounts) {
    for (int i = 0; i < 5; ++i) {
        Json body = {{"edits", Json::array({triangle_mesh("m" + std::to_string(i)),
                                            {{"op", "set_camera"}, {"fov_y_deg", 30 + i}}})}};
        if (i == 2) body["message"] = "third \xc3\xa9";
        ASSERT_EQ(srv.post("/v1/edits", body).status, 200);
    }
    const Reply first = srv.get("/v1/history?limit=2");
    ASSERT_EQ(first.status, 200) << first.body;
    EXPECT_EQ(first.header("ETag"), "\"5\"");
    const Json p1 = first.json();
    ASSERT_EQ(p1["entries"].size(), 2u);
    EXPECT_EQ(p1["entries"][0]["version"], 5);
    EXPECT_EQ(p1["entries"][0]["kind"], "edit");
    EXPECT_EQ(p1["entries"][0]["edits"], 2);
    EXPECT_EQ(p1["entries"][0]["ops"], (Json{{"add_mesh", 1}, {"set_camera", 1}}));
    EXPECT_TRUE(p1["entries"][0]["undoable"]);
    EXPECT_THAT(p1["entries"][0]["time"].get<std::string>(),
                ::testing::MatchesRegex("20[0-9][0-9]-[01][0-9]-[0-3][0-9]T[0-9:]+\\.[0-9]+Z"));
    EXPECT_FALSE(p1["entries"][0].contains("message"));
    EXPECT_EQ(p1["oldest"], 1);
    ASSERT_TRUE(p1["next_cursor"].is_string());
    const Json p2 =
        srv.get("/v1/history?limit=2&cursor=" + p1["next_cursor"].get<std::string>()).json();
    ASSERT_EQ(p2["entries"].size(), 2u);
    EXPECT_EQ(p2["entries"][0]["version"], 3);
    EXPECT_EQ(p2["entries"][0]["message"], "third \xc3\xa9");
    const Json p3 =
        srv.get("/v1/history?limit=2&cursor=" + p2["next_cursor"].get<std::string>()).json();
    ASSERT_EQ(p3["entries"].size(), 1u);
    EXPECT_EQ(p3["entries"][0]["version"], 1);
    EXPECT_TRUE(p3["next_cursor"].is_null());
}

TEST_F(History, BadQueriesAndMessagesAreRefused) {
    expect_problem(srv.get("/v1/history?limit=0"), 400, "invalid-request");
    expect_problem(srv.get("/v1/history?limit=1001"), 400, "invalid-request");
    expect_problem(srv.get("/v1/history?cursor=abc"), 400, "invalid-request");
    expect_problem(srv.get("/v1/history?limit=1&limit=2"), 400, "invalid-request");
    expect_problem(srv.get("/v1/history?since=3"), 400, "invalid-request");
    const Reply not_text = srv.post("/v1/edits", Json{{"edits", Json::array()}, {"message", 3}});
    expect_problem(not_text, 400, "invalid-request");
    const Reply control =
        srv.post("/v1/edits", Json{{"edits", Json::array()}, {"message", "a\x01"}});
    expect_problem(control, 422, "invalid-value");
    EXPECT_EQ(control.json()["pointer"], "/message");
    EXPECT_EQ(control.json()["detail"], "/message: the batch's message holds a control character");
    const Reply long_one =
        srv.post("/v1/edits", Json{{"edits", Json::array()}, {"message", std::string(1025, 'x')}});
    EXPECT_TRUE(long_one.status == 400 || long_one.status == 422) << long_one.body;
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], 0);
}

TEST_F(History, UndoWithoutIfMatchTakesBackTheNewestWhileOthersWrite) {
    // A writer keeps adding meshes while undos land: every undo answers 200 or 409 (never 412,
    // never a 5xx), and the scene ends as the batches and undos leave it.
    std::atomic<bool> stop{false};
    std::atomic<int> written{0};
    std::thread writer([&] {
        for (int i = 0; i < 60 && !stop; ++i) {
            if (srv.edits({triangle_mesh("w" + std::to_string(i))}).status == 200) ++written;
        }
    });
    int undone = 0;
    for (int i = 0; i < 30; ++i) {
        const Reply r = srv.post("/v1/undo", std::string());
        ASSERT_TRUE(r.status == 200 || r.status == 409) << r.status << " " << r.body;
        if (r.status == 200) ++undone;
    }
    stop = true;
    writer.join();
    // Every undo took back exactly one mesh.
    EXPECT_EQ(scene_counts()["meshes"], written.load() - undone);
    EXPECT_EQ(srv.get("/v1/scene").json()["version"], written.load() + undone);
}

}  // namespace
}  // namespace strata::server::test
