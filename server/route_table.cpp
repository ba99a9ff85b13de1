#include "server/route_table.h"

#include <algorithm>

#include <spdlog/spdlog.h>

#include "protocol/safe_text.h"
#include "server/request_target.h"

namespace strata::server {

namespace {

using protocol::ProblemType;

bool is_parameter(std::string_view segment) {
    return segment.size() > 2 && segment.front() == '{' && segment.back() == '}';
}

bool is_rest_parameter(std::string_view segment) {
    return is_parameter(segment) && segment.size() > 5 &&
           segment.substr(segment.size() - 4) == "...}";
}

/// "/a/b/c" -> {"a", "b", "c"}; "/" -> {""}.
std::vector<std::string_view> split_path(std::string_view path) {
    std::vector<std::string_view> out;
    if (!path.empty() && path.front() == '/') path.remove_prefix(1);
    for (;;) {
        const std::size_t slash = path.find('/');
        out.push_back(path.substr(0, slash));
        if (slash == std::string_view::npos) return out;
        path.remove_prefix(slash + 1);
    }
}

/// What a handler's exception becomes: logged with the request, answered without internals.
protocol::ApiResponse internal_error(const HttpRequest& request, const char* what) {
    spdlog::error("{} {}: unhandled exception: {}", request.method, request.path,
                  protocol::escape_for_log(what));
    return protocol::problem_response(
        protocol::make_problem(ProblemType::Internal, "internal error while handling the request"));
}

}  // namespace

protocol::ApiResponse method_not_allowed(std::string_view method, std::string_view path,
                                         const std::string& allow) {
    protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
        ProblemType::MethodNotAllowed, std::string(method) + " is not allowed on " +
                                           std::string(path) + " (allowed: " + allow + ")"));
    r.headers.emplace_back("Allow", allow);
    return r;
}

void RouteTable::add(std::string method, std::string_view pattern, Endpoint e) {
    std::vector<std::string> segments;
    for (std::string_view s : split_path(pattern)) segments.emplace_back(s);
    auto it = std::find_if(m_routes.begin(), m_routes.end(),
                           [&](const Route& r) { return r.segments == segments; });
    if (it == m_routes.end())
        it = m_routes.insert(m_routes.end(), Route{std::string(pattern), segments, {}, {}});
    it->handlers.push_back({std::move(method), std::move(e.doc), std::move(e.handler)});
    // Allow: the methods in alphabetical order, then HEAD when GET is served.
    std::vector<std::string> methods;
    for (const Method& m : it->handlers) methods.push_back(m.method);
    std::sort(methods.begin(), methods.end());
    it->allow.clear();
    for (const std::string& m : methods) it->allow += (it->allow.empty() ? "" : ", ") + m;
    if (std::count(methods.begin(), methods.end(), "GET")) it->allow += ", HEAD";
}

void RouteTable::describe(std::string method, std::string_view pattern, protocol::RouteDoc doc) {
    m_described.push_back(
        {std::string(pattern), {}, {{std::move(method), std::move(doc), {}}}, {}});
}

std::vector<protocol::RouteListing> RouteTable::listing() const {
    std::vector<protocol::RouteListing> out;
    for (const auto* routes : {&m_routes, &m_described}) {
        for (const Route& r : *routes) {
            for (const Method& m : r.handlers) out.push_back({m.method, r.pattern, &m.doc});
        }
    }
    return out;
}

bool RouteTable::match(const Route& route, std::string_view path,
                       const std::vector<std::string_view>& parts,
                       std::vector<std::string>& params) {
    params.clear();
    for (std::size_t i = 0; i < route.segments.size(); ++i) {
        const std::string& want = route.segments[i];
        if (i >= parts.size()) return false;
        if (is_rest_parameter(want)) {
            // The rest of the path, slashes included: from this segment's start to the end.
            const std::string_view rest = path.substr(std::size_t(parts[i].data() - path.data()));
            if (rest.empty()) return false;
            params.push_back(decode_path_segment(rest));
            return true;
        }
        if (is_parameter(want)) {
            if (parts[i].empty()) return false;
            params.push_back(decode_path_segment(parts[i]));
        } else if (want != parts[i]) {
            return false;
        }
    }
    return parts.size() == route.segments.size();
}

Reply RouteTable::dispatch(HttpRequest& request, RequestContext& context) const {
    RouteCall call{request, {}, context};
    const std::vector<std::string_view> parts = split_path(request.path);
    const auto route = std::find_if(m_routes.begin(), m_routes.end(), [&](const Route& r) {
        return match(r, request.path, parts, call.params);
    });
    if (route == m_routes.end()) {
        // The path is the normalised target: ASCII, non-printable bytes percent-encoded.
        return protocol::make_problem(ProblemType::NotFound,
                                      "no route for " + request.method + " " + request.path);
    }
    const std::string_view method =
        request.method == "HEAD" ? std::string_view("GET") : std::string_view(request.method);
    const auto handler = std::find_if(route->handlers.begin(), route->handlers.end(),
                                      [&](const Method& h) { return h.method == method; });
    if (handler == route->handlers.end())
        return method_not_allowed(request.method, request.path, route->allow);
    try {
        return handler->handler(call);
    } catch (const std::exception& e) {
        return internal_error(request, e.what());
    } catch (...) {
        return internal_error(request, "unknown exception");
    }
}

}  // namespace strata::server
