#pragma once
// The strata-server command line.

#include <string>
#include <variant>

#include "server/server_config.h"

namespace strata::server {

/// The environment variable that may hold the bearer token itself (a token file is given with
/// --token-file or STRATA_TOKEN_FILE; every flag --x-y has a variable STRATA_X_Y).
inline constexpr const char* TOKEN_ENV = "STRATA_TOKEN";

/// Longest --max-uri-bytes. The whole head is bounded by --max-header-bytes as well.
inline constexpr std::size_t MAX_URI_BYTES = 64 * 1024;

/// What the command line and the environment ask for.
struct CommandLine {
    ServerConfig config;
    std::string token_file;
    std::string tokens_file;  ///< --tokens-file: tokens with roles per scene
    std::string token_source;  ///< where the token came from, for the log (never the token)
    std::string log_level = "info";
    bool insecure = false;
    bool healthcheck = false;  ///< probe a running server instead of starting one
};

/// Parses argv, falling back to STRATA_* environment variables for options not on it. Returns
/// the exit code instead when the program should stop now (--help: 0, a usage error: 2), having
/// printed what to print.
std::variant<CommandLine, int> parse_command_line(int argc, char** argv);

/// Reads the token (a token file, or STRATA_TOKEN; both at once is an error) and enforces the
/// loopback rule: a non-loopback --host needs a token unless --insecure is given. Returns the
/// error message, or "" when the server may start.
std::string finish_config(CommandLine& cl);

}  // namespace strata::server
