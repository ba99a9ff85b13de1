#pragma once
// Bearer-token authentication: the token file, the header check and the loopback rule.

#include <string>
#include <string_view>

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

/// True for addresses that only this machine can reach: 127.0.0.0/8, ::1 and "localhost".
bool is_loopback_host(const std::string& host);

}  // namespace strata::server
