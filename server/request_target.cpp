#include "server/request_target.h"

#include <optional>

#include "protocol/safe_text.h"

namespace strata::server {

using protocol::make_problem;
using protocol::Problem;
using protocol::ProblemType;

namespace {

constexpr char HEX[] = "0123456789ABCDEF";

int hex_value(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

bool is_unreserved(unsigned char c) {
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '-' ||
           c == '.' || c == '_' || c == '~';
}

void append_escape(std::string& out, unsigned char c) {
    out += '%';
    out += HEX[c >> 4];
    out += HEX[c & 15];
}

/// The byte a "%XX" at s[i] stands for, or -1 when it is not a complete escape.
int escaped_byte(std::string_view s, std::size_t i) {
    if (i + 2 >= s.size()) return -1;
    const int hi = hex_value(s[i + 1]), lo = hex_value(s[i + 2]);
    return hi < 0 || lo < 0 ? -1 : hi * 16 + lo;
}

Problem bad(std::string detail) {
    return make_problem(ProblemType::InvalidRequest, std::move(detail));
}

/// Decodes a query name or value ('+' is a space); nullopt on a malformed escape.
std::optional<std::string> decode_query_part(std::string_view s) {
    std::string out;
    out.reserve(s.size());
    for (std::size_t i = 0; i < s.size(); ++i) {
        if (s[i] == '+') {
            out += ' ';
        } else if (s[i] != '%') {
            out += s[i];
        } else {
            const int b = escaped_byte(s, i);
            if (b < 0) return std::nullopt;
            out += char(b);
            i += 2;
        }
    }
    return out;
}

std::variant<std::vector<std::pair<std::string, std::string>>, Problem> parse_query(
    std::string_view q) {
    std::vector<std::pair<std::string, std::string>> out;
    while (!q.empty()) {
        const std::size_t amp = q.find('&');
        const std::string_view item = q.substr(0, amp);
        q.remove_prefix(amp == std::string_view::npos ? q.size() : amp + 1);
        if (item.empty()) continue;
        const std::size_t eq = item.find('=');
        auto name = decode_query_part(item.substr(0, eq));
        auto value = decode_query_part(eq == std::string_view::npos ? std::string_view()
                                                                    : item.substr(eq + 1));
        if (!name || !value) return bad("malformed percent-escape in the query");
        const std::string shown = "query parameter '" + protocol::escape_for_log(*name) + "'";
        if (name->empty()) return bad("a query parameter has no name");
        for (const std::string* part : {&*name, &*value}) {
            if (!protocol::is_valid_utf8(*part)) return bad(shown + " is not valid UTF-8");
            for (unsigned char c : *part) {
                if (c < 0x20 || c == 0x7F) return bad(shown + " holds a control character");
            }
        }
        for (const auto& [seen, ignored] : out) {
            if (seen == *name) return bad(shown + " is given more than once");
        }
        out.emplace_back(std::move(*name), std::move(*value));
    }
    return out;
}

}  // namespace

std::variant<RequestTarget, Problem> parse_request_target(std::string_view raw) {
    for (std::string_view scheme : {"http://", "https://"}) {
        if (raw.size() >= scheme.size() && iequals(raw.substr(0, scheme.size()), scheme)) {
            // absolute-form (RFC 9112 section 3.2.2): the authority is not ours to route on.
            const std::size_t slash = raw.find_first_of("/?", scheme.size());
            raw = slash == std::string_view::npos ? std::string_view("/") : raw.substr(slash);
            if (raw.front() == '?') return bad("an absolute request target without a path");
        }
    }
    if (raw.empty() || raw.front() != '/')
        return bad("the request target must be a path starting with '/'");
    if (raw.find('#') != std::string_view::npos)
        return bad("a fragment ('#') in the request target");
    const std::size_t qmark = raw.find('?');
    const std::string_view path = raw.substr(0, qmark);
    RequestTarget target;
    target.path.reserve(path.size());
    for (std::size_t i = 0; i < path.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(path[i]);
        if (c < 0x21 || c > 0x7E) return bad("invalid character in the path");
        if (c != '%') {
            target.path += char(c);
            continue;
        }
        const int b = escaped_byte(path, i);
        if (b < 0) return bad("malformed percent-escape in the path");
        if (is_unreserved(static_cast<unsigned char>(b))) {
            target.path += char(b);
        } else {
            append_escape(target.path, static_cast<unsigned char>(b));
        }
        i += 2;
    }
    if (qmark != std::string_view::npos) {
        auto query = parse_query(raw.substr(qmark + 1));
        if (auto* e = std::get_if<Problem>(&query)) return *e;
        target.query = std::move(std::get<0>(query));
    }
    return target;
}

std::string decode_path_segment(std::string_view segment) {
    std::string out;
    out.reserve(segment.size());
    for (std::size_t i = 0; i < segment.size(); ++i) {
        const int b = segment[i] == '%' ? escaped_byte(segment, i) : -1;
        if (b < 0) {
            out += segment[i];
        } else {
            out += char(b);
            i += 2;
        }
    }
    return out;
}

}  // namespace strata::server
