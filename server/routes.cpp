// Every /v1 route and /metrics: thin adapters over protocol/api.h, which does the work for the
// server and for `strata play --embedded` alike. What stays here is HTTP: reading the request,
// and the server's own logs and metrics.

#include <charconv>
#include <thread>

#include <spdlog/spdlog.h>

#include "engine/core/timer.h"
#include "engine/durable/durable_store.h"
#include "protocol/api.h"
#include "server/context.h"
#include "server/front_end_counters.h"
#include "server/replica/replica.h"
#include "server/route_table.h"
#include "server/stream_hub.h"

namespace strata::server {

namespace {

using Query = std::multimap<std::string, std::string>;

/// An API answer whose commit, if it ran one, is logged and measured.
protocol::ApiResponse committed(ServerContext& ctx, protocol::ApiResponse&& answer,
                                const char* cause) {
    if (answer.commit) {
        ctx.metrics.commit_seconds.observe(answer.commit->phases.total_ms / 1000.0);
        spdlog::info("commit ({}) {}", cause, answer.commit->summary());
    }
    return std::move(answer);
}

/// Renders with `render`, observing the duration of successful renders (commit, tracing and
/// encoding).
template <class Render>
protocol::ApiResponse rendered(ServerContext& ctx, Render&& render) {
    Stopwatch clock;
    protocol::ApiResponse answer = render();
    if (answer.status == 200) ctx.metrics.render_seconds.observe(clock.ms() / 1000.0);
    return committed(ctx, std::move(answer), "render");
}

/// The detail of a min_version wait that timed out: how far behind this server is.
std::string behind_detail(ServerContext& ctx, uint64_t wanted, uint64_t version) {
    std::string detail = "this server is at version " + std::to_string(version) +
                         ", behind min_version " + std::to_string(wanted) + " after waiting " +
                         std::to_string(ctx.config.min_version_wait_ms) + " ms";
    if (!ctx.replica) return detail;
    const replica::ReplicaStatus st = ctx.replica->status();
    char lag[160];
    std::snprintf(lag, sizeof lag,
                  " (replica lag: %llu entries, %.3f s behind the log at version %llu%s)",
                  static_cast<unsigned long long>(st.lag_entries), st.lag_seconds,
                  static_cast<unsigned long long>(st.log_version),
                  st.stopped      ? "; the replica has stopped"
                  : !st.connected ? "; Redis unreachable"
                                  : "");
    return detail + lag;
}

/// Read-your-writes across replicas: a read with `min_version` (query) or X-Strata-Min-Version
/// (header) waits, at most --min-version-wait-ms, until this server has applied that version.
/// Takes min_version out of the request's query; returns the refusal when the value is
/// malformed (400) or the version was not reached in time (503; the detail names the lag).
std::optional<protocol::ApiResponse> await_min_version(ServerContext& ctx, HttpRequest& req) {
    std::optional<std::string> text;
    if (auto it = req.query.find("min_version"); it != req.query.end()) {
        text = it->second;
        req.query.erase(it);
    }
    if (!text) text = req.header_value("X-Strata-Min-Version");
    if (!text) return std::nullopt;
    uint64_t wanted = 0;
    const auto [end, ec] = std::from_chars(text->data(), text->data() + text->size(), wanted);
    if (ec != std::errc() || end != text->data() + text->size() || text->empty()) {
        protocol::Problem p = protocol::make_problem(
            protocol::ProblemType::InvalidRequest,
            "min_version must be a scene version (a whole number), not '" + text->substr(0, 40) +
                "'");
        p.pointer = "min_version";
        return protocol::problem_response(p);
    }
    const auto timeout = std::chrono::milliseconds(ctx.config.min_version_wait_ms);
    auto version = [&] { return ctx.engine.read([](const Scene& s) { return s.version(); }); };
    bool reached = false;
    if (ctx.replica) {
        reached = ctx.replica->wait_applied(wanted, timeout);
    } else {
        // Without a log only this server's own writes move the version: poll for them.
        const auto deadline = std::chrono::steady_clock::now() + timeout;
        while (!(reached = version() >= wanted) && std::chrono::steady_clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (reached) return std::nullopt;
    protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
        protocol::ProblemType::Unavailable, behind_detail(ctx, wanted, version())));
    r.headers.emplace_back("Retry-After", "1");
    return r;
}

/// A GET route whose handler runs once `min_version`, if asked for, is reached.
template <class Handler>
RouteTable::Handler after_min_version(ServerContext& ctx, Handler handler) {
    return [&ctx, handler = std::move(handler)](RouteCall& call) -> Reply {
        if (auto refusal = await_min_version(ctx, call.request)) return std::move(*refusal);
        return handler(call);
    };
}

/// A POST route whose body is JSON: other body types are 415 before the handler runs.
template <class Handler>
RouteTable::Handler json_body(Handler handler) {
    return [handler = std::move(handler)](RouteCall& call) -> Reply {
        if (auto problem =
                protocol::json_body_type_problem(call.request.header_value("Content-Type")))
            return *problem;
        return handler(call);
    };
}

void add_scene_object_routes(RouteTable& routes, ServerContext& ctx, const char* collection,
                             protocol::SceneObject kind) {
    const std::string path = std::string("/v1/scene/") + collection;
    routes.get(path, after_min_version(ctx, [&ctx, kind](RouteCall& call) {
                   return protocol::get_scene_list(ctx.engine, kind, call.request.query);
               }));
    // The path keeps reserved characters percent-encoded (request_target.h): an id holding '/'
    // arrives as one segment, decoded by the route table.
    routes.get(path + "/{id}", after_min_version(ctx, [&ctx, kind](RouteCall& call) {
                   return protocol::get_scene_object(ctx.engine, kind, call.params[0]);
               }));
}

/// What GET /metrics reads: the numbers of every part of the server that exists.
MetricsSnapshot metrics_snapshot(const ServerContext& ctx) {
    MetricsSnapshot s;
    const Engine& engine = ctx.engine;
    s.engine = engine.counters();
    std::tie(s.scene_version, s.scene) =
        engine.read([](const Scene& scene) { return std::pair(scene.version(), scene.counts()); });
    s.blas_bytes = uint64_t(engine.memory_bytes(MemoryCategory::Blas));
    s.tlas_bytes = uint64_t(engine.memory_bytes(MemoryCategory::Tlas));
    s.tiers = engine.last_report().tlas;
    s.responses = ctx.metrics.responses();
    s.commit_seconds = ctx.metrics.commit_seconds.counts();
    s.render_seconds = ctx.metrics.render_seconds.counts();
    s.front_end = ctx.front_end;
    if (ctx.store) s.durable = ctx.store->stats();
    if (ctx.replica) s.replica = ctx.replica->status();
    if (ctx.streams) s.streams = ctx.streams->stats();
    return s;
}

void add_write_routes(RouteTable& routes, ServerContext& ctx) {
    routes.post("/v1/edits", json_body([&ctx](RouteCall& call) {
                    HttpRequest& req = call.request;
                    return protocol::post_edits(ctx.engine, std::move(req.body),
                                                req.header_value("If-Match"), ctx.api_limits,
                                                ctx.batch_apply());
                }));
    routes.post("/v1/assets", [&ctx](RouteCall& call) {
        HttpRequest& req = call.request;
        return protocol::post_assets(ctx.engine, std::move(req.body), req.query,
                                     req.header_value("Content-Type"), req.header_value("If-Match"),
                                     ctx.api_limits, ctx.batch_apply());
    });
    routes.post("/v1/commit", [&ctx](RouteCall&) {
        return committed(ctx, protocol::post_commit(ctx.engine), "commit");
    });
    routes.post("/v1/scene/snapshot", [&ctx](RouteCall& call) {
        HttpRequest& req = call.request;
        return protocol::post_snapshot(ctx.engine, std::move(req.body),
                                       req.header_value("If-Match"), ctx.batch_apply());
    });
}

void add_render_routes(RouteTable& routes, ServerContext& ctx) {
    routes.post("/v1/render", json_body(after_min_version(ctx, [&ctx](RouteCall& call) {
                    return rendered(ctx, [&] {
                        return protocol::post_render(ctx.engine, call.request.body, ctx.api_limits,
                                                     call.context.cancel, ctx.split());
                    });
                })));
    routes.get("/v1/render", [&ctx](RouteCall& call) -> Reply {
        if (call.request.method == "HEAD") {
            // Its headers (ETag, size, rebuild summary) exist only once the frame is rendered.
            protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
                protocol::ProblemType::MethodNotAllowed,
                "HEAD /v1/render would have to render the frame to know its headers; use GET or "
                "POST"));
            r.headers.emplace_back("Allow", "GET, POST");
            return r;
        }
        if (auto refusal = await_min_version(ctx, call.request)) return std::move(*refusal);
        return rendered(ctx, [&] {
            return protocol::get_render(ctx.engine, call.request.query, ctx.api_limits,
                                        call.context.cancel, ctx.split());
        });
    });
    routes.get("/v1/pick", after_min_version(ctx, [&ctx](RouteCall& call) {
                   return protocol::get_pick(ctx.engine, call.request.query);
               }));
    routes.post("/v1/pick", json_body(after_min_version(ctx, [&ctx](RouteCall& call) {
                    return protocol::post_pick(ctx.engine, call.request.body, ctx.api_limits);
                })));
}

void add_read_routes(RouteTable& routes, ServerContext& ctx) {
    routes.get("/v1/plan", [&ctx](RouteCall&) { return protocol::get_plan(ctx.engine); });
    routes.get("/v1/scene", after_min_version(ctx, [&ctx](RouteCall&) {
                   return protocol::get_scene(ctx.engine);
               }));
    add_scene_object_routes(routes, ctx, "meshes", protocol::SceneObject::Mesh);
    add_scene_object_routes(routes, ctx, "instances", protocol::SceneObject::Instance);
    add_scene_object_routes(routes, ctx, "materials", protocol::SceneObject::Material);
    add_scene_object_routes(routes, ctx, "groups", protocol::SceneObject::Group);
    add_scene_object_routes(routes, ctx, "lights", protocol::SceneObject::Light);
    add_scene_object_routes(routes, ctx, "textures", protocol::SceneObject::Texture);
    routes.get("/v1/scene/groups/{id}/children", [&ctx](RouteCall& call) {
        return protocol::get_group_children(ctx.engine, call.params[0], call.request.query);
    });
    routes.get("/v1/scene/tree", [&ctx](RouteCall& call) {
        return protocol::get_scene_tree(ctx.engine, call.request.query);
    });
    routes.get("/v1/scene/snapshot", after_min_version(ctx, [&ctx](RouteCall&) {
                   return protocol::get_snapshot(ctx.engine);
               }));
    routes.get("/v1/stats", [&ctx](RouteCall&) {
        if (!ctx.store) return protocol::get_stats(ctx.engine);
        const durable::DurableStats durable = ctx.store->stats();
        return protocol::get_stats(ctx.engine, &durable);
    });
    routes.get("/metrics", [&ctx](RouteCall&) {
        protocol::ApiResponse r;
        r.content_type = "text/plain; version=0.0.4; charset=utf-8";
        r.body = prometheus_text(metrics_snapshot(ctx));
        return r;
    });
}

}  // namespace

void add_api_routes(RouteTable& routes, ServerContext& ctx) {
    add_write_routes(routes, ctx);
    add_render_routes(routes, ctx);
    add_read_routes(routes, ctx);
}

}  // namespace strata::server
