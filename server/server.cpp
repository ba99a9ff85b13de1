#include "server/server.h"

#include "engine/core/memory_trim.h"

#include "server/application.h"
#include "server/named_scenes.h"
#include "server/reactor.h"
#include "server/stream_hub.h"
#include "server/worker_pool.h"

namespace strata::server {

Server::Server(ServerConfig config, Engine& engine, durable::DurableStore* store)
    : m_config(std::move(config)), m_engine(engine) {
    m_reactor = std::make_unique<Reactor>(
        m_config, m_metrics,
        [this](uint64_t conn, PreparedRequest&& request, std::shared_ptr<CancelToken> cancel,
               bool close) {
            const bool heavy = request.heavy;
            if (heavy) ++m_api_heavy;  // viewer renders wait while API renders are queued
            m_workers->submit(
                heavy, [this, conn, request = std::move(request), cancel, close, heavy]() mutable {
                    RequestContext context;
                    context.cancel = cancel.get();
                    const std::size_t body_bytes = request.http.body.size();
                    Outcome outcome = m_app->handle(std::move(request), context, close);
                    if (heavy) --m_api_heavy;
                    m_reactor->complete(conn, std::move(outcome), close);
                    // A large body leaves a parsed document's worth of freed memory behind.
                    if (body_bytes >= TRIM_THRESHOLD_BYTES) release_free_memory();
                });
        });
    m_reactor->set_version_source([this](std::string_view scene) {
        return scene.empty() ? m_engine.version() : m_app->scenes().version_of(scene);
    });
    m_streams = std::make_unique<StreamHub>(
        m_engine, [this] { return m_api_heavy.load() > 0; }, m_config.max_stream_mb << 20);
    m_app = std::make_unique<Application>(m_config, m_engine, m_metrics, &m_reactor->counters(),
                                          store, m_streams.get(),
                                          [this] { return m_api_heavy.load() > 0; });
    m_workers = std::make_unique<WorkerPool>(m_config.threads);
}

Server::~Server() {
    stop();
    m_workers->shutdown();
    m_streams->join();
}

Result<int> Server::bind() {
    auto listener = Listener::open(m_config.host, m_config.port, m_config.listen_backlog);
    if (!listener) return Unexpected(listener.error());
    m_listener = std::move(listener.value());
    if (Status opened = m_reactor->open(m_listener.fd()); !opened) {
        m_listener.close();
        return Unexpected(opened.error());
    }
    m_port = m_listener.port();
    return m_port;
}

void Server::listen() {
    m_listening = true;
    if (m_listener.fd() >= 0) m_reactor->run();
    // No more connections queue up in the backlog while the last workers finish.
    m_listener.close();
    m_workers->shutdown();
    m_streams->join();
    m_listening = false;
}

void Server::stop() {
    m_streams->stop();
    m_app->scenes().stop_streams();
    m_reactor->drain();
}

Status Server::recover_scenes() {
    return m_app->scenes().recover();
}

void Server::follow_scene_log(const replica::ReplicaOptions& options) {
    m_app->scenes().follow_log(options);
}

void Server::attach_replica(replica::Replica* replica) {
    m_app->attach_replica(replica);
}

void Server::set_readiness(std::function<Readiness()> readiness) {
    m_reactor->set_readiness(std::move(readiness));
}

bool Server::ready() const {
    return m_listening && !m_reactor->draining() && !m_reactor->starting();
}

void Server::set_starting(bool starting, std::function<std::string()> progress) {
    m_reactor->set_starting(starting, std::move(progress));
}

void Server::attach_store(durable::DurableStore* store) {
    // Routes read the context only for requests the front end lets through, which it does not
    // while starting; clearing `starting` afterwards publishes this write (an atomic store).
    m_app->attach_store(store);
}

}  // namespace strata::server
