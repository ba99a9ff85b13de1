// strata-server: the engine behind JSON over HTTP. Flags: strata-server --help.

#include <csignal>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "engine/scene/demo_scene.h"
#include "server/cli.h"
#include "server/healthcheck.h"
#include "server/server.h"
#include "server/shutdown.h"

namespace {

using namespace strata;

/// Serves until SIGTERM or SIGINT; returns the process exit code.
int serve(server::CommandLine& cl) {
    server::ShutdownSignals signals;  // before any thread starts, so that all inherit the mask

    auto engine = Engine::create();
    if (!engine) {
        spdlog::critical("cannot start the engine: {}", engine.error().describe());
        return 1;
    }
    if (cl.config.demo) {
        auto applied = engine.value()->apply(make_demo_scene());
        if (!applied) {
            spdlog::critical("demo scene rejected: {}", applied.error().describe());
            return 1;
        }
        spdlog::info("demo scene loaded (version {})", applied.value().version);
    }

    server::Server http(cl.config, *engine.value());
    auto port = http.bind();
    if (!port) {
        spdlog::critical("{}", port.error().message);
        return 1;
    }
    signals.start([&http](int signo) {
        spdlog::info("{} received: finishing in-flight requests",
                     signo == SIGINT ? "SIGINT" : "SIGTERM");
        http.stop();
    });
    spdlog::info("strata-server listening on http://{}:{} ({} threads, {})", cl.config.host,
                 port.value(), cl.config.threads,
                 cl.config.token.empty() ? "no authentication"
                                         : "bearer token required, from " + cl.token_source);
    http.listen();
    spdlog::info("stopped");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    auto parsed = server::parse_command_line(argc, argv);
    if (auto* code = std::get_if<int>(&parsed)) return *code;
    auto& cl = std::get<server::CommandLine>(parsed);
    if (cl.healthcheck) return server::run_healthcheck(cl.config.host, cl.config.port);

    spdlog::set_default_logger(spdlog::stderr_color_mt("strata"));
    spdlog::set_level(spdlog::level::from_str(cl.log_level));
    spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

    if (const std::string problem = server::finish_config(cl); !problem.empty()) {
        spdlog::critical("{}", problem);
        return 2;
    }
    return serve(cl);
}
