#include "server/replica/redis_url.h"

#include <charconv>

namespace strata::replica {

namespace {

Unexpected<Error> bad(std::string_view url, const std::string& why) {
    return failure(ErrorCode::InvalidArgument, "--log '" + std::string(url.substr(0, 200)) + "': " +
                                                   why + " (expected redis://HOST:PORT/STREAM)");
}

bool plain_name_char(char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' ||
           c == '.' || c == '_';
}

}  // namespace

std::string RedisUrl::describe() const {
    const bool v6 = host.find(':') != std::string::npos;
    return "redis://" + (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port) + "/" + stream;
}

Result<RedisUrl> parse_redis_url(std::string_view url) {
    constexpr std::string_view SCHEME = "redis://";
    if (url.substr(0, SCHEME.size()) != SCHEME) return bad(url, "the scheme must be redis://");
    std::string_view rest = url.substr(SCHEME.size());
    const std::size_t slash = rest.find('/');
    if (slash == std::string_view::npos) return bad(url, "the stream name is missing");
    std::string_view authority = rest.substr(0, slash);
    const std::string_view stream = rest.substr(slash + 1);
    if (authority.find('@') != std::string_view::npos)
        return bad(url, "credentials in the URL are not supported");

    RedisUrl out;
    // Step: the host, bracketed when it is an IPv6 address.
    std::string_view port_text;
    if (!authority.empty() && authority.front() == '[') {
        const std::size_t close = authority.find(']');
        if (close == std::string_view::npos) return bad(url, "an IPv6 host lacks its ']'");
        out.host = std::string(authority.substr(1, close - 1));
        std::string_view after = authority.substr(close + 1);
        if (!after.empty()) {
            if (after.front() != ':') return bad(url, "junk after the IPv6 host");
            port_text = after.substr(1);
            if (port_text.empty()) return bad(url, "the port after ':' is empty");
        }
        for (char c : out.host)
            if (!(plain_name_char(c) || c == ':')) return bad(url, "the IPv6 host is malformed");
    } else {
        const std::size_t colon = authority.find(':');
        out.host = std::string(authority.substr(0, colon));
        if (colon != std::string_view::npos) {
            port_text = authority.substr(colon + 1);
            if (port_text.empty()) return bad(url, "the port after ':' is empty");
        }
        for (char c : out.host)
            if (!plain_name_char(c)) return bad(url, "the host has a character it cannot have");
    }
    if (out.host.empty()) return bad(url, "the host is missing");

    // Step: the port.
    if (!port_text.empty()) {
        int port = 0;
        const auto [end, ec] =
            std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
        if (ec != std::errc() || end != port_text.data() + port_text.size() || port < 1 ||
            port > 65535)
            return bad(url, "the port must be a number from 1 to 65535");
        out.port = port;
    }

    // Step: the stream, one segment of printable ASCII.
    if (stream.empty()) return bad(url, "the stream name is missing");
    if (stream.size() > 200) return bad(url, "the stream name is longer than 200 characters");
    for (char c : stream)
        if (c <= ' ' || c > '~' || c == '/' || c == '?' || c == '#')
            return bad(url, "the stream name must be one path segment of printable characters");
    out.stream = std::string(stream);
    return out;
}

}  // namespace strata::replica
