#pragma once
// What every route handler needs: the engine, the configuration, metrics and request limits.

#include "engine/engine.h"
#include "protocol/api.h"
#include "server/metrics.h"
#include "server/past_scenes.h"
#include "server/server_config.h"

namespace strata::durable {
class DurableStore;
}
namespace strata::replica {
class Replica;
}

namespace strata::server {

struct FrontEndCounters;
class SceneDirectory;
class StreamHub;

struct ServerContext {
    Engine& engine;
    const ServerConfig& config;
    ServerMetrics& metrics;
    protocol::ApiLimits api_limits;
    const FrontEndCounters* front_end = nullptr;  ///< connection counters for /metrics
    durable::DurableStore* store = nullptr;       ///< the data directory; null without --data
    replica::Replica* replica = nullptr;          ///< the shared edit log; null without --log
    protocol::BatchApply append_to_log;           ///< the replica's append, when there is one
    StreamHub* streams = nullptr;                 ///< /v1/stream and /v1/events; null: 503
    /// Renders `split=N` frames with --peers (split_render.h); empty without peers.
    protocol::SplitRender split_render;
    /// Older versions for `at_version` reads, loaded from `store` (past_scenes.h).
    std::unique_ptr<PastScenes> past = nullptr;
    /// The named scenes (the default scene's context only), for /metrics.
    const SceneDirectory* scenes = nullptr;

    /// Sends this scene's writes through `r` (the shared edit log) from now on.
    void attach_replica(replica::Replica* r);
    /// Where write endpoints send batches: the log's append with --log, else the engine.
    const protocol::BatchApply* batch_apply() const { return replica ? &append_to_log : nullptr; }
    /// How `split` renders are made: null without --peers (a split above 1 is then a 422).
    const protocol::SplitRender* split() const { return split_render ? &split_render : nullptr; }
};

class RouteTable;

/// Every /v1 endpoint (over protocol/api.h) and GET /metrics; liveness and readiness are
/// answered by the front end (request_reader.cpp).
void add_api_routes(RouteTable& routes, ServerContext& ctx);

/// GET /v1/stream and GET /v1/events (stream_routes.cpp).
void add_stream_routes(RouteTable& routes, ServerContext& ctx);

/// GET / and /web/...: the viewer's files (web_routes.cpp).
void add_web_routes(RouteTable& routes);

/// GET /v1/scenes and GET, PUT and DELETE /v1/scenes/{scene} (scene_directory_routes.cpp);
/// `ctx` is the default scene's.
void add_scene_directory_routes(RouteTable& routes, ServerContext& ctx, SceneDirectory& scenes);
/// Lists every /v1 route again under /v1/scenes/{scene}/, for the OpenAPI description; after
/// every route is added.
void describe_scene_routes(RouteTable& routes);
/// Whether a named scene serves `route` ("/v1/render": yes; "/v1/scenes", "/v1/openapi.json":
/// only the unprefixed path does).
bool scene_route(std::string_view route);
/// The 404 for a scene that does not exist.
protocol::Problem unknown_scene(std::string_view name);

}  // namespace strata::server
