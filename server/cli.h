#pragma once
// The strata-server command line.

#include <string>
#include <variant>

#include "server/server_config.h"

namespace strata::server {

/// What the command line asks for.
struct CommandLine {
    ServerConfig config;
    std::string token_file;
    std::string log_level = "info";
    bool insecure = false;
};

/// Parses argv. Returns the exit code instead when the program should stop now (--help: 0,
/// a usage error: 2), having printed what to print.
std::variant<CommandLine, int> parse_command_line(int argc, char** argv);

/// Reads the token file and enforces the loopback rule: a non-loopback --host needs a token
/// unless --insecure is given. Returns the error message, or "" when the server may start.
std::string finish_config(CommandLine& cl);

}  // namespace strata::server
