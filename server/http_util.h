#pragma once
// Small helpers shared by the route files: JSON and problem responses, entity tags and the
// If-Match precondition.

#include <cstdint>
#include <optional>
#include <string>

#include <httplib.h>

#include "protocol/problem.h"

namespace strata::server {

/// Sends `body` as application/json.
void send_json(httplib::Response& res, int status, const protocol::Json& body);
/// Sends an application/problem+json document with the problem's status.
void send_problem(httplib::Response& res, const protocol::Problem& problem);

/// The entity tag of a scene version: "N" with the quotes.
std::string etag(uint64_t version);
void set_etag(httplib::Response& res, uint64_t version);

/// What If-Match asks for: absent or "*" (no constraint once the scene exists), or one version.
struct IfMatch {
    std::optional<uint64_t> version;
};
/// Parses the If-Match header: `"N"`, `*`, or a bare N for curl users. Weak tags (W/"N") never
/// match (RFC 9110 uses strong comparison); a list of several tags is refused.
std::optional<IfMatch> parse_if_match(const httplib::Request& req, protocol::Problem& problem);

}  // namespace strata::server
