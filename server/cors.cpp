#include "server/cors.h"

#include <algorithm>
#include <cctype>

namespace strata::server {

namespace {

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

/// "scheme://host[:port]" with nothing after the authority.
bool is_origin(std::string_view s) {
    const std::size_t sep = s.find("://");
    if (sep == std::string_view::npos || sep == 0) return false;
    const std::string_view authority = s.substr(sep + 3);
    if (authority.empty()) return false;
    return std::none_of(authority.begin(), authority.end(), [](char c) {
        return c == '/' || c == '?' || c == '#' || c == ',' || c <= ' ' || c > '~';
    });
}

}  // namespace

Result<CorsPolicy> CorsPolicy::parse(std::string_view spec) {
    CorsPolicy p;
    spec = trim(spec);
    if (spec.empty()) return p;
    while (!spec.empty()) {
        const std::size_t comma = spec.find(',');
        const std::string_view entry = trim(spec.substr(0, comma));
        spec = comma == std::string_view::npos ? std::string_view() : spec.substr(comma + 1);
        if (entry == "*") {
            p.m_any = true;
        } else if (is_origin(entry)) {
            // Scheme and host compare case-insensitively (RFC 6454); a trailing slash is no part
            // of an origin but a common slip.
            p.m_origins.push_back(lower(entry));
        } else {
            return failure(ErrorCode::InvalidArgument,
                           "--cors-origin: '" + std::string(entry.substr(0, 100)) +
                               "' is not an origin (scheme://host[:port], no path) or '*'");
        }
    }
    return p;
}

std::optional<std::string> CorsPolicy::allow(const std::string* origin) const {
    if (!origin || origin->empty() || !enabled()) return std::nullopt;
    // Echoed rather than '*', so that answers vary by origin the same way in both modes.
    if (m_any) {
        if (!is_origin(*origin) && *origin != "null") return std::nullopt;
        return *origin;
    }
    const std::string key = lower(*origin);
    if (std::find(m_origins.begin(), m_origins.end(), key) == m_origins.end()) return std::nullopt;
    return *origin;
}

std::string cors_header_lines(std::string_view allowed_origin) {
    return "Access-Control-Allow-Origin: " + std::string(allowed_origin) +
           "\r\nVary: Origin\r\n"
           "Access-Control-Expose-Headers: ETag, Retry-After, X-Strata-Rebuild, X-Strata-Report, "
           "X-Strata-Samples\r\n";
}

}  // namespace strata::server
