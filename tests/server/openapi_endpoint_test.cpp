// GET /v1/openapi.json on the real server: every route of the table is described, with a summary
// and an answer, and what each says about tokens is what the front end does (request_reader.h).

#include <set>
#include <string>

#include <gtest/gtest.h>

#include "server/request_reader.h"
#include "tests/server/test_server.h"

namespace strata::server {
namespace {

using test::TestServer;

/// A concrete path the pattern matches: each parameter an "x", a scene "default".
std::string sample_path(const std::string& path) {
    std::string out;
    bool in_parameter = false;
    for (std::size_t i = 0; i < path.size(); ++i) {
        const char c = path[i];
        if (path.compare(i, 7, "{scene}") == 0) {
            out += "default";  // a scene every server has
            i += 6;
        } else if (c == '{') {
            in_parameter = true;
            out += 'x';
        } else if (c == '}') {
            in_parameter = false;
        } else if (!in_parameter) {
            out += c;
        }
    }
    return out;
}

class OpenApiEndpoint : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        server = new TestServer();
        const test::Reply r = server->get("/v1/openapi.json");
        ASSERT_EQ(r.status, 200);
        EXPECT_EQ(r.header("Content-Type"), "application/json");
        document = new protocol::Json(r.json());
    }
    static void TearDownTestSuite() {
        delete document;
        delete server;
    }
    static TestServer* server;
    static protocol::Json* document;
};
TestServer* OpenApiEndpoint::server = nullptr;
protocol::Json* OpenApiEndpoint::document = nullptr;

TEST_F(OpenApiEndpoint, DescribesEveryRouteTheServerAnswers) {
    const protocol::Json& paths = (*document)["paths"];
    for (const char* path : {"/v1/edits",
                             "/v1/assets",
                             "/v1/commit",
                             "/v1/plan",
                             "/v1/render",
                             "/v1/pick",
                             "/v1/scene",
                             "/v1/scene/meshes",
                             "/v1/scene/instances/{id}",
                             "/v1/scene/snapshot",
                             "/v1/scene/tree",
                             "/v1/scene/groups/{id}/children",
                             "/v1/stats",
                             "/v1/stream",
                             "/v1/events",
                             "/v1/openapi.json",
                             "/metrics",
                             "/livez",
                             "/readyz",
                             "/",
                             "/web/{path}"})
        EXPECT_TRUE(paths.contains(path)) << path;
    EXPECT_TRUE(paths["/v1/render"].contains("post") && paths["/v1/render"].contains("get"));
    for (const auto& [path, item] : paths.items()) {
        for (const auto& [method, op] : item.items()) {
            if (method != "get" && method != "post") continue;
            EXPECT_FALSE(op.value("summary", "").empty()) << method << " " << path;
            const protocol::Json& responses = op["responses"];
            EXPECT_TRUE(responses.contains("200")) << method << " " << path;
            // A route the server answers is a route the document has, and the other way round.
            if (path != "/livez" && path != "/readyz") {
                const std::string m = method == "get" ? "GET" : "POST";
                auto client = server->client();
                const auto probe = client.Options(sample_path(path).c_str());
                ASSERT_TRUE(probe);
                const std::string allow = probe->get_header_value("Allow");
                EXPECT_NE(allow.find(m), std::string::npos) << path << " allows " << allow;
            }
        }
    }
}

TEST_F(OpenApiEndpoint, TokensAreDocumentedAsTheFrontEndAsksForThem) {
    for (const auto& [path, item] : (*document)["paths"].items()) {
        const std::string sample = sample_path(path);
        for (const auto& [method, op] : item.items()) {
            if (method != "get" && method != "post") continue;
            const bool open = op.contains("security") && op["security"].empty();
            EXPECT_EQ(open, is_health_path(sample) || is_public_path(sample)) << path;
            const bool query_token = op.contains("security") && op["security"].size() == 2;
            EXPECT_EQ(query_token, !open && method == "get" && accepts_query_token(sample))
                << method << " " << path;
        }
    }
}

TEST_F(OpenApiEndpoint, EveryProblemAnswerReferencesTheOneProblemSchema) {
    std::set<std::string> schemas;
    for (const auto& [path, item] : (*document)["paths"].items()) {
        for (const auto& [method, op] : item.items()) {
            if (method != "get" && method != "post") continue;
            for (const auto& [status, listed] : op["responses"].items()) {
                if (status[0] < '4') continue;
                // A refusal of the front end's that the route says nothing of is shared.
                const protocol::Json answer =
                    listed.contains("$ref") ? document->at(protocol::Json::json_pointer(
                                                  listed["$ref"].get<std::string>().substr(1)))
                                            : listed;
                schemas.insert(answer["content"]["application/problem+json"]["schema"]["$ref"]);
            }
        }
    }
    EXPECT_EQ(schemas, std::set<std::string>{"#/components/schemas/Problem"});
}

}  // namespace
}  // namespace strata::server
