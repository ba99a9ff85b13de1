// POST /v1/render (JSON body) and GET /v1/render (query string): one frame, encoded.

#include <spdlog/spdlog.h>

#include "engine/core/timer.h"
#include "protocol/render_parser.h"
#include "server/context.h"
#include "server/http_util.h"
#include "server/router.h"

namespace strata::server {

namespace {

using protocol::ProblemType;

void render(ServerContext& ctx, const protocol::RenderSpec& spec, httplib::Response& res) {
    const RenderRequest& q0 = spec.request;
    const uint64_t pixels = uint64_t(q0.width) * q0.height;
    if (pixels > ctx.config.max_pixels) {
        protocol::Problem p = protocol::make_problem(
            ProblemType::TooLarge, std::to_string(q0.width) + "x" + std::to_string(q0.height) +
                                       " is " + std::to_string(pixels) +
                                       " pixels; this server renders at most " +
                                       std::to_string(ctx.config.max_pixels) + " (--max-pixels)");
        p.pointer = "/width";
        return send_problem(res, p);
    }
    RenderRequest request = spec.request;
    if (spec.camera) {
        // Fields the override leaves out come from the scene camera as it is now.
        const Camera scene_camera = ctx.engine.read([](const Scene& s) { return s.camera(); });
        request = protocol::resolve_render_request(spec, scene_camera);
    }
    Stopwatch clock;
    auto image = ctx.engine.render(request);
    if (!image) return send_problem(res, protocol::problem_from(image.error()));
    ctx.metrics.render_seconds.observe(clock.ms() / 1000.0);
    const RenderedImage& frame = image.value();
    record_commit(ctx, frame.report, "render");
    set_etag(res, frame.version);
    res.set_header("X-Strata-Rebuild", frame.report.summary());
    res.set_header("Cache-Control", "no-store");
    res.status = 200;
    res.set_content(reinterpret_cast<const char*>(frame.bytes.data()), frame.bytes.size(),
                    frame.content_type.c_str());
}

}  // namespace

void add_render_routes(Router& router, ServerContext& ctx) {
    router.post(
        "/v1/render", [&ctx](const httplib::Request&, httplib::Response& res, std::string&& body) {
            // An empty body means every default, like GET without a query.
            auto doc = body.empty() ? protocol::Parsed<protocol::Json>(protocol::Json::object())
                                    : protocol::parse_json(body, ctx.json_limits);
            if (!doc) return send_problem(res, protocol::problem_from(doc.error()));
            auto spec = protocol::parse_render_body(doc.value());
            if (!spec) return send_problem(res, protocol::problem_from(spec.error()));
            render(ctx, spec.value(), res);
        });
    router.get("/v1/render", [&ctx](const httplib::Request& req, httplib::Response& res) {
        auto spec = protocol::parse_render_query(req.params);
        if (!spec) return send_problem(res, protocol::problem_from(spec.error()));
        render(ctx, spec.value(), res);
    });
}

}  // namespace strata::server
