// POST /v1/edits, POST /v1/commit, GET /v1/plan.

#include <spdlog/spdlog.h>

#include "protocol/edit_parser.h"
#include "protocol/report_json.h"
#include "server/context.h"
#include "server/http_util.h"
#include "server/router.h"

namespace strata::server {

using protocol::Json;

void record_commit(ServerContext& ctx, const RebuildReport& report, const char* cause) {
    ctx.metrics.commit_seconds.observe(report.phases.total_ms / 1000.0);
    spdlog::info("commit ({}) {}", cause, report.summary());
}

namespace {

void post_edits(ServerContext& ctx, const httplib::Request& req, httplib::Response& res,
                std::string&& body) {
    protocol::Problem problem;
    const auto if_match = parse_if_match(req, problem);
    if (!if_match) return send_problem(res, problem);

    auto parsed = protocol::parse_edit_batch(body, ctx.json_limits);
    body = {};  // the DOM and the batch hold what is needed; free the text early
    if (!parsed) return send_problem(res, protocol::problem_from(parsed.error()));
    protocol::ParsedBatch& batch = parsed.value();

    auto applied = ctx.engine.apply(std::move(batch.batch), if_match->version);
    if (!applied) {
        const Error& e = applied.error();
        if (e.code == ErrorCode::VersionMismatch) {
            set_etag(res, ctx.engine.read([](const Scene& s) { return s.version(); }));
            return send_problem(res, protocol::make_problem(protocol::ProblemType::VersionMismatch,
                                                            "If-Match: " + e.message));
        }
        return send_problem(res, protocol::problem_from_batch_error(e, batch.sources));
    }
    set_etag(res, applied.value().version);
    send_json(res, 200,
              {{"version", applied.value().version}, {"applied", applied.value().applied}});
}

void post_commit(ServerContext& ctx, httplib::Response& res) {
    auto report = ctx.engine.commit();
    if (!report) return send_problem(res, protocol::problem_from(report.error()));
    record_commit(ctx, report.value(), "commit");
    set_etag(res, report.value().version);
    send_json(res, 200, protocol::report_to_json(report.value()));
}

void get_plan(ServerContext& ctx, httplib::Response& res) {
    RebuildReport plan = ctx.engine.plan();
    // A plan's memory is what the acceleration structures hold now, before the commit.
    plan.memory_blas_bytes = ctx.engine.memory_bytes(MemoryCategory::Blas);
    plan.memory_tlas_bytes = ctx.engine.memory_bytes(MemoryCategory::Tlas);
    set_etag(res, plan.version);
    send_json(res, 200, protocol::report_to_json(plan));
}

}  // namespace

void add_edit_routes(Router& router, ServerContext& ctx) {
    router.post("/v1/edits",
                [&ctx](const httplib::Request& req, httplib::Response& res, std::string&& body) {
                    post_edits(ctx, req, res, std::move(body));
                });
    router.post("/v1/commit", [&ctx](const httplib::Request&, httplib::Response& res,
                                     std::string&&) { post_commit(ctx, res); });
    router.get("/v1/plan",
               [&ctx](const httplib::Request&, httplib::Response& res) { get_plan(ctx, res); });
}

}  // namespace strata::server
