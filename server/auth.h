#pragma once
// Bearer-token authentication: the token file, the header check and the loopback rule.

#include <string>
#include <string_view>

#include "engine/core/result.h"

namespace strata::server {

/// Checks a token's text: surrounding whitespace is trimmed; an empty token, or one with
/// whitespace or non-ASCII inside, is an error naming `source` (never the token).
Result<std::string> parse_token(std::string_view text, const std::string& source);

/// Reads a token file with parse_token; an unreadable file is an error too.
Result<std::string> read_token_file(const std::string& path);

/// True when `authorization` is "Bearer <token>" (scheme case-insensitive) with the right token.
/// The token comparison takes the same time wherever the first difference is.
bool bearer_token_matches(std::string_view authorization, std::string_view token);

/// True for addresses that only this machine can reach: 127.0.0.0/8, ::1 and "localhost".
bool is_loopback_host(const std::string& host);

}  // namespace strata::server
