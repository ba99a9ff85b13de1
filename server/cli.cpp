#include "server/cli.h"

#include <cctype>
#include <cstdlib>
#include <thread>

#include <CLI/CLI.hpp>

#include "server/auth.h"

namespace strata::server {

std::variant<CommandLine, int> parse_command_line(int argc, char** argv) {
    CommandLine cl;
    ServerConfig& c = cl.config;
    c.threads = std::max(8u, std::thread::hardware_concurrency());
    std::size_t max_body_mb = c.max_body_bytes >> 20;

    CLI::App app{
        "strata-server: a dynamic ray-tracing scene server (JSON over HTTP; see "
        "protocol/README.md)"};
    app.option_defaults()->always_capture_default();
    app.add_option("--host", c.host,
                   "Address to listen on; a non-loopback one needs a token (--token-file or "
                   "STRATA_TOKEN) or --insecure");
    app.add_option("--port", c.port, "TCP port (0: any free port)")->check(CLI::Range(0, 65535));
    app.add_option(
           "--threads", c.threads,
           "HTTP worker threads, i.e. connections served at once (rendering uses every core "
           "through TBB regardless)")
        ->check(CLI::Range(1, 1024));
    app.add_option("--data", c.data_dir,
                   "Data directory (reserved for durability; unused for now)");
    app.add_option("--max-body-mb", max_body_mb, "Largest request body, in MiB (413 beyond)")
        ->check(CLI::Range(1, 4096));
    app.add_option("--max-pixels", c.max_pixels,
                   "Largest width * height of one render (413 beyond)")
        ->check(CLI::Range(uint64_t(1), uint64_t(64) << 20));
    app.add_option("--max-json-depth", c.max_json_depth,
                   "Deepest JSON nesting accepted (400 beyond)")
        ->check(CLI::Range(4, 1024));
    app.add_option("--max-array-elements", c.max_array_elements,
                   "Most elements in one JSON array (413 beyond)")
        ->check(CLI::Range(std::size_t(16), std::size_t(1) << 30));
    app.add_option("--read-timeout", c.read_timeout_s, "Seconds to wait for request data")
        ->check(CLI::Range(1, 3600));
    app.add_option("--write-timeout", c.write_timeout_s, "Seconds to wait while sending a response")
        ->check(CLI::Range(1, 3600));
    app.add_option("--token-file", cl.token_file,
                   "File holding a bearer token; then every endpoint but /livez and /readyz needs "
                   "'Authorization: Bearer <token>'. Or give the token itself in STRATA_TOKEN")
        ->check(CLI::ExistingFile);
    app.add_flag("--insecure", cl.insecure, "Allow a non-loopback --host without a token");
    app.add_flag("--demo", c.demo, "Start with the demo scene");
    app.add_option("--log-level", cl.log_level, "trace, debug, info, warn, error, critical or off")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
    // Every option above can also come from the environment, --x-y from STRATA_X_Y (containers
    // are configured that way); the command line wins. --help and --healthcheck are about one
    // invocation, so they have no variable.
    for (CLI::Option* opt : app.get_options()) {
        if (opt->get_lnames().empty() || opt->get_lnames().front() == "help") continue;
        std::string name = "STRATA_" + opt->get_lnames().front();
        for (char& ch : name)
            ch = ch == '-' ? '_' : char(std::toupper(static_cast<unsigned char>(ch)));
        opt->envname(name);
    }
    app.add_flag("--healthcheck", cl.healthcheck,
                 "Start no server: GET /readyz on --host (a wildcard address means 127.0.0.1 or "
                 "::1) and --port, exit 0 on 200 and 1 otherwise");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    c.max_body_bytes = max_body_mb << 20;
    return cl;
}

std::string finish_config(CommandLine& cl) {
    const char* env_token = std::getenv(TOKEN_ENV);
    const bool has_env_token = env_token != nullptr && *env_token != '\0';
    if (!cl.token_file.empty()) {
        if (has_env_token)
            return std::string("both a token file (--token-file or STRATA_TOKEN_FILE) and ") +
                   TOKEN_ENV + " are set; give the token one way only";
        auto token = read_token_file(cl.token_file);
        if (!token) return token.error().message;
        cl.config.token = std::move(token.value());
        cl.token_source = "token file '" + cl.token_file + "'";
    } else if (has_env_token) {
        auto token = parse_token(env_token, TOKEN_ENV);
        if (!token) return token.error().message;
        cl.config.token = std::move(token.value());
        cl.token_source = TOKEN_ENV;
    }
    if (cl.config.token.empty() && !cl.insecure && !is_loopback_host(cl.config.host))
        return "refusing to listen on non-loopback address '" + cl.config.host +
               "' without a token: give --token-file, STRATA_TOKEN_FILE or STRATA_TOKEN (or "
               "--insecure, STRATA_INSECURE=1, to allow it)";
    return {};
}

}  // namespace strata::server
