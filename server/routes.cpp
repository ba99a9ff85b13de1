// Every /v1 route and /metrics: thin httplib adapters over protocol/api.h, which does the work
// for the server and for `strata play --embedded` alike. What stays here is HTTP: reading the
// request, writing the response, and the server's own logs and metrics.

#include <spdlog/spdlog.h>

#include "engine/core/timer.h"
#include "engine/durable/durable_store.h"
#include "protocol/api.h"
#include "server/context.h"
#include "server/front_end_counters.h"
#include "server/http_util.h"
#include "server/request_target.h"
#include "server/route_table.h"
#include "server/router.h"
#include "server/stream_hub.h"

namespace strata::server {

namespace {

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
                   send(res, protocol::get_scene_list(ctx.engine, kind, req.params));
               });
    // The path keeps reserved characters percent-encoded (request_target.h): an id holding '/'
    // arrives as one segment, decoded here.
    router.get(std::string("/v1/scene/") + collection + "/([^/]+)",
               [&ctx, kind](const httplib::Request& req, httplib::Response& res) {
                   send(res, protocol::get_scene_object(ctx.engine, kind,
                                                        decode_path_segment(req.matches[1].str())));
               });
}

/// The cancel token of the request this worker handles (null outside the server's front end).
CancelToken* request_cancel() {
    const RequestContext* context = current_request();
    return context ? context->cancel : nullptr;
}

}  // namespace

void add_api_routes(Router& router, ServerContext& ctx) {
    using Req = httplib::Request;
    using Res = httplib::Response;
    router.post("/v1/edits", [&ctx](const Req& req, Res& res, std::string&& body) {
        const std::optional<std::string> if_match =
            req.has_header("If-Match") ? std::optional(req.get_header_value("If-Match"))
                                       : std::nullopt;
        send(res, protocol::post_edits(ctx.engine, std::move(body), if_match, ctx.api_limits));
    });
    router.post("/v1/assets", [&ctx](const Req& req, Res& res, std::string&& body) {
        const auto header = [&](const char* name) {
            return req.has_header(name) ? std::optional(req.get_header_value(name))
                                        : std::nullopt;
        };
        const std::optional<std::string> if_match = header("If-Match");
        const std::optional<std::string> content_type = header("Content-Type");
        send(res, protocol::post_assets(ctx.engine, std::move(body), req.params, content_type,
                                        if_match, ctx.api_limits));
    });
    router.post("/v1/commit", [&ctx](const Req&, Res& res, std::string&&) {
        respond(ctx, res, protocol::post_commit(ctx.engine), "commit");
    });
    router.get("/v1/plan",
               [&ctx](const Req&, Res& res) { send(res, protocol::get_plan(ctx.engine)); });
    router.post("/v1/render", [&ctx](const Req&, Res& res, std::string&& body) {
        respond_render(ctx, res, [&] {
            return protocol::post_render(ctx.engine, body, ctx.api_limits, request_cancel());
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
        respond_render(ctx, res, [&] {
            return protocol::get_render(ctx.engine, req.params, ctx.api_limits, request_cancel());
        });
    });
    router.get("/v1/scene",
               [&ctx](const Req&, Res& res) { send(res, protocol::get_scene(ctx.engine)); });
    add_scene_object_route(router, ctx, "meshes", protocol::SceneObject::Mesh);
    add_scene_object_route(router, ctx, "instances", protocol::SceneObject::Instance);
    add_scene_object_route(router, ctx, "materials", protocol::SceneObject::Material);
    add_scene_object_route(router, ctx, "groups", protocol::SceneObject::Group);
    router.get("/v1/scene/groups/([^/]+)/children", [&ctx](const Req& req, Res& res) {
        send(res, protocol::get_group_children(
                      ctx.engine, decode_path_segment(req.matches[1].str()), req.params));
    });
    router.get("/v1/scene/tree",
               [&ctx](const Req& req, Res& res) { send(res, protocol::get_scene_tree(ctx.engine, req.params)); });
    router.get("/v1/pick", [&ctx](const Req& req, Res& res) {
        send(res, protocol::get_pick(ctx.engine, req.params));
    });
    router.post("/v1/pick", [&ctx](const Req&, Res& res, std::string&& body) {
        send(res, protocol::post_pick(ctx.engine, body, ctx.api_limits));
    });
    router.get("/v1/scene/snapshot",
               [&ctx](const Req&, Res& res) { send(res, protocol::get_snapshot(ctx.engine)); });
    router.post("/v1/scene/snapshot", [&ctx](const Req& req, Res& res, std::string&& body) {
        const std::optional<std::string> if_match =
            req.has_header("If-Match") ? std::optional(req.get_header_value("If-Match"))
                                       : std::nullopt;
        send(res, protocol::post_snapshot(ctx.engine, std::move(body), if_match));
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
        if (ctx.streams) write_stream_metrics(text, ctx.streams->stats());
        res.set_content(text, "text/plain; version=0.0.4; charset=utf-8");
    });
}

}  // namespace strata::server
