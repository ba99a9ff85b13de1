// Every /v1 route and /metrics: thin httplib adapters over protocol/api.h, which does the work
// for the server and for `strata play --embedded` alike. What stays here is HTTP: reading the
// request, writing the response, and the server's own logs and metrics.

#include <charconv>
#include <thread>

#include <spdlog/spdlog.h>

#include "engine/core/timer.h"
#include "engine/durable/durable_store.h"
#include "protocol/api.h"
#include "server/context.h"
#include "server/front_end_counters.h"
#include "server/http_util.h"
#include "server/replica/replica.h"
#include "server/replica/replica_metrics.h"
#include "server/request_target.h"
#include "server/route_table.h"
#include "server/router.h"
#include "server/stream_hub.h"

namespace strata::server {

namespace {

using Query = std::multimap<std::string, std::string>;
std::optional<Query> await_min_version(ServerContext& ctx, const httplib::Request& req,
                                       httplib::Response& res);

/// Sends an API answer; logs and measures the commit it ran, if any.
void respond(ServerContext& ctx, httplib::Response& res, protocol::ApiResponse&& answer,
             const char* cause) {
    if (answer.commit) {
        ctx.metrics.commit_seconds.observe(answer.commit->phases.total_ms / 1000.0);
        spdlog::info("commit ({}) {}", cause, answer.commit->summary());
    }
    send(res, std::move(answer));
}

/// Renders with `render`, observing the duration of successful renders (commit, tracing and
/// encoding).
template <class Render>
void respond_render(ServerContext& ctx, httplib::Response& res, Render&& render) {
    Stopwatch clock;
    protocol::ApiResponse answer = render();
    if (answer.status == 200) ctx.metrics.render_seconds.observe(clock.ms() / 1000.0);
    respond(ctx, res, std::move(answer), "render");
}

void add_scene_object_route(Router& router, ServerContext& ctx, const char* collection,
                            protocol::SceneObject kind) {
    router.get(std::string("/v1/scene/") + collection,
               [&ctx, kind](const httplib::Request& req, httplib::Response& res) {
                   const auto query = await_min_version(ctx, req, res);
                   if (!query) return;
                   send(res, protocol::get_scene_list(ctx.engine, kind, *query));
               });
    // The path keeps reserved characters percent-encoded (request_target.h): an id holding '/'
    // arrives as one segment, decoded here.
    router.get(std::string("/v1/scene/") + collection + "/([^/]+)",
               [&ctx, kind](const httplib::Request& req, httplib::Response& res) {
                   if (!await_min_version(ctx, req, res)) return;
                   send(res, protocol::get_scene_object(ctx.engine, kind,
                                                        decode_path_segment(req.matches[1].str())));
               });
}

/// The cancel token of the request this worker handles (null outside the server's front end).
CancelToken* request_cancel() {
    const RequestContext* context = current_request();
    return context ? context->cancel : nullptr;
}

/// Read-your-writes across replicas: a read with `min_version` (query) or X-Strata-Min-Version
/// (header) waits, at most --min-version-wait-ms, until this server has applied that version.
/// Returns the query without min_version, or nullopt after answering 400 (malformed) or 503 (not
/// reached in time; the detail names the lag).
std::optional<Query> await_min_version(ServerContext& ctx, const httplib::Request& req,
                                       httplib::Response& res) {
    Query query = req.params;
    std::optional<std::string> text;
    if (auto it = query.find("min_version"); it != query.end()) text = it->second;
    query.erase("min_version");
    if (!text && req.has_header("X-Strata-Min-Version"))
        text = req.get_header_value("X-Strata-Min-Version");
    if (!text) return query;
    uint64_t wanted = 0;
    const auto [end, ec] = std::from_chars(text->data(), text->data() + text->size(), wanted);
    if (ec != std::errc() || end != text->data() + text->size() || text->empty()) {
        protocol::Problem p = protocol::make_problem(
            protocol::ProblemType::InvalidRequest,
            "min_version must be a scene version (a whole number), not '" + text->substr(0, 40) +
                "'");
        p.pointer = "min_version";
        send_problem(res, p);
        return std::nullopt;
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
    if (reached) return query;
    std::string detail = "this server is at version " + std::to_string(version()) +
                         ", behind min_version " + std::to_string(wanted) + " after waiting " +
                         std::to_string(ctx.config.min_version_wait_ms) + " ms";
    if (ctx.replica) {
        const replica::ReplicaStatus st = ctx.replica->status();
        char lag[160];
        std::snprintf(lag, sizeof lag,
                      " (replica lag: %llu entries, %.3f s behind the log at version %llu%s)",
                      static_cast<unsigned long long>(st.lag_entries), st.lag_seconds,
                      static_cast<unsigned long long>(st.log_version),
                      st.stopped ? "; the replica has stopped" : !st.connected ? "; Redis unreachable" : "");
        detail += lag;
    }
    res.set_header("Retry-After", "1");
    send_problem(res, protocol::make_problem(protocol::ProblemType::Unavailable, detail));
    return std::nullopt;
}

}  // namespace

void add_api_routes(Router& router, ServerContext& ctx) {
    using Req = httplib::Request;
    using Res = httplib::Response;
    router.post("/v1/edits", [&ctx](const Req& req, Res& res, std::string&& body) {
        const std::optional<std::string> if_match =
            req.has_header("If-Match") ? std::optional(req.get_header_value("If-Match"))
                                       : std::nullopt;
        send(res, protocol::post_edits(ctx.engine, std::move(body), if_match, ctx.api_limits,
                                       ctx.batch_apply()));
    });
    router.post("/v1/assets", [&ctx](const Req& req, Res& res, std::string&& body) {
        const auto header = [&](const char* name) {
            return req.has_header(name) ? std::optional(req.get_header_value(name))
                                        : std::nullopt;
        };
        const std::optional<std::string> if_match = header("If-Match");
        const std::optional<std::string> content_type = header("Content-Type");
        send(res, protocol::post_assets(ctx.engine, std::move(body), req.params, content_type,
                                        if_match, ctx.api_limits, ctx.batch_apply()));
    });
    router.post("/v1/commit", [&ctx](const Req&, Res& res, std::string&&) {
        respond(ctx, res, protocol::post_commit(ctx.engine), "commit");
    });
    router.get("/v1/plan",
               [&ctx](const Req&, Res& res) { send(res, protocol::get_plan(ctx.engine)); });
    router.post("/v1/render", [&ctx](const Req& req, Res& res, std::string&& body) {
        if (!await_min_version(ctx, req, res)) return;
        respond_render(ctx, res, [&] {
            return protocol::post_render(ctx.engine, body, ctx.api_limits, request_cancel(),
                                         ctx.split());
        });
    });
    router.get("/v1/render", [&ctx](const Req& req, Res& res) {
        if (req.method == "HEAD") {
            // Its headers (ETag, size, rebuild summary) exist only once the frame is rendered.
            res.set_header("Allow", "GET, POST");
            return send_problem(
                res, protocol::make_problem(protocol::ProblemType::MethodNotAllowed,
                                            "HEAD /v1/render would have to render the frame to "
                                            "know its headers; use GET or POST"));
        }
        const auto query = await_min_version(ctx, req, res);
        if (!query) return;
        respond_render(ctx, res, [&] {
            return protocol::get_render(ctx.engine, *query, ctx.api_limits, request_cancel(),
                                        ctx.split());
        });
    });
    router.get("/v1/scene", [&ctx](const Req& req, Res& res) {
        if (!await_min_version(ctx, req, res)) return;
        send(res, protocol::get_scene(ctx.engine));
    });
    add_scene_object_route(router, ctx, "meshes", protocol::SceneObject::Mesh);
    add_scene_object_route(router, ctx, "instances", protocol::SceneObject::Instance);
    add_scene_object_route(router, ctx, "materials", protocol::SceneObject::Material);
    add_scene_object_route(router, ctx, "groups", protocol::SceneObject::Group);
    add_scene_object_route(router, ctx, "lights", protocol::SceneObject::Light);
    add_scene_object_route(router, ctx, "textures", protocol::SceneObject::Texture);
    router.get("/v1/scene/groups/([^/]+)/children", [&ctx](const Req& req, Res& res) {
        send(res, protocol::get_group_children(
                      ctx.engine, decode_path_segment(req.matches[1].str()), req.params));
    });
    router.get("/v1/scene/tree",
               [&ctx](const Req& req, Res& res) { send(res, protocol::get_scene_tree(ctx.engine, req.params)); });
    router.get("/v1/pick", [&ctx](const Req& req, Res& res) {
        const auto query = await_min_version(ctx, req, res);
        if (!query) return;
        send(res, protocol::get_pick(ctx.engine, *query));
    });
    router.post("/v1/pick", [&ctx](const Req& req, Res& res, std::string&& body) {
        if (!await_min_version(ctx, req, res)) return;
        send(res, protocol::post_pick(ctx.engine, body, ctx.api_limits));
    });
    router.get("/v1/scene/snapshot", [&ctx](const Req& req, Res& res) {
        if (!await_min_version(ctx, req, res)) return;
        send(res, protocol::get_snapshot(ctx.engine));
    });
    router.post("/v1/scene/snapshot", [&ctx](const Req& req, Res& res, std::string&& body) {
        const std::optional<std::string> if_match =
            req.has_header("If-Match") ? std::optional(req.get_header_value("If-Match"))
                                       : std::nullopt;
        send(res, protocol::post_snapshot(ctx.engine, std::move(body), if_match,
                                          ctx.batch_apply()));
    });
    router.get("/v1/stats", [&ctx](const Req&, Res& res) {
        if (!ctx.store) return send(res, protocol::get_stats(ctx.engine));
        const durable::DurableStats durable = ctx.store->stats();
        send(res, protocol::get_stats(ctx.engine, &durable));
    });
    router.get("/metrics", [&ctx](const Req&, Res& res) {
        res.status = 200;
        std::string text = ctx.metrics.prometheus_text(ctx.engine);
        if (ctx.front_end) ctx.front_end->write_prometheus(text);
        if (ctx.store) write_durable_metrics(text, ctx.store->stats());
        if (ctx.replica) replica::write_replica_metrics(text, ctx.replica->status());
        if (ctx.streams) write_stream_metrics(text, ctx.streams->stats());
        res.set_content(text, "text/plain; version=0.0.4; charset=utf-8");
    });
}

}  // namespace strata::server
