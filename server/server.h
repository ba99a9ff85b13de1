#pragma once
// The HTTP server: cpp-httplib with Strata's routes, authentication, limits, access log and
// metrics around one Engine.
//
// Concurrency model. httplib runs each connection on a worker of a fixed thread pool (--threads).
// Handlers share nothing but the Engine, which is thread-safe (see engine/engine.h): edits take
// the scene lock briefly and never wait for tracing; commits and renders are serialised by the
// engine's launch mutex, and each render traces exactly the version its own commit produced,
// which is the version its ETag names. If-Match is checked under the same scene lock as the
// apply. Rendering itself is parallel inside TBB, whatever --threads says.

#include <atomic>
#include <memory>

#include "engine/engine.h"
#include "server/metrics.h"
#include "server/server_config.h"

namespace httplib {
class Server;
}

namespace strata::server {

struct ServerContext;

class Server {
public:
    Server(ServerConfig config, Engine& engine);
    ~Server();
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    /// Binds the listening socket; returns the port (useful with port 0) or an error.
    Result<int> bind();
    /// Serves until stop(); returns once in-flight requests have finished.
    void listen();
    /// Makes listen() return. Thread-safe; idempotent; callable before listen() starts.
    void stop();

    /// True while serving and not shutting down (GET /readyz).
    bool ready() const;
    int port() const { return m_port; }
    ServerMetrics& metrics() { return m_metrics; }

private:
    void install_hooks();
    void install_routes();

    ServerConfig m_config;
    Engine& m_engine;
    ServerMetrics m_metrics;
    std::shared_ptr<ServerContext> m_context;  ///< declared before m_http: handlers refer to it
    std::unique_ptr<httplib::Server> m_http;
    int m_port = -1;
    std::atomic<bool> m_listening{false};
    std::atomic<bool> m_stop_requested{false};
};

}  // namespace strata::server
