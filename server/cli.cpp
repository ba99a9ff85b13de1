#include "server/cli.h"

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
                   "Address to listen on; a non-loopback one needs --token-file or --insecure");
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
                   "'Authorization: Bearer <token>'")
        ->check(CLI::ExistingFile);
    app.add_flag("--insecure", cl.insecure, "Allow a non-loopback --host without a token");
    app.add_flag("--demo", c.demo, "Start with the demo scene");
    app.add_option("--log-level", cl.log_level, "trace, debug, info, warn, error, critical or off")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    c.max_body_bytes = max_body_mb << 20;
    return cl;
}

std::string finish_config(CommandLine& cl) {
    if (!cl.token_file.empty()) {
        auto token = read_token_file(cl.token_file);
        if (!token) return token.error().message;
        cl.config.token = std::move(token.value());
    }
    if (cl.config.token.empty() && !cl.insecure && !is_loopback_host(cl.config.host))
        return "refusing to listen on non-loopback address '" + cl.config.host +
               "' without --token-file (pass --insecure to allow it)";
    return {};
}

}  // namespace strata::server
