#include "server/application.h"

#include <chrono>

#include <spdlog/spdlog.h>

#include "server/context.h"
#include "server/replica/replica.h"
#include "server/http_util.h"
#include "server/router.h"
#include "server/split_render.h"

namespace strata::server {

namespace {

using protocol::ProblemType;

double ms_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

Application::Application(const ServerConfig& config, Engine& engine, ServerMetrics& metrics,
                         const FrontEndCounters* front_end, std::function<bool()> ready,
                         durable::DurableStore* store, StreamHub* streams)
    : m_config(config),
      m_engine(engine),
      m_metrics(metrics),
      m_ready(std::move(ready)),
      m_store(store) {
    m_routes.set_payload_max_length(m_config.max_body_bytes);
    m_routes.set_keep_alive_timeout(m_config.keep_alive_timeout_s);
    m_routes.set_keep_alive_max_count(m_config.max_keep_alive_requests);
    install_hooks();
    install_routes(front_end, streams);
}

Application::~Application() = default;

void Application::install_hooks() {
    // Responses that leave httplib without a body of ours: unknown routes (404), bodies over the
    // cap on routes without a content reader (413), anything else httplib refuses itself.
    m_routes.set_error_handler(httplib::Server::HandlerWithResponse(
        [](const httplib::Request& req, httplib::Response& res) {
            using R = httplib::Server::HandlerResponse;
            if (!res.body.empty()) return R::Unhandled;
            protocol::Problem p;
            if (res.status == 404) {
                // req.path is the normalised target: ASCII, non-printable bytes percent-encoded.
                p = protocol::make_problem(ProblemType::NotFound,
                                           "no route for " + req.method + " " + req.path);
            } else if (res.status == 413) {
                p = protocol::make_problem(ProblemType::TooLarge,
                                           "request body is larger than the limit");
            } else {
                p = protocol::make_problem(
                    res.status < 500 ? ProblemType::InvalidRequest : ProblemType::Internal,
                    "malformed or unsupported HTTP request (status " + std::to_string(res.status) +
                        ")");
            }
            p.status = res.status;
            send_problem(res, p);
            return R::Handled;
        }));

    m_routes.set_exception_handler(answer_unhandled_exception);

    m_routes.set_logger([this](const httplib::Request& req, const httplib::Response& res) {
        m_metrics.count_response(res.status);
        RequestContext* context = current_request();
        if (context && res.get_header_value("Connection") == "close") context->close = true;
        spdlog::info("{} {} {} {}B {:.2f}ms", req.method, req.path, res.status, res.body.size(),
                     context ? ms_since(context->received) : 0.0);
    });
}

void Application::attach_store(durable::DurableStore* store) {
    m_store = store;
    m_context->store = store;
}

void Application::attach_replica(replica::Replica* replica) {
    m_context->replica = replica;
    m_context->append_to_log = [replica](EditBatch&& batch, std::optional<uint64_t> expected) {
        return replica->append(std::move(batch), expected);
    };
}

void Application::install_routes(const FrontEndCounters* front_end, StreamHub* streams) {
    m_context = std::make_unique<ServerContext>(ServerContext{
        m_engine, m_config, m_metrics,
        protocol::ApiLimits{
            protocol::JsonLimits{m_config.max_json_depth, m_config.max_array_elements},
            m_config.max_pixels, m_config.render_timeout_s,
            SceneBudget{m_config.max_scene_triangles, m_config.max_scene_vertices,
                        m_config.max_texture_mb << 20}},
        front_end, m_store, nullptr, {}, streams, {}});
    if (!m_config.peers.empty()) {
        // finish_config checked the list.
        auto peers = parse_peers(m_config.peers);
        if (peers && !peers.value().empty()) {
            auto splitter = std::make_shared<SplitRenderer>(
                m_engine, std::move(peers.value()), m_config.token,
                std::chrono::milliseconds(m_config.peer_timeout_ms));
            spdlog::info("split renders: up to {} bands, with peers {}",
                         splitter->peers().size() + 1, m_config.peers);
            m_context->split_render = [splitter](const RenderRequest& r, uint32_t split) {
                return splitter->render(r, split);
            };
        }
    }
    Router router(m_routes, m_config.max_body_bytes);
    add_api_routes(router, *m_context);
    add_stream_routes(router, *m_context);
    add_web_routes(router);
    // The front end answers /livez and /readyz itself; these routes make them known to the
    // router, so that other methods get 405 with Allow.
    router.get("/livez", [](const httplib::Request&, httplib::Response& res) {
        send_json(res, 200, {{"status", "ok"}});
    });
    router.get("/readyz", [this](const httplib::Request&, httplib::Response& res) {
        if (m_ready()) return send_json(res, 200, {{"status", "ready"}});
        send_problem(res, protocol::make_problem(ProblemType::Unavailable,
                                                 "the server is starting or shutting down"));
    });
    router.finish();
}

}  // namespace strata::server
