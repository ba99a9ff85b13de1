#pragma once
// What every route handler needs: the engine, the configuration, metrics and parse limits.

#include "engine/engine.h"
#include "protocol/json_document.h"
#include "server/metrics.h"
#include "server/server_config.h"

namespace strata::server {

struct ServerContext {
    Engine& engine;
    const ServerConfig& config;
    ServerMetrics& metrics;
    protocol::JsonLimits json_limits;
};

class Router;

/// POST /v1/edits, POST /v1/commit, GET /v1/plan.
void add_edit_routes(Router& router, ServerContext& ctx);
/// POST /v1/render, GET /v1/render.
void add_render_routes(Router& router, ServerContext& ctx);
/// GET /v1/scene and GET /v1/scene/{meshes,instances,materials}/{id}.
void add_scene_routes(Router& router, ServerContext& ctx);
/// GET /v1/stats and GET /metrics (liveness and readiness live in server.cpp).
void add_stats_routes(Router& router, ServerContext& ctx);

/// Logs a commit's report (one line) and observes its duration.
void record_commit(ServerContext& ctx, const RebuildReport& report, const char* cause);

}  // namespace strata::server
