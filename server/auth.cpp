#include "server/auth.h"

#include <arpa/inet.h>
#include <sys/stat.h>

#include <fstream>

namespace strata::server {

Result<std::string> parse_token(std::string_view text, const std::string& source) {
    const auto first = text.find_first_not_of(" \t\r\n");
    if (first == std::string_view::npos)
        return failure(ErrorCode::InvalidArgument, source + " is empty");
    const auto last = text.find_last_not_of(" \t\r\n");
    std::string token(text.substr(first, last - first + 1));
    for (unsigned char c : token) {
        if (c < 0x21 || c > 0x7E)
            return failure(ErrorCode::InvalidArgument,
                           source + " holds whitespace or non-ASCII characters inside the token");
    }
    return token;
}

Result<std::string> read_token_file(const std::string& path) {
    const std::string source = "token file '" + path + "'";
    // A regular file only: a FIFO could block start-up forever, /dev/zero never ends.
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
        return failure(ErrorCode::InvalidArgument,
                       "cannot read " + source + ": not a readable regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) return failure(ErrorCode::InvalidArgument, "cannot read " + source);
    std::string text(MAX_TOKEN_FILE_BYTES + 1, '\0');
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(std::size_t(in.gcount()));
    if (text.size() > MAX_TOKEN_FILE_BYTES)
        return failure(ErrorCode::InvalidArgument, source + " is larger than " +
                                                          std::to_string(MAX_TOKEN_FILE_BYTES) +
                                                          " bytes; it should hold the token alone");
    return parse_token(text, source);
}

bool bearer_token_matches(std::string_view authorization, std::string_view token) {
    constexpr std::string_view SCHEME = "bearer ";
    if (authorization.size() < SCHEME.size()) return false;
    for (std::size_t i = 0; i < SCHEME.size(); ++i) {
        const char c = authorization[i];
        if ((c >= 'A' && c <= 'Z' ? char(c + 32) : c) != SCHEME[i]) return false;
    }
    std::string_view given = authorization.substr(SCHEME.size());
    while (!given.empty() && given.front() == ' ') given.remove_prefix(1);
    while (!given.empty() && given.back() == ' ') given.remove_suffix(1);
    // Constant time in the token's content: every byte of the longer string is looked at.
    const std::size_t n = std::max(given.size(), token.size());
    unsigned diff = given.size() == token.size() ? 0u : 1u;
    for (std::size_t i = 0; i < n; ++i) {
        const unsigned char a = i < given.size() ? static_cast<unsigned char>(given[i]) : 0;
        const unsigned char b = i < token.size() ? static_cast<unsigned char>(token[i]) : 0;
        diff |= unsigned(a ^ b);
    }
    return diff == 0 && !token.empty();
}

bool is_loopback_host(const std::string& host) {
    if (host == "localhost") return true;
    in_addr v4{};
    if (inet_pton(AF_INET, host.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
    in6_addr v6{};
    if (inet_pton(AF_INET6, host.c_str(), &v6) == 1) return IN6_IS_ADDR_LOOPBACK(&v6);
    return false;
}

}  // namespace strata::server
