#pragma once
// The server's routes: method and path pattern to handler. A handler takes the request the front
// end already read and checked (http_request.h) and returns a Reply: a response, or the head of
// a stream the front end then writes. GET routes answer HEAD too (the writer leaves the body
// out); a known path asked with another method gets 405 with Allow, an unknown one 404, and an
// exception escaping a handler a 500 problem.
//
// Patterns are literal segments and parameters: "/v1/scene/meshes/{id}" matches one non-empty
// segment, "/web/{path...}" the non-empty rest of the path. Parameters reach the handler
// percent-decoded, in pattern order.
//
// Each route is registered with its description (protocol/openapi.h, RouteDoc): summary,
// parameters, body and answers by status. listing() hands them to the OpenAPI generator, which
// GET /v1/openapi.json serves; routes the front end answers itself (/livez, /readyz) are
// described here too, without a handler.

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/api.h"
#include "protocol/openapi.h"
#include "protocol/problem.h"
#include "server/http_request.h"

namespace strata::server {

class StreamChannel;

/// What a handler answers.
struct Reply {
    /// The response; for a stream, its status, headers and the bytes before the first part.
    protocol::ApiResponse response;
    /// Set: the front end writes this channel's parts after `response` (no Content-Length).
    std::shared_ptr<StreamChannel> stream;

    Reply(protocol::ApiResponse r) : response(std::move(r)) {}  // NOLINT: implicit by design
    Reply(const protocol::Problem& p) : response(protocol::problem_response(p)) {}  // NOLINT
    static Reply streaming(protocol::ApiResponse head, std::shared_ptr<StreamChannel> channel) {
        Reply r(std::move(head));
        r.stream = std::move(channel);
        return r;
    }
};

/// One request as a handler sees it.
struct RouteCall {
    HttpRequest& request;             ///< the handler may move the body out
    std::vector<std::string> params;  ///< decoded path parameters, in pattern order
    RequestContext& context;
};

/// The answer to a method a known path does not serve: 405 with `Allow`.
protocol::ApiResponse method_not_allowed(std::string_view method, std::string_view path,
                                         const std::string& allow);

using RouteHandler = std::function<Reply(RouteCall&)>;

/// A route's handler with its description.
struct Endpoint {
    protocol::RouteDoc doc;
    RouteHandler handler;
};

class RouteTable {
public:
    using Handler = RouteHandler;

    /// GET (and HEAD) on `pattern`.
    void get(std::string_view pattern, Endpoint e) { add("GET", pattern, std::move(e)); }
    void post(std::string_view pattern, Endpoint e) { add("POST", pattern, std::move(e)); }
    /// A route without a description (tests of the table itself).
    void get(std::string_view pattern, Handler handler) { get(pattern, {{}, std::move(handler)}); }
    void post(std::string_view pattern, Handler handler) {
        post(pattern, {{}, std::move(handler)});
    }
    void add(std::string method, std::string_view pattern, Endpoint e);
    /// Describes a route the front end answers before the table sees the request (/livez):
    /// listed, never dispatched.
    void describe(std::string method, std::string_view pattern, protocol::RouteDoc doc);

    /// Runs the handler of `request`'s method and path; never throws.
    Reply dispatch(HttpRequest& request, RequestContext& context) const;

    /// Every route with its description, in registration order (the described-only ones
    /// last): what the OpenAPI generator reads.
    std::vector<protocol::RouteListing> listing() const;

private:
    struct Method {
        std::string method;
        protocol::RouteDoc doc;
        Handler handler;
    };
    struct Route {
        std::string pattern;
        std::vector<std::string> segments;  ///< "{name}" and a last "{name...}" are parameters
        std::vector<Method> handlers;       ///< by method
        std::string allow;                  ///< "GET, HEAD, POST"
    };
    /// Whether `path`, split into `parts`, matches `route`; its parameters go to `params`.
    static bool match(const Route& route, std::string_view path,
                      const std::vector<std::string_view>& parts, std::vector<std::string>& params);

    std::vector<Route> m_routes;
    std::vector<Route> m_described;  ///< answered by the front end
};

}  // namespace strata::server
