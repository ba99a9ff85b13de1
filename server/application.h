#pragma once
// Strata's HTTP application without any socket: the route table over protocol/api.h, and the
// response writer. The server runs it on its workers; the HTTP fuzzer calls it directly with what
// the request reader produced.

#include <functional>
#include <memory>
#include <string>

#include "engine/engine.h"
#include "server/metrics.h"
#include "server/request_reader.h"
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
class SceneDirectory;
class StreamChannel;
class StreamHub;

/// A worker's answer to one request.
struct Outcome {
    int status = 0;
    /// The whole response; for a stream, its head (status line, headers, first bytes).
    std::string bytes;
    /// Set: the front end writes this channel's parts after `bytes`, then closes.
    std::shared_ptr<StreamChannel> stream;
};

class Application {
public:
    /// `front_end`, when given, adds the connection counters to /metrics. All must outlive the
    /// application.
    /// `api_busy` tells named scenes' viewer renders to wait (Server: API renders queued).
    Application(const ServerConfig& config, Engine& engine, ServerMetrics& metrics,
                const FrontEndCounters* front_end, durable::DurableStore* store = nullptr,
                StreamHub* streams = nullptr, std::function<bool()> api_busy = {});
    ~Application();
    Application(const Application&) = delete;
    Application& operator=(const Application&) = delete;

    /// Runs one checked request through the routes and writes the answer; `close`: the response
    /// says `Connection: close`. Never throws.
    Outcome handle(PreparedRequest&& request, RequestContext& context, bool close) const;

    /// The data directory for the routes (set while the front end refuses requests).
    void attach_store(durable::DurableStore* store);
    /// The shared edit log for the routes (set while the front end refuses requests).
    void attach_replica(replica::Replica* replica);
    /// The named scenes beside the default one (named_scenes.h).
    SceneDirectory& scenes() { return *m_scenes; }

private:
    void install_routes(const FrontEndCounters* front_end, StreamHub* streams);
    /// The route table of the request's scene runs it: /v1/scenes/NAME/REST as /v1/REST.
    Reply dispatch(HttpRequest& request, RequestContext& context) const;

    const ServerConfig& m_config;
    Engine& m_engine;
    ServerMetrics& m_metrics;
    std::unique_ptr<ServerContext> m_context;  ///< declared before m_routes: handlers refer to it
    std::unique_ptr<SceneDirectory> m_scenes;  ///< the default scene's routes list and make them
    RouteTable m_routes;
};

}  // namespace strata::server
