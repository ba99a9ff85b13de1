// The route table: patterns and their parameters, 404 and 405 with Allow, HEAD on GET routes,
// and an exception escaping a handler becoming a 500 problem while the table keeps serving.

#include <stdexcept>

#include <gtest/gtest.h>

#include "protocol/json_document.h"
#include "server/route_table.h"

namespace strata::server {
namespace {

HttpRequest request(std::string method, std::string path) {
    HttpRequest r;
    r.method = std::move(method);
    r.path = std::move(path);
    return r;
}

protocol::ApiResponse text(std::string body) {
    protocol::ApiResponse r;
    r.content_type = "text/plain";
    r.body = std::move(body);
    return r;
}

Reply run(const RouteTable& routes, std::string method, std::string path) {
    HttpRequest r = request(std::move(method), std::move(path));
    RequestContext context;
    return routes.dispatch(r, context);
}

void expect_internal_problem(const protocol::ApiResponse& res) {
    EXPECT_EQ(res.status, 500);
    EXPECT_EQ(res.content_type, "application/problem+json");
    const auto body = protocol::Json::parse(res.body);
    EXPECT_EQ(body["status"], 500);
    EXPECT_EQ(body["detail"], "internal error while handling the request");
    EXPECT_EQ(res.body.find("secret"), std::string::npos) << "internals must not leak";
}

TEST(RouteTable, AThrowingRouteGetsA500AndTheTableKeepsServing) {
    RouteTable routes;
    routes.get("/throw", [](RouteCall&) -> Reply { throw std::logic_error("secret bug"); });
    routes.get("/other", [](RouteCall&) -> Reply { throw 42; });
    routes.get("/ok", [](RouteCall&) { return text("fine"); });
    for (int i = 0; i < 3; ++i) expect_internal_problem(run(routes, "GET", "/throw").response);
    expect_internal_problem(run(routes, "GET", "/other").response);
    const Reply ok = run(routes, "GET", "/ok");
    EXPECT_EQ(ok.response.status, 200);
    EXPECT_EQ(ok.response.body, "fine");
}

TEST(RouteTable, ParametersAreDecodedSegmentsOrTheRestOfThePath) {
    RouteTable routes;
    std::vector<std::string> seen;
    const auto record = [&](RouteCall& call) {
        seen = call.params;
        return text("ok");
    };
    routes.get("/v1/scene/meshes/{id}", record);
    routes.get("/v1/scene/groups/{id}/children", record);
    routes.get("/web/{path...}", record);
    EXPECT_EQ(run(routes, "GET", "/v1/scene/meshes/a%2Fb%25c").response.status, 200);
    EXPECT_EQ(seen, std::vector<std::string>{"a/b%c"});
    EXPECT_EQ(run(routes, "GET", "/v1/scene/groups/g%20h/children").response.status, 200);
    EXPECT_EQ(seen, std::vector<std::string>{"g h"});
    EXPECT_EQ(run(routes, "GET", "/web/js/app%2Ejs").response.status, 200);
    EXPECT_EQ(seen, std::vector<std::string>{"js/app.js"});
    // An empty segment or rest matches no parameter; extra segments match no route.
    EXPECT_EQ(run(routes, "GET", "/v1/scene/meshes/").response.status, 404);
    EXPECT_EQ(run(routes, "GET", "/web/").response.status, 404);
    EXPECT_EQ(run(routes, "GET", "/v1/scene/meshes/a/b").response.status, 404);
    EXPECT_EQ(run(routes, "GET", "/v1/scene/groups/g/children/x").response.status, 404);
}

TEST(RouteTable, UnknownPathsAre404AndOtherMethods405WithAllow) {
    RouteTable routes;
    routes.post("/v1/render", [](RouteCall&) { return text("post"); });
    routes.get("/v1/render", [](RouteCall&) { return text("get"); });
    routes.post("/v1/edits", [](RouteCall&) { return text("edits"); });
    const Reply missing = run(routes, "GET", "/v1/nothing");
    EXPECT_EQ(missing.response.status, 404);
    EXPECT_NE(missing.response.body.find("no route for GET /v1/nothing"), std::string::npos);
    const Reply put = run(routes, "PUT", "/v1/render");
    EXPECT_EQ(put.response.status, 405);
    EXPECT_EQ(put.response.header("Allow"), "GET, POST, HEAD");
    EXPECT_EQ(run(routes, "GET", "/v1/edits").response.header("Allow"), "POST");
    EXPECT_EQ(run(routes, "OPTIONS", "/v1/edits").response.status, 405);
    // HEAD runs the GET handler; the writer leaves the body out.
    EXPECT_EQ(run(routes, "HEAD", "/v1/render").response.body, "get");
    EXPECT_EQ(run(routes, "POST", "/v1/render").response.body, "post");
}

}  // namespace
}  // namespace strata::server
