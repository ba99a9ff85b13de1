#pragma once
// Strata's HTTP application without any socket: the routes, the error and exception handlers and
// the access log on top of httplib's router (route_table.h). The server runs it on its workers;
// the HTTP fuzzer calls it directly with what the request reader produced.

#include <functional>
#include <memory>
#include <string>
#include <string_view>

#include "engine/engine.h"
#include "server/metrics.h"
#include "server/route_table.h"
#include "server/server_config.h"

namespace strata::durable {
class DurableStore;
}
namespace strata::replica {
class Replica;
}

namespace strata::server {

struct FrontEndCounters;
struct ServerContext;
class StreamHub;

class Application {
public:
    /// `ready` answers whether the server takes requests (GET /readyz); `front_end`, when given,
    /// adds the connection counters to /metrics. All must outlive the application.
    Application(const ServerConfig& config, Engine& engine, ServerMetrics& metrics,
                const FrontEndCounters* front_end, std::function<bool()> ready,
                durable::DurableStore* store = nullptr, StreamHub* streams = nullptr);
    ~Application();
    Application(const Application&) = delete;
    Application& operator=(const Application&) = delete;

    /// Runs one checked request (PreparedRequest::wire_bytes) and returns the whole response;
    /// see RouteTable::handle.
    std::string handle(std::string_view wire_bytes, const Peer& peer, bool close,
                       RequestContext& context) {
        return m_routes.handle(wire_bytes, peer, close, context);
    }

    /// The data directory for the routes (set while the front end refuses requests).
    void attach_store(durable::DurableStore* store);
    /// The shared edit log for the routes (set while the front end refuses requests).
    void attach_replica(replica::Replica* replica);

private:
    void install_hooks();
    void install_routes(const FrontEndCounters* front_end, StreamHub* streams);

    const ServerConfig& m_config;
    Engine& m_engine;
    ServerMetrics& m_metrics;
    std::function<bool()> m_ready;
    durable::DurableStore* m_store;
    std::unique_ptr<ServerContext> m_context;  ///< declared before m_routes: handlers refer to it
    RouteTable m_routes;
};

}  // namespace strata::server
