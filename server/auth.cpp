#include "server/auth.h"

#include <arpa/inet.h>
#include <sys/stat.h>

#include <algorithm>
#include <fstream>

#include "protocol/api.h"

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

namespace {

/// A regular file of at most `max` bytes: a FIFO could block start-up forever, /dev/zero never
/// ends.
Result<std::string> read_small_file(const std::string& path, std::size_t max,
                                    const std::string& source, const char* holds) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode))
        return failure(ErrorCode::InvalidArgument,
                       "cannot read " + source + ": not a readable regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) return failure(ErrorCode::InvalidArgument, "cannot read " + source);
    std::string text(max + 1, '\0');
    in.read(text.data(), std::streamsize(text.size()));
    text.resize(std::size_t(in.gcount()));
    if (text.size() > max)
        return failure(ErrorCode::InvalidArgument, source + " is larger than " +
                                                       std::to_string(max) + " bytes; " + holds);
    return text;
}

constexpr const char* ROLE_NAMES[] = {"none", "read", "edit", "admin"};

/// One `SCENE:ROLE` of a tokens file line into `grants`; an error message, or "".
std::string add_grant(std::string_view word, Grants& grants) {
    const std::size_t colon = word.rfind(':');
    if (colon == std::string_view::npos) return "'" + std::string(word) + "' is not SCENE:ROLE";
    const std::string_view scene = word.substr(0, colon);
    const std::string_view name = word.substr(colon + 1);
    Role role = Role::None;
    for (int r = 1; r <= int(Role::Admin); ++r)
        if (name == ROLE_NAMES[r]) role = Role(r);
    if (role == Role::None)
        return "the role '" + std::string(name) + "' is not read, edit or admin";
    if (scene == "*") {
        if (grants.every != Role::None) return "'*' is granted twice";
        grants.every = role;
        return "";
    }
    if (!protocol::valid_scene_name(scene))
        return "'" + std::string(scene) + "' is not a scene name or '*'";
    if (!grants.scenes.emplace(std::string(scene), role).second)
        return "the scene '" + std::string(scene) + "' is granted twice";
    return "";
}

}  // namespace

Result<std::string> read_token_file(const std::string& path) {
    const std::string source = "token file '" + path + "'";
    auto text =
        read_small_file(path, MAX_TOKEN_FILE_BYTES, source, "it should hold the token alone");
    if (!text) return Unexpected(text.error());
    return parse_token(text.value(), source);
}

const char* role_name(Role role) {
    return ROLE_NAMES[int(role)];
}

Role Grants::in(std::string_view scene) const {
    const auto it = scenes.find(scene);
    const Role own = it == scenes.end() ? Role::None : it->second;
    return std::max(own, every);
}

Result<TokenTable> parse_token_table(std::string_view text, const std::string& source) {
    TokenTable table;
    std::size_t line_number = 0;
    while (!text.empty()) {
        const std::size_t end = std::min(text.find('\n'), text.size());
        std::string_view line = text.substr(0, end);
        text.remove_prefix(std::min(end + 1, text.size()));
        ++line_number;
        const std::string where = source + " line " + std::to_string(line_number) + ": ";
        std::vector<std::string_view> words;
        for (std::size_t i = 0; i < line.size();) {
            const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
            if (blank(line[i])) {
                ++i;
                continue;
            }
            const std::size_t start = i;
            for (; i < line.size() && !blank(line[i]); ++i) {
                const unsigned char c = static_cast<unsigned char>(line[i]);
                if (c < 0x21 || c > 0x7E)
                    return failure(ErrorCode::InvalidArgument,
                                   where + "a control or non-ASCII character");
            }
            words.push_back(line.substr(start, i - start));
        }
        if (words.empty() || words[0].front() == '#') continue;
        if (words.size() < 2)
            return failure(ErrorCode::InvalidArgument,
                           where + "a token without grants (SCENE:ROLE after it)");
        for (const auto& [token, grants] : table.entries) {
            if (token == words[0])
                return failure(ErrorCode::InvalidArgument,
                               where + "the token of an earlier line again");
        }
        auto grants = std::make_shared<Grants>();
        for (std::size_t w = 1; w < words.size(); ++w) {
            if (std::string problem = add_grant(words[w], *grants); !problem.empty())
                return failure(ErrorCode::InvalidArgument, where + problem);
        }
        table.entries.emplace_back(std::string(words[0]), std::move(grants));
    }
    if (table.entries.empty())
        return failure(ErrorCode::InvalidArgument, source + " holds no token");
    return table;
}

Result<TokenTable> read_token_table(const std::string& path) {
    const std::string source = "tokens file '" + path + "'";
    auto text = read_small_file(path, MAX_TOKENS_FILE_BYTES, source, "too many tokens");
    if (!text) return Unexpected(text.error());
    return parse_token_table(text.value(), source);
}

std::shared_ptr<const Grants> match_grants(const TokenTable& table,
                                           std::string_view authorization) {
    std::shared_ptr<const Grants> found;
    for (const auto& [token, grants] : table.entries)
        if (bearer_token_matches(authorization, token)) found = grants;
    return found;
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
