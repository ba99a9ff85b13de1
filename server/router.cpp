#include "server/router.h"

#include <cstdlib>

#include "server/http_util.h"

namespace strata::server {

using protocol::ProblemType;

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
        if (req.has_header("Content-Length")) {
            // Reserve up front; the pre-routing handler already refused lengths over the cap.
            body.reserve(std::min<std::size_t>(
                std::strtoull(req.get_header_value("Content-Length").c_str(), nullptr, 10), max));
        }
        bool too_large = false;
        const bool ok = reader([&](const char* data, std::size_t n) {
            if (body.size() + n > max) {
                too_large = true;
                return false;
            }
            body.append(data, n);
            return true;
        });
        if (!ok) {
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
    for (const auto& [pattern, served] : m_methods) {
        std::string allow;
        for (const std::string& m : served) allow += (allow.empty() ? "" : ", ") + m;
        if (served.count("GET")) allow += ", HEAD";
        auto refuse = [allow](const httplib::Request& req, httplib::Response& res) {
            res.set_header("Allow", allow);
            send_problem(res, protocol::make_problem(ProblemType::MethodNotAllowed,
                                                     req.method + " is not allowed on " + req.path +
                                                         " (allowed: " + allow + ")"));
        };
        if (!served.count("GET")) m_http.Get(pattern, refuse);
        if (!served.count("POST")) m_http.Post(pattern, refuse);
        m_http.Put(pattern, refuse);
        m_http.Patch(pattern, refuse);
        m_http.Delete(pattern, refuse);
        m_http.Options(pattern, refuse);
    }
}

}  // namespace strata::server
