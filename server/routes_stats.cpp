// GET /v1/stats (JSON) and GET /metrics (Prometheus text).

#include "protocol/report_json.h"
#include "server/context.h"
#include "server/http_util.h"
#include "server/router.h"

namespace strata::server {

void add_stats_routes(Router& router, ServerContext& ctx) {
    router.get("/v1/stats", [&ctx](const httplib::Request&, httplib::Response& res) {
        const EngineCounters counters = ctx.engine.counters();
        const RebuildReport last = ctx.engine.last_report();
        const uint64_t version = ctx.engine.read([](const Scene& s) { return s.version(); });
        protocol::Json doc = {{"version", version},
                              {"counters", protocol::counters_to_json(counters)},
                              {"last_report", counters.commits ? protocol::report_to_json(last)
                                                               : protocol::Json(nullptr)},
                              {"memory_bytes",
                               {{"blas", ctx.engine.memory_bytes(MemoryCategory::Blas)},
                                {"tlas", ctx.engine.memory_bytes(MemoryCategory::Tlas)}}}};
        set_etag(res, version);
        send_json(res, 200, doc);
    });
    router.get("/metrics", [&ctx](const httplib::Request&, httplib::Response& res) {
        res.status = 200;
        res.set_content(ctx.metrics.prometheus_text(ctx.engine),
                        "text/plain; version=0.0.4; charset=utf-8");
    });
}

}  // namespace strata::server
