// strata-server: the engine behind JSON over HTTP. Flags: strata-server --help.

#include <sys/resource.h>

#include <csignal>

#include <spdlog/spdlog.h>

#include "engine/scene/demo_scene.h"
#include "server/cli.h"
#include "server/healthcheck.h"
#include "server/log_sink.h"
#include "server/server.h"
#include "server/shutdown.h"

namespace {

using namespace strata;

/// Raises the soft limit on open files to the hard one: each connection holds a descriptor.
/// Returns the limit in force.
rlim_t raise_file_limit() {
    rlimit lim{};
    if (getrlimit(RLIMIT_NOFILE, &lim) != 0) return 1024;
    if (lim.rlim_cur < lim.rlim_max) {
        lim.rlim_cur = lim.rlim_max;
        setrlimit(RLIMIT_NOFILE, &lim);
        getrlimit(RLIMIT_NOFILE, &lim);
    }
    return lim.rlim_cur;
}

/// Serves until SIGTERM or SIGINT; returns the process exit code.
int serve(server::CommandLine& cl) {
    server::ShutdownSignals signals;  // before any thread starts, so that all inherit the mask
    // Writes to a connection the client closed fail with EPIPE instead of killing the process.
    std::signal(SIGPIPE, SIG_IGN);
    const rlim_t files = raise_file_limit();
    if (files != RLIM_INFINITY && files < cl.config.max_connections + 64) {
        spdlog::warn(
            "only {} open files allowed (ulimit -n): lowering --max-connections from {} "
            "to {}",
            files, cl.config.max_connections, files > 128 ? files - 64 : 64);
        cl.config.max_connections = files > 128 ? std::size_t(files - 64) : 64;
    }

    EngineConfig engine_config;
    engine_config.budget = {cl.config.max_scene_triangles, cl.config.max_scene_vertices};
    engine_config.accel.tlas = *parse_tlas_kind(cl.config.tlas);  // checked by the parser
    engine_config.accel.tlas_policy.max_dynamic_fraction = cl.config.tlas_max_dynamic_fraction;
    engine_config.accel.tlas_policy.min_instances = cl.config.tlas_min_instances;
    engine_config.accel.tlas_policy.background_merge = cl.config.tlas_background_merge;
    auto engine = Engine::create(engine_config);
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
    signals.start([&http, &cl](int signo) {
        spdlog::info(
            "{} received: finishing in-flight requests (renders still running after {} "
            "s are stopped; a second signal exits at once)",
            signo == SIGINT ? "SIGINT" : "SIGTERM", cl.config.shutdown_grace_s);
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

    spdlog::set_default_logger(server::make_safe_logger("strata"));
    spdlog::set_level(spdlog::level::from_str(cl.log_level));
    spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

    if (const std::string problem = server::finish_config(cl); !problem.empty()) {
        spdlog::critical("{}", problem);
        return 2;
    }
    return serve(cl);
}
