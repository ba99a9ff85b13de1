#include "server/application.h"

#include <spdlog/spdlog.h>

#include "server/access.h"
#include "server/context.h"
#include "server/named_scenes.h"
#include "server/replica/replica.h"
#include "server/request_target.h"
#include "server/response_writer.h"
#include "server/scene_path.h"
#include "server/split_render.h"
#include "server/stream_channel.h"

namespace strata::server {

Application::Application(const ServerConfig& config, Engine& engine, ServerMetrics& metrics,
                         const FrontEndCounters* front_end, durable::DurableStore* store,
                         StreamHub* streams, std::function<bool()> api_busy)
    : m_config(config), m_engine(engine), m_metrics(metrics) {
    m_scenes = std::make_unique<SceneDirectory>(
        SceneShared{config, metrics, front_end, std::move(api_busy), engine.shared_device()});
    install_routes(front_end, streams);
    m_context->store = store;
}

Application::~Application() = default;

Outcome Application::handle(PreparedRequest&& request, RequestContext& context, bool close) const {
    context.grants = request.grants.get();
    Reply reply = dispatch(request.http, context);
    Outcome out;
    out.status = reply.response.status;
    if (reply.stream) {
        out.bytes = write_stream_head(reply.response, request.cors_origin);
        out.stream = std::move(reply.stream);
        return out;
    }
    Framing framing;
    framing.close = close;
    framing.head_only = request.http.method == "HEAD";
    framing.cors_origin = request.cors_origin;
    out.bytes = write_response(reply.response, framing);
    return out;
}

Reply Application::dispatch(HttpRequest& request, RequestContext& context) const {
    if (context.grants) {
        if (auto refused = refuse_access(*context.grants,
                                         required_access(request.method, request.path)))
            return *refused;
    }
    const std::optional<ScenePath> scoped = scene_path(request.path);
    if (!scoped) return m_routes.dispatch(request, context);
    const std::string name = decode_path_segment(scoped->scene);
    std::shared_ptr<HostedScene> scene;  // held while its route runs
    const RouteTable* routes = &m_routes;
    if (name != "default") {
        scene = m_scenes->find(name);
        if (!scene) return unknown_scene(name);
        routes = &scene->routes();
    }
    // What only the unprefixed paths serve: the directory of scenes, the API's description.
    if (!scene_route(scoped->route))
        return protocol::make_problem(protocol::ProblemType::NotFound,
                                      "no route for " + request.method + " " + request.path);
    request.path = scoped->route;
    return routes->dispatch(request, context);
}

void Application::attach_store(durable::DurableStore* store) {
    m_context->store = store;
}

void ServerContext::attach_replica(replica::Replica* r) {
    replica = r;
    append_to_log = [r](EditBatch&& batch, std::optional<uint64_t> expected) {
        return r->append(std::move(batch), expected);
    };
}

void Application::attach_replica(replica::Replica* replica) {
    m_context->attach_replica(replica);
}

void Application::install_routes(const FrontEndCounters* front_end, StreamHub* streams) {
    m_context = std::make_unique<ServerContext>(ServerContext{
        m_engine, m_config, m_metrics, api_limits(m_config), front_end, nullptr, nullptr, {},
        streams, {}});
    // Past versions share the scene's Embree device: their meshes mostly share its BLASes.
    EngineConfig past = engine_config(m_config);
    past.accel.shared_device = m_engine.shared_device();
    m_context->past = std::make_unique<PastScenes>(past);
    m_context->scenes = m_scenes.get();
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
    add_api_routes(m_routes, *m_context);
    add_stream_routes(m_routes, *m_context);
    add_scene_directory_routes(m_routes, *m_context, *m_scenes);
    add_web_routes(m_routes);
    describe_scene_routes(m_routes);
}

}  // namespace strata::server
