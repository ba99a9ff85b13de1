// The embedded transport answers exactly like strata-server over HTTP (same statuses, documents,
// problems and headers), and a script plays to the same verdict through both.

#include <sstream>

#include <gtest/gtest.h>

#include "clients/cli/embedded_transport.h"
#include "clients/cli/http_transport.h"
#include "clients/cli/script_runner.h"
#include "tests/cli/server_transport.h"
#include "tests/server/test_server.h"

namespace strata::cli {
namespace {

using server::test::TestServer;

/// A reply's JSON with what differs between two runs (times) removed.
Json without_times(Json j) {
    if (j.is_object()) {
        for (const char* key : {"ms", "phases", "commit_seconds", "render_seconds"}) j.erase(key);
        for (auto& [key, value] : j.items()) value = without_times(value);
    } else if (j.is_array()) {
        for (Json& e : j) e = without_times(e);
    }
    return j;
}

/// Asserts two replies agree: status, content type, ETag, and the body (JSON without times, or
/// the bytes).
void expect_same(const Reply& http, const Reply& embedded, const std::string& what) {
    SCOPED_TRACE(what);
    ASSERT_NE(http.status, 0) << http.error;
    EXPECT_EQ(http.status, embedded.status) << http.body << "\n" << embedded.body;
    EXPECT_EQ(http.content_type, embedded.content_type);
    EXPECT_EQ(http.header("ETag"), embedded.header("ETag"));
    EXPECT_EQ(http.header("Cache-Control"), embedded.header("Cache-Control"));
    if (http.content_type.find("json") != std::string::npos) {
        EXPECT_EQ(without_times(Json::parse(http.body)), without_times(Json::parse(embedded.body)));
    } else {
        EXPECT_EQ(http.body, embedded.body);
    }
}

class Transports : public ::testing::Test {
protected:
    void SetUp() override {
        auto h = HttpTransport::create(test::options_for(srv));
        ASSERT_TRUE(h.has_value()) << h.error().message;
        http = std::move(h.value());
        auto e = EmbeddedTransport::create(false);
        ASSERT_TRUE(e.has_value()) << e.error().message;
        embedded = std::move(e.value());
    }

    /// Sends the same request through both transports and compares the answers.
    template <class Request>
    void same(const std::string& what, Request&& request) {
        expect_same(request(*http), request(*embedded), what);
    }

    TestServer srv;
    std::unique_ptr<HttpTransport> http;
    std::unique_ptr<EmbeddedTransport> embedded;
};

TEST_F(Transports, EveryEndpointAnswersTheSameInProcessAsOverHttp) {
    const std::string scene = R"({"edits": [
        {"op": "add_mesh", "id": "ball", "shape": {"type": "sphere", "segments": 12}},
        {"op": "add_material", "id": "red", "base_color": [0.9, 0.1, 0.1]},
        {"op": "add_instance", "id": "b0", "mesh": "ball", "material": "red"},
        {"op": "add_group", "id": "g", "transform": {"translate": [2, 0, 0]}},
        {"op": "add_instance", "id": "b1", "mesh": "ball", "parent": "g"},
        {"op": "set_camera", "eye": [0, 1, 5], "target": [0, 0, 0]}]})";
    same("edits", [&](Transport& t) { return t.edits(scene, std::nullopt); });
    same("plan", [](Transport& t) { return t.plan(); });
    same("commit", [](Transport& t) { return t.commit(); });
    same("unknown id", [](Transport& t) {
        return t.edits(R"({"edits": [{"op": "remove_instance", "instance": "nope"}]})",
                       std::nullopt);
    });
    same("schema error", [](Transport& t) {
        return t.edits(R"({"edits": [{"op": "add_mesh", "id": "m", "postions": []}]})",
                       std::nullopt);
    });
    same("malformed", [](Transport& t) { return t.edits("{\"edits\": [", std::nullopt); });
    same("version mismatch",
         [](Transport& t) { return t.edits(R"({"edits": []})", std::string("\"41\"")); });
    same("bad If-Match",
         [](Transport& t) { return t.edits(R"({"edits": []})", std::string("1, 2")); });
    same("conditional", [](Transport& t) {
        return t.edits(
            R"({"edits": [{"op": "set_transform", "instance": "b0", "transform": {"translate": [0, 1, 0]}}]})",
            std::string("\"1\""));
    });
    same("render", [](Transport& t) { return t.render(R"({"width": 48, "height": 32})"); });
    same("render with a camera", [](Transport& t) {
        return t.render(R"({"width": 16, "height": 16, "camera": {"eye": [0, 5, 0.1]}})");
    });
    same("render exr",
         [](Transport& t) { return t.render(R"({"width": 8, "height": 8, "format": "exr"})"); });
    same("render too large",
         [](Transport& t) { return t.render(R"({"width": 65536, "height": 65536})"); });
    same("render schema", [](Transport& t) { return t.render(R"({"widht": 3})"); });
    same("stats", [](Transport& t) { return t.stats(); });
    same("scene", [](Transport& t) { return t.scene(); });
    same("list", [](Transport& t) { return t.scene_list("instances", {{"limit", "5"}}); });
    same("list filtered",
         [](Transport& t) { return t.scene_list("instances", {{"mesh", "ball"}}); });
    same("list bad cursor",
         [](Transport& t) { return t.scene_list("meshes", {{"cursor", "instances-0"}}); });
    same("list unknown collection", [](Transport& t) { return t.scene_list("widgets", {}); });
    same("list groups", [](Transport& t) { return t.scene_list("groups", {{"parent", ""}}); });
    same("tree", [](Transport& t) { return t.scene_list("tree", {{"depth", "3"}}); });
    same("object with a slash", [](Transport& t) { return t.scene_object("instances", "a/b"); });
    same("object", [](Transport& t) { return t.scene_object("materials", "red"); });
    same("pick", [](Transport& t) {
        return t.pick(R"({"width": 48, "height": 32, "pixels": [[24, 16], [0, 0]]})");
    });
    same("pick outside", [](Transport& t) {
        return t.pick(R"({"width": 48, "height": 32, "pixels": [[48, 16]]})");
    });
}

TEST_F(Transports, ARenderSaysWhatItsCommitDidInTheSameHeader) {
    const std::string add = R"({"edits": [{"op": "add_mesh", "id": "box", "shape": {"type": "box"}},
        {"op": "add_instance", "id": "x", "mesh": "box"}]})";
    http->edits(add, std::nullopt);
    embedded->edits(add, std::nullopt);
    const Reply a = http->render("{}");
    const Reply b = embedded->render("{}");
    ASSERT_EQ(a.status, 200);
    const std::string ha = a.header("X-Strata-Rebuild"), hb = b.header("X-Strata-Rebuild");
    // Identical up to the commit time at the end ("... ms=0.123").
    EXPECT_EQ(ha.substr(0, ha.find(" ms=")), hb.substr(0, hb.find(" ms=")));
    EXPECT_EQ(ha.substr(0, ha.find(" ms=")), "v1 tlas=update(1) rebuilds=1 refits=0 prims=12");
}

/// Plays `text` and returns the verdict.
Verdict play_text(Transport& t, const std::string& text) {
    std::istringstream in(text);
    auto script = load_script(in, "t.jsonl");
    EXPECT_TRUE(script.has_value());
    struct Quiet final : PlayObserver {
        void on_start(const Script&, std::size_t) override {}
        void on_step(const StepRecord&) override {}
        void on_finish(const PlayResult&) override {}
    } quiet;
    return play(script.value(), t, PlayOptions{}, quiet).verdict;
}

TEST_F(Transports, AScriptPlaysToTheSameVerdictThroughBoth) {
    const std::string good =
        R"({"edits": [{"op": "add_mesh", "id": "m", "shape": {"type": "box"}}, {"repeat": 20, "var": "i", "items": [{"op": "add_instance", "id": "i{i}", "mesh": "m", "transform": {"translate": ["{i * 2}", 0, 0]}}]}]})"
        "\n"
        R"({"commit": {}, "expect": {"tlas": "update", "tlas_instances": 20, "rebuilt": {"m": "added"}, "primitives_built": 12}})"
        "\n"
        R"({"repeat": 3, "steps": [{"edits": [{"op": "set_transform", "instance": "i{n * 7}", "transform": {"translate": [0, 1, 0]}}]}, {"render": {"width": 16, "height": 16}, "expect": {"tlas": "update", "blas_rebuilds": 0, "blas_refits": 0, "rebuilt": [], "refit": []}}]})";
    EXPECT_EQ(play_text(*http, good), Verdict::Passed);
    EXPECT_EQ(play_text(*embedded, good), Verdict::Passed);
    const std::string bad = R"({"commit": {}, "expect": {"tlas": "rebuild"}})";
    EXPECT_EQ(play_text(*http, bad), Verdict::ExpectationFailed);
    EXPECT_EQ(play_text(*embedded, bad), Verdict::ExpectationFailed);
}

TEST_F(Transports, PickAndListStepsPlayToTheSameVerdictThroughBoth) {
    const std::string good =
        R"({"edits": [{"op": "clear"}, {"op": "add_mesh", "id": "m", "shape": {"type": "box"}}, {"op": "add_mesh", "id": "unused", "shape": {"type": "sphere"}}, {"repeat": 3, "var": "i", "items": [{"op": "add_instance", "id": "i{i}", "mesh": "m", "user_id": "{i + 10}", "transform": {"translate": ["{i * 3}", 0, 0]}}]}]})"
        "\n"
        R"({"pick": {"x": 32, "y": 32, "width": 64, "height": 64, "camera": {"eye": [0, 0, 10], "target": [0, 0, 0]}}, "expect": {"hit": true, "hit.instance": "i0", "hit.mesh": "m", "hit.user_id": 10, "hit.distance": {"min": 8, "max": 10}}})"
        "\n"
        R"({"pick": {"x": 0, "y": 0, "width": 64, "height": 64, "camera": {"eye": [0, 0, 10], "target": [0, 0, 0]}}, "expect": {"hit": false}})"
        "\n"
        R"({"list": "instances", "filter": {"mesh": "m"}, "expect": {"count": 3, "ids": ["i0", "i1", "i2"]}})"
        "\n"
        R"({"list": "meshes", "expect": {"ids": ["m", "unused"]}})"
        "\n"
        R"({"edits": [{"op": "update_instance", "instance": "i1", "visible": false}]})"
        "\n"
        R"({"list": "instances", "filter": {"visible": false}, "expect": {"count": 1, "ids": ["i1"]}})";
    EXPECT_EQ(play_text(*http, good), Verdict::Passed);
    EXPECT_EQ(play_text(*embedded, good), Verdict::Passed);
    const std::string wrong_hit =
        R"({"pick": {"x": 32, "y": 32, "width": 64, "height": 64, "camera": {"eye": [0, 0, 10], "target": [0, 0, 0]}}, "expect": {"hit.instance": "i2"}})";
    EXPECT_EQ(play_text(*http, wrong_hit), Verdict::ExpectationFailed);
    EXPECT_EQ(play_text(*embedded, wrong_hit), Verdict::ExpectationFailed);
    const std::string wrong_count = R"({"list": "instances", "expect": {"count": 2}})";
    EXPECT_EQ(play_text(*http, wrong_count), Verdict::ExpectationFailed);
    EXPECT_EQ(play_text(*embedded, wrong_count), Verdict::ExpectationFailed);
    const std::string outside = R"({"pick": {"x": 64, "y": 0, "width": 64, "height": 64}})";
    EXPECT_EQ(play_text(*http, outside), Verdict::RequestFailed);
    EXPECT_EQ(play_text(*embedded, outside), Verdict::RequestFailed);
}

TEST(HttpTransport, RefusesUrlsItCannotUse) {
    for (const char* url : {"localhost:7070", "ftp://host", "http://", "http://host/v1",
                            "http://host:port", "http://host:123456"}) {
        auto t = HttpTransport::create({url, "", 1, {}, {}});
        EXPECT_FALSE(t.has_value()) << url;
    }
    EXPECT_TRUE(HttpTransport::create({"http://127.0.0.1:7070/", "", 1, {}, {}}).has_value());
    EXPECT_TRUE(HttpTransport::create({"https://strata.example:8443", "", 1, {}, {}}).has_value());
}

TEST(HttpTransport, AnUnreachableServerIsAnAnswerWithoutStatusThatSaysWhy) {
    auto t = HttpTransport::create({"http://127.0.0.1:1", "", 2, {}, {}});
    ASSERT_TRUE(t.has_value());
    const Reply r = t.value()->commit();
    EXPECT_EQ(r.status, 0);
    EXPECT_NE(describe_failure(r).find("could not connect (http://127.0.0.1:1)"), std::string::npos)
        << describe_failure(r);
}

TEST(HttpTransport, SendsTheBearerToken) {
    server::ServerConfig config;
    config.token = "s3cret";
    TestServer srv(config);
    const std::string url = "http://127.0.0.1:" + std::to_string(srv.port());
    EXPECT_EQ(HttpTransport::create({url, "", 5, {}, {}}).value()->stats().status, 401);
    EXPECT_EQ(HttpTransport::create({url, "wrong", 5, {}, {}}).value()->stats().status, 401);
    EXPECT_EQ(HttpTransport::create({url, "s3cret", 5, {}, {}}).value()->stats().status, 200);
}

}  // namespace
}  // namespace strata::cli
