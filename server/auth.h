#pragma once
// Bearer-token authentication: the token file, the header check and the loopback rule.

#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "engine/core/result.h"

namespace strata::server {

/// Checks a token's text: surrounding whitespace is trimmed; an empty token, or one with
/// whitespace or non-ASCII inside, is an error naming `source` (never the token).
Result<std::string> parse_token(std::string_view text, const std::string& source);

/// Largest token file read; a bigger one is refused (it cannot be a token).
inline constexpr std::size_t MAX_TOKEN_FILE_BYTES = 4096;

/// Reads a token file with parse_token; an unreadable file, one that is not a regular file, and
/// one larger than MAX_TOKEN_FILE_BYTES are errors too.
Result<std::string> read_token_file(const std::string& path);

/// True when `authorization` is "Bearer <token>" (scheme case-insensitive) with the right token.
/// The token comparison takes the same time wherever the first difference is.
bool bearer_token_matches(std::string_view authorization, std::string_view token);

/// What a token may do in a scene; each role includes the ones before it. Read: GET, renders,
/// picks, streams. Edit: edits, undo, imports, snapshots loaded. Admin: create and delete it.
enum class Role : uint8_t { None, Read, Edit, Admin };
const char* role_name(Role role);

/// One token's roles: per scene name ("default" included), and for every scene ("*").
struct Grants {
    std::map<std::string, Role, std::less<>> scenes;
    Role every = Role::None;
    /// The role in `scene`: the higher of its own and every scene's.
    Role in(std::string_view scene) const;
};

/// --tokens-file: several tokens, each with its roles per scene.
struct TokenTable {
    std::vector<std::pair<std::string, std::shared_ptr<const Grants>>> entries;
};

/// Largest tokens file read.
inline constexpr std::size_t MAX_TOKENS_FILE_BYTES = std::size_t(1) << 20;

/// The tokens file's text: one token per line followed by its grants, `SCENE:ROLE` separated by
/// spaces (SCENE a scene name, "default" or "*"; ROLE read, edit or admin); blank lines and
/// lines starting with '#' are skipped. Errors name `source` and the line, never a token.
Result<TokenTable> parse_token_table(std::string_view text, const std::string& source);
/// Reads and parses a tokens file (a regular file of at most MAX_TOKENS_FILE_BYTES).
Result<TokenTable> read_token_table(const std::string& path);
/// The grants of the token `authorization` ("Bearer <token>") carries; null when none matches.
/// Every token of the table is compared, each in constant time.
std::shared_ptr<const Grants> match_grants(const TokenTable& table,
                                           std::string_view authorization);

/// True for addresses that only this machine can reach: 127.0.0.0/8, ::1 and "localhost".
bool is_loopback_host(const std::string& host);

}  // namespace strata::server
