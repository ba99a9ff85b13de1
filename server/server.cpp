#include "server/server.h"

#include "engine/core/memory_trim.h"

#include "server/application.h"
#include "server/cors.h"
#include "server/reactor.h"
#include "server/stream_hub.h"
#include "server/worker_pool.h"

namespace strata::server {

Server::Server(ServerConfig config, Engine& engine, durable::DurableStore* store)
    : m_config(std::move(config)), m_engine(engine) {
    m_reactor = std::make_unique<Reactor>(
        m_config, m_metrics,
        [this](uint64_t conn, PreparedRequest&& request, std::shared_ptr<CancelToken> cancel,
               Peer peer, bool close, std::chrono::steady_clock::time_point received) {
            const bool heavy = request.heavy;
            if (heavy) ++m_api_heavy;  // viewer renders wait while API renders are queued
            m_workers->submit(heavy, [this, conn, request = std::move(request), cancel,
                                      peer = std::move(peer), close, received] {
                RequestContext context;
                context.cancel = cancel.get();
                context.received = received;
                std::string response = m_app->handle(request.wire_bytes, peer, close, context);
                if (request.heavy) --m_api_heavy;
                if (context.stream) {
                    if (!request.cors_origin.empty())
                        context.stream->add_head_lines(cors_header_lines(request.cors_origin));
                    m_reactor->complete_stream(conn, std::move(context.stream));
                    return;
                }
                if (!request.cors_origin.empty()) add_cors_headers(response, request.cors_origin);
                m_reactor->complete(conn, std::move(response), close || context.close);
                // A large body leaves a parsed document's worth of freed memory behind.
                if (request.wire_bytes.size() >= TRIM_THRESHOLD_BYTES) release_free_memory();
            });
        });
    m_streams = std::make_unique<StreamHub>(m_engine, [this] { return m_api_heavy.load() > 0; });
    m_app = std::make_unique<Application>(
        m_config, m_engine, m_metrics, &m_reactor->counters(), [this] { return ready(); }, store,
        m_streams.get());
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
    m_port = m_listener.port();
    return m_port;
}

void Server::listen() {
    m_listening = true;
    if (m_listener.fd() >= 0) m_reactor->run(m_listener.fd());
    // No more connections queue up in the backlog while the last workers finish.
    m_listener.close();
    m_workers->shutdown();
    m_streams->join();
    m_listening = false;
}

void Server::stop() {
    m_streams->stop();
    m_reactor->drain();
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
