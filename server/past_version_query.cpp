// `at_version` and `at_time` query parameters (past_version_query.h).

#include "server/past_version_query.h"

#include <charconv>

#include "protocol/api.h"

namespace strata::server {

namespace {

protocol::Problem bad_past(const char* parameter, std::string detail) {
    protocol::Problem p =
        protocol::make_problem(protocol::ProblemType::InvalidRequest, std::move(detail));
    p.pointer = std::string("/") + parameter;
    return p;
}

}  // namespace

Expected<std::optional<uint64_t>, protocol::Problem> asked_version(
    const Engine& live, std::multimap<std::string, std::string>& query) {
    const auto it = query.find("at_version");
    const auto time = query.find("at_time");
    if (it == query.end() && time == query.end()) return std::optional<uint64_t>();
    if (it != query.end() && time != query.end())
        return Unexpected(bad_past("at_time", "give at_version or at_time, not both"));
    if (time != query.end()) {
        if (query.count("at_time") > 1)
            return Unexpected(bad_past("at_time", "at_time is given twice"));
        auto found = protocol::version_at_time(live, time->second);
        if (!found) return Unexpected(std::move(found.error()));
        query.erase("at_time");
        return std::optional(found.value());
    }
    uint64_t version = 0;
    const std::string& text = it->second;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), version);
    if (query.count("at_version") > 1 || text.empty() || ec != std::errc() ||
        end != text.data() + text.size())
        return Unexpected(bad_past("at_version",
                                   "at_version must be one scene version (a whole number), not '" +
                                       text.substr(0, 40) + "'"));
    query.erase("at_version");
    return std::optional(version);
}

protocol::Problem past_version_problem(const Error& e) {
    const bool missing = e.code == ErrorCode::OutOfRange || e.code == ErrorCode::InvalidArgument;
    if (!missing) return protocol::problem_from(e);
    protocol::Problem p =
        protocol::make_problem(protocol::ProblemType::NotFound, "at_version: " + e.message);
    p.pointer = "/at_version";
    return p;
}

void describe_past_version(protocol::RouteDoc& doc, const char* how) {
    doc.parameters.push_back(
        {.name = "at_version",
         .description = std::string("read the scene as it was at this version: ") + how,
         .schema = R"({"type": "integer", "minimum": 0})"});
    doc.parameters.push_back(
        {.name = "at_time",
         .description = "read the scene as it was at this time (RFC 3339): the newest version "
                        "the history lists that was made at or before it, then as at_version",
         .schema = R"({"type": "string", "format": "date-time"})"});
    doc.responses.push_back(protocol::problem(
        404, "at_version names a version that does not exist or that the data directory "
             "no longer holds, or the server runs without --data; at_time is older "
             "than the history's oldest version"));
}

}  // namespace strata::server
