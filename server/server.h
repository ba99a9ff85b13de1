#pragma once
// The HTTP server: Strata's front end (reactor.h) owns the sockets; complete, checked requests
// run on a worker pool through the Application (Strata's route table and response writer) around
// one Engine; the front end writes every answer and keeps the access log.
//
// Concurrency model. One reactor thread reads and writes every connection; --threads workers
// run handlers, never waiting on a client. Handlers share nothing but the Engine, which is
// thread-safe (see engine/engine.h): edits take the scene lock briefly and never wait for
// tracing; commits and renders are serialised by the engine's launch mutex, and each render
// traces exactly the version its own commit produced, which is the version its ETag names.
// If-Match is checked under the same scene lock as the apply. Rendering itself is parallel
// inside TBB, whatever --threads says.

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "engine/engine.h"
#include "server/listener.h"
#include "server/metrics.h"
#include "server/request_reader.h"
#include "server/server_config.h"

namespace strata::durable {
class DurableStore;
}
namespace strata::replica {
class Replica;
struct ReplicaOptions;
}

namespace strata::server {

class Application;
class Reactor;
class StreamHub;
class WorkerPool;

class Server {
public:
    /// `store`, when given, is the data directory (GET /v1/stats, /metrics, snapshots).
    Server(ServerConfig config, Engine& engine, durable::DurableStore* store = nullptr);
    ~Server();
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    /// Binds the listening socket; returns the port (useful with port 0) or an error naming the
    /// address and the cause.
    Result<int> bind();
    /// Serves until stop() and the drain that follows; returns once in-flight requests have
    /// finished (or were cancelled after --shutdown-grace).
    void listen();
    /// Starts the graceful shutdown. Thread-safe; idempotent; callable before listen() starts.
    void stop();

    /// True while serving, not starting and not shutting down (GET /readyz).
    bool ready() const;
    /// While true (the data directory is being recovered, then its scene built), /readyz
    /// answers 503 with `progress()` as its detail and every other endpoint but /livez 503 with
    /// Retry-After. `progress` runs on the front end's thread. Thread-safe.
    void set_starting(bool starting, std::function<std::string()> progress = {});
    /// The data directory, once recovered (while starting; before that, routes see none).
    void attach_store(durable::DurableStore* store);
    /// Recovers the named scenes under --data/scenes (while starting, after attach_store).
    Status recover_scenes();
    /// The shared edit log (while starting, like attach_store).
    void attach_replica(replica::Replica* replica);
    /// The named scenes follow the shared edit log's scene directory from now on (while
    /// starting, after recover_scenes); `options`: the default scene's replica's.
    void follow_scene_log(const replica::ReplicaOptions& options);
    /// What /readyz asks beyond starting and draining (a replica's state). Before listen() only.
    void set_readiness(std::function<Readiness()> readiness);
    int port() const { return m_port; }
    ServerMetrics& metrics() { return m_metrics; }
    /// The live viewer's streams (counts for tests and /metrics).
    StreamHub& streams() { return *m_streams; }

private:
    ServerConfig m_config;
    Engine& m_engine;
    ServerMetrics m_metrics;
    std::unique_ptr<Reactor> m_reactor;
    std::unique_ptr<StreamHub> m_streams;  ///< viewer frames and commit events
    std::unique_ptr<Application> m_app;
    std::unique_ptr<WorkerPool> m_workers;  ///< after m_reactor: workers call into it until joined
    Listener m_listener;
    int m_port = -1;
    std::atomic<bool> m_listening{false};
    std::atomic<int> m_api_heavy{0};  ///< API renders and commits queued or running
};

}  // namespace strata::server
