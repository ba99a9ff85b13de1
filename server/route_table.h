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

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/api.h"
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

class RouteTable {
public:
    using Handler = std::function<Reply(RouteCall&)>;

    /// GET (and HEAD) on `pattern`.
    void get(std::string_view pattern, Handler handler) { add("GET", pattern, std::move(handler)); }
    void post(std::string_view pattern, Handler handler) {
        add("POST", pattern, std::move(handler));
    }
    void add(std::string method, std::string_view pattern, Handler handler);

    /// Runs the handler of `request`'s method and path; never throws.
    Reply dispatch(HttpRequest& request, RequestContext& context) const;

private:
    struct Route {
        std::vector<std::string> segments;  ///< "{name}" and a last "{name...}" are parameters
        std::vector<std::pair<std::string, Handler>> handlers;  ///< by method
        std::string allow;                                      ///< "GET, HEAD, POST"
    };
    /// Whether `path`, split into `parts`, matches `route`; its parameters go to `params`.
    static bool match(const Route& route, std::string_view path,
                      const std::vector<std::string_view>& parts, std::vector<std::string>& params);

    std::vector<Route> m_routes;
};

}  // namespace strata::server
