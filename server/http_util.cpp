#include "server/http_util.h"

#include <charconv>

namespace strata::server {

void send_json(httplib::Response& res, int status, const protocol::Json& body) {
    res.status = status;
    res.set_content(body.dump(), "application/json");
}

void send_problem(httplib::Response& res, const protocol::Problem& problem) {
    res.status = problem.status;
    res.set_content(protocol::problem_to_json(problem).dump(), "application/problem+json");
}

std::string etag(uint64_t version) {
    return "\"" + std::to_string(version) + "\"";
}

void set_etag(httplib::Response& res, uint64_t version) {
    res.set_header("ETag", etag(version));
}

std::optional<IfMatch> parse_if_match(const httplib::Request& req, protocol::Problem& problem) {
    if (!req.has_header("If-Match")) return IfMatch{};
    std::string v = req.get_header_value("If-Match");
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.pop_back();
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.erase(0, 1);
    if (v == "*") return IfMatch{};
    auto bad = [&](const std::string& why) -> std::optional<IfMatch> {
        problem =
            protocol::make_problem(protocol::ProblemType::InvalidRequest,
                                   "If-Match: " + why + " (expected an entity tag such as \"12\")");
        return std::nullopt;
    };
    if (v.find(',') != std::string::npos)
        return bad("lists of several entity tags are not supported");
    if (v.rfind("W/", 0) == 0) {
        // A weak tag never matches under the strong comparison If-Match requires.
        return IfMatch{UINT64_MAX};
    }
    if (v.size() >= 2 && v.front() == '"' && v.back() == '"') v = v.substr(1, v.size() - 2);
    uint64_t n = 0;
    const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (v.empty() || ec != std::errc() || end != v.data() + v.size())
        return bad("'" + req.get_header_value("If-Match") + "' is not a Strata entity tag");
    return IfMatch{n};
}

}  // namespace strata::server
