#include "server/server.h"

#include <chrono>
#include <thread>

#include <httplib.h>
#include <spdlog/spdlog.h>

#include "server/auth.h"
#include "server/context.h"
#include "server/http_util.h"
#include "server/router.h"

namespace strata::server {

namespace {

using protocol::ProblemType;
using Clock = std::chrono::steady_clock;

/// When the request on this worker thread started (set by the pre-routing hook; a worker serves
/// one request at a time from start to access-log line).
thread_local Clock::time_point t_request_start{};

bool is_health_path(const std::string& path) {
    return path == "/livez" || path == "/readyz";
}

}  // namespace

Server::Server(ServerConfig config, Engine& engine)
    : m_config(std::move(config)), m_engine(engine), m_http(std::make_unique<httplib::Server>()) {
    const std::size_t threads = std::max<std::size_t>(1, m_config.threads);
    m_http->new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
    m_http->set_payload_max_length(m_config.max_body_bytes);
    m_http->set_read_timeout(m_config.read_timeout_s, 0);
    m_http->set_write_timeout(m_config.write_timeout_s, 0);
    m_http->set_keep_alive_timeout(m_config.keep_alive_timeout_s);
    m_http->set_keep_alive_max_count(1000);
    // httplib writes a response's headers and body separately: with Nagle's algorithm, every
    // request after the first on a keep-alive connection would wait ~40 ms for the client's
    // delayed ACK.
    m_http->set_tcp_nodelay(true);
    install_hooks();
    install_routes();
}

Server::~Server() {
    stop();
}

void Server::install_hooks() {
    m_http->set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
        t_request_start = Clock::now();
        using R = httplib::Server::HandlerResponse;
        if (!m_config.token.empty() && !is_health_path(req.path) &&
            !bearer_token_matches(req.get_header_value("Authorization"), m_config.token)) {
            res.set_header("WWW-Authenticate", "Bearer realm=\"strata\"");
            res.set_header("Connection", "close");  // the body, if any, is never read
            send_problem(res, protocol::make_problem(
                                  ProblemType::Unauthorized,
                                  req.has_header("Authorization")
                                      ? "the bearer token is not valid"
                                      : "this server requires Authorization: Bearer <token>"));
            return R::Handled;
        }
        if (req.has_header("Content-Length") &&
            std::strtoull(req.get_header_value("Content-Length").c_str(), nullptr, 10) >
                m_config.max_body_bytes) {
            // Refuse before reading: httplib would otherwise read and discard the whole body.
            res.set_header("Connection", "close");
            send_problem(
                res, protocol::make_problem(
                         ProblemType::TooLarge,
                         "request body of " + req.get_header_value("Content-Length") +
                             " bytes is larger than the limit of " +
                             std::to_string(m_config.max_body_bytes) + " bytes (--max-body-mb)"));
            return R::Handled;
        }
        return R::Unhandled;
    });

    // Responses that leave httplib without a body of ours: unknown routes (404), bodies over the
    // cap on routes without a content reader (413), malformed request lines (400).
    m_http->set_error_handler(httplib::Server::HandlerWithResponse(
        [](const httplib::Request& req, httplib::Response& res) {
            using R = httplib::Server::HandlerResponse;
            if (!res.body.empty()) return R::Unhandled;
            protocol::Problem p;
            if (res.status == 404) {
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

    m_http->set_exception_handler(answer_unhandled_exception);

    m_http->set_logger([this](const httplib::Request& req, const httplib::Response& res) {
        m_metrics.count_response(res.status);
        const double ms =
            t_request_start == Clock::time_point{}
                ? 0.0
                : std::chrono::duration<double, std::milli>(Clock::now() - t_request_start).count();
        t_request_start = {};
        spdlog::info("{} {} {} {}B {:.2f}ms", req.method, req.path, res.status, res.body.size(),
                     ms);
    });
}

void Server::install_routes() {
    auto ctx = std::make_shared<ServerContext>(ServerContext{
        m_engine, m_config, m_metrics,
        protocol::ApiLimits{
            protocol::JsonLimits{m_config.max_json_depth, m_config.max_array_elements},
            m_config.max_pixels}});
    m_context = ctx;  // outlives m_http, whose handlers refer to it
    Router router(*m_http, m_config.max_body_bytes);
    add_api_routes(router, *ctx);
    router.get("/livez", [](const httplib::Request&, httplib::Response& res) {
        send_json(res, 200, {{"status", "ok"}});
    });
    router.get("/readyz", [this](const httplib::Request&, httplib::Response& res) {
        if (ready()) return send_json(res, 200, {{"status", "ready"}});
        send_problem(
            res, protocol::make_problem(ProblemType::Unavailable, "the server is shutting down"));
    });
    router.finish();
}

Result<int> Server::bind() {
    const int port =
        m_config.port == 0
            ? m_http->bind_to_any_port(m_config.host)
            : (m_http->bind_to_port(m_config.host, m_config.port) ? m_config.port : -1);
    if (port < 0)
        return failure(ErrorCode::InvalidArgument,
                       "cannot listen on " + m_config.host + ":" + std::to_string(m_config.port));
    m_port = port;
    return port;
}

void Server::listen() {
    m_listening = true;
    if (!m_stop_requested) m_http->listen_after_bind();
    m_listening = false;
}

void Server::stop() {
    m_stop_requested = true;
    // httplib's stop() is a no-op until listen_after_bind() has started: wait for that, briefly.
    for (int i = 0; i < 2000 && m_listening && !m_http->is_running(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    m_http->stop();
}

bool Server::ready() const {
    return m_http->is_running() && !m_stop_requested;
}

}  // namespace strata::server
