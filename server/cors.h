#pragma once
// Cross-origin access (--cors-origin): which browser origins may call the API from a page served
// elsewhere, the headers their answers carry, and the answer to a preflight (OPTIONS). Applied
// by the response writer (response_writer.h) to every answer: the workers', the front end's own
// refusals and the streams' heads.

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"

namespace strata::server {

class CorsPolicy {
public:
    /// `spec`: empty (no cross-origin access), "*" (any origin), or a comma-separated list of
    /// origins such as "https://viewer.example.org,http://localhost:8000" (scheme, host and
    /// optional port; no path). An error names the entry that is not an origin.
    static Result<CorsPolicy> parse(std::string_view spec);

    /// The Access-Control-Allow-Origin value for a request's Origin header, or nothing when that
    /// origin is not allowed (or there is no Origin).
    std::optional<std::string> allow(const std::string* origin) const;

    bool enabled() const { return m_any || !m_origins.empty(); }

private:
    bool m_any = false;
    std::vector<std::string> m_origins;
};

/// The header lines (each ending in CRLF) of an answer to an allowed origin.
std::string cors_header_lines(std::string_view allowed_origin);

/// Methods and request headers a preflight allows.
inline constexpr const char* CORS_ALLOW_METHODS = "GET, HEAD, POST, PUT, DELETE, OPTIONS";
inline constexpr const char* CORS_ALLOW_HEADERS = "Authorization, Content-Type, If-Match";

}  // namespace strata::server
