#include "server/router.h"

#include <cstdlib>

#include "server/http_util.h"

namespace strata::server {

using protocol::ProblemType;

namespace {

/// Whether the request carries a body. RFC 9112 section 6.3: a request with neither
/// Content-Length nor Transfer-Encoding has none. (httplib would otherwise read such a request
/// "until close" and stall until the read timeout: `curl -X POST` sends no Content-Length.)
bool has_body(const httplib::Request& req) {
    if (req.has_header("Transfer-Encoding")) return true;
    return req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0";
}

/// Registers `handler` for a method whose body httplib must not read before dispatch.
using BodyMethod = httplib::Server& (httplib::Server::*)(const std::string&,
                                                         httplib::Server::HandlerWithContentReader);

/// Bytes of an over-limit body read and thrown away before answering 413, so that a client still
/// sending (a chunked upload has no Content-Length to refuse up front) gets to read the answer
/// instead of a reset connection. Beyond this the server stops reading and closes.
constexpr std::size_t DRAIN_LIMIT = std::size_t(8) << 20;

/// Answers without reading the body: then the connection cannot be reused.
void refuse_unread(const httplib::Request& req, httplib::Response& res,
                   const protocol::Problem& p) {
    if (has_body(req)) res.set_header("Connection", "close");
    send_problem(res, p);
}

}  // namespace

void Router::get(const std::string& pattern, Handler handler) {
    m_methods[pattern].insert("GET");
    m_http.Get(pattern, std::move(handler));
}

void Router::post(const std::string& pattern, BodyHandler handler) {
    m_methods[pattern].insert("POST");
    const std::size_t max = m_max_body;
    m_http.Post(pattern, [handler = std::move(handler), max](const httplib::Request& req,
                                                             httplib::Response& res,
                                                             const httplib::ContentReader& reader) {
        std::string body;
        if (!has_body(req)) return handler(req, res, std::move(body));
        if (req.has_header("Content-Length")) {
            // Reserve up front; the pre-routing handler already refused lengths over the cap.
            body.reserve(std::min<std::size_t>(
                std::strtoull(req.get_header_value("Content-Length").c_str(), nullptr, 10), max));
        }
        bool too_large = false;
        std::size_t drained = 0;
        const bool ok = reader([&](const char* data, std::size_t n) {
            if (!too_large && body.size() + n <= max) {
                body.append(data, n);
                return true;
            }
            if (!too_large) {
                too_large = true;
                body = std::string();  // free what was kept; the rest is only counted
            }
            drained += n;
            return drained <= DRAIN_LIMIT;
        });
        if (!ok || too_large) {
            res.set_header("Connection", "close");
            if (too_large || res.status == 413) {
                send_problem(res,
                             protocol::make_problem(ProblemType::TooLarge,
                                                    "request body is larger than the limit of " +
                                                        std::to_string(max) + " bytes"));
            } else {
                send_problem(res, protocol::make_problem(ProblemType::InvalidRequest,
                                                         "could not read the request body"));
            }
            return;
        }
        handler(req, res, std::move(body));
    });
}

void Router::finish() {
    static constexpr BodyMethod BODY_METHODS[] = {&httplib::Server::Post, &httplib::Server::Put,
                                                  &httplib::Server::Patch,
                                                  &httplib::Server::Delete};
    for (const auto& [pattern, served] : m_methods) {
        std::string allow;
        for (const std::string& m : served) allow += (allow.empty() ? "" : ", ") + m;
        if (served.count("GET")) allow += ", HEAD";
        auto refuse = [allow](const httplib::Request& req, httplib::Response& res) {
            res.set_header("Allow", allow);
            refuse_unread(req, res,
                          protocol::make_problem(ProblemType::MethodNotAllowed,
                                                 req.method + " is not allowed on " + req.path +
                                                     " (allowed: " + allow + ")"));
        };
        auto refuse_body = [refuse](const httplib::Request& req, httplib::Response& res,
                                    const httplib::ContentReader&) { refuse(req, res); };
        if (!served.count("GET")) m_http.Get(pattern, refuse);
        for (std::size_t i = 0; i < std::size(BODY_METHODS); ++i) {
            // BODY_METHODS[0] is POST, which the pattern may serve.
            if (i != 0 || !served.count("POST")) (m_http.*BODY_METHODS[i])(pattern, refuse_body);
        }
        m_http.Options(pattern, refuse);
    }
    // Unknown paths with a body method: answered here, before httplib would read the body.
    for (BodyMethod method : BODY_METHODS) {
        (m_http.*method)(".*", [](const httplib::Request& req, httplib::Response& res,
                                  const httplib::ContentReader&) {
            refuse_unread(req, res,
                          protocol::make_problem(ProblemType::NotFound,
                                                 "no route for " + req.method + " " + req.path));
        });
    }
}

}  // namespace strata::server
