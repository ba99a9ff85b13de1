#pragma once
// The request target, split and normalised once at the front end (RFC 3986 section 6.2.2):
// percent-escapes of unreserved characters are decoded and the others kept upper-case, so routes
// match one spelling of each path and a segment such as an id holding '/' (sent as %2F) stays one
// segment until the route decodes it. The query is decoded strictly: a malformed escape, invalid
// UTF-8, a control character or a repeated name is a 400 naming the parameter.

#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "server/http_parser.h"

namespace strata::server {

/// A request target that passed every check.
struct RequestTarget {
    /// Percent-encoded path: unreserved characters decoded, other escapes as upper-case %XX.
    std::string path;
    /// Decoded query parameters (valid UTF-8, no control characters, names unique), in order.
    std::vector<std::pair<std::string, std::string>> query;
};

/// Splits and checks an origin-form ("/path?query") or absolute-form ("http://host/path")
/// target.
std::variant<RequestTarget, protocol::Problem> parse_request_target(std::string_view raw);

/// Decodes the percent-escapes of one path segment as RequestTarget::path holds it.
std::string decode_path_segment(std::string_view segment);

}  // namespace strata::server
