#include "clients/cli/embedded_transport.h"

#include "engine/engine.h"
#include "protocol/demo/demo_models.h"
#include "protocol/api.h"

namespace strata::cli {

namespace {

/// The server's default limits (strata-server without flags).
const protocol::ApiLimits LIMITS{};

Reply to_reply(protocol::ApiResponse&& r) {
    Reply out;
    out.status = r.status;
    out.content_type = std::move(r.content_type);
    out.body = std::move(r.body);
    out.headers = std::move(r.headers);
    out.headers.emplace_back("Content-Type", out.content_type);
    return out;
}

}  // namespace

Outcome<std::unique_ptr<EmbeddedTransport>> EmbeddedTransport::create(bool demo) {
    auto engine = Engine::create();
    if (!engine)
        return Unexpected(Failure{"cannot start the engine: " + engine.error().describe()});
    if (demo) {
        auto batch = demo::scene_with_models();
        if (!batch)
            return Unexpected(Failure{"demo scene not built: " + batch.error().describe()});
        auto applied = engine.value()->apply(std::move(batch.value()));
        if (!applied)
            return Unexpected(Failure{"demo scene rejected: " + applied.error().describe()});
    }
    return std::unique_ptr<EmbeddedTransport>(new EmbeddedTransport(std::move(engine.value())));
}

EmbeddedTransport::EmbeddedTransport(std::unique_ptr<Engine> engine)
    : m_engine(std::move(engine)) {}

EmbeddedTransport::~EmbeddedTransport() = default;

Reply EmbeddedTransport::edits(std::string body, const std::optional<std::string>& if_match) {
    return to_reply(protocol::post_edits(
        *m_engine, std::move(body),
        if_match ? std::optional<std::string_view>(*if_match) : std::nullopt, LIMITS));
}

Reply EmbeddedTransport::undo(bool redo, const std::optional<std::string>& if_match) {
    return to_reply(protocol::post_undo(
        *m_engine, redo, if_match ? std::optional<std::string_view>(*if_match) : std::nullopt));
}

Reply EmbeddedTransport::history(const std::multimap<std::string, std::string>& query) {
    return to_reply(protocol::get_history(*m_engine, query));
}

Reply EmbeddedTransport::commit() {
    return to_reply(protocol::post_commit(*m_engine));
}

Reply EmbeddedTransport::plan() {
    return to_reply(protocol::get_plan(*m_engine));
}

Reply EmbeddedTransport::render(const std::string& body) {
    return to_reply(protocol::post_render(*m_engine, body, LIMITS));
}

Reply EmbeddedTransport::stats() {
    return to_reply(protocol::get_stats(*m_engine));
}

Reply EmbeddedTransport::scene() {
    return to_reply(protocol::get_scene(*m_engine));
}

namespace {

/// The listing kind of a collection name, as the server's routes spell them.
std::optional<protocol::SceneObject> collection_kind(const std::string& collection) {
    if (collection == "meshes") return protocol::SceneObject::Mesh;
    if (collection == "instances") return protocol::SceneObject::Instance;
    if (collection == "materials") return protocol::SceneObject::Material;
    if (collection == "groups") return protocol::SceneObject::Group;
    if (collection == "lights") return protocol::SceneObject::Light;
    if (collection == "textures") return protocol::SceneObject::Texture;
    return std::nullopt;
}

Reply no_route(const std::string& collection) {
    return to_reply(protocol::problem_response(protocol::make_problem(
        protocol::ProblemType::NotFound, "no route for GET /v1/scene/" + collection)));
}

}  // namespace

Reply EmbeddedTransport::scene_list(const std::string& collection,
                                    const std::multimap<std::string, std::string>& query) {
    if (collection == "tree") return to_reply(protocol::get_scene_tree(*m_engine, query));
    const auto kind = collection_kind(collection);
    if (!kind) return no_route(collection);
    return to_reply(protocol::get_scene_list(*m_engine, *kind, query));
}

Reply EmbeddedTransport::scene_object(const std::string& collection, const std::string& id) {
    const auto kind = collection_kind(collection);
    if (!kind) return no_route(collection);
    return to_reply(protocol::get_scene_object(*m_engine, *kind, id));
}

Reply EmbeddedTransport::pick(const std::string& body) {
    return to_reply(protocol::post_pick(*m_engine, body, LIMITS));
}

Reply EmbeddedTransport::get_snapshot(std::optional<uint64_t> at_version,
                                      const std::optional<std::string>& at_time) {
    if ((at_version && *at_version != m_engine->version()) || at_time)
        return to_reply(protocol::problem_response(protocol::make_problem(
            protocol::ProblemType::NotFound,
            "at_version, at_time: the embedded engine keeps no data directory, only its current "
            "version " +
                std::to_string(m_engine->version()))));
    return to_reply(protocol::get_snapshot(*m_engine));
}

Reply EmbeddedTransport::put_snapshot(std::string bytes) {
    return to_reply(protocol::post_snapshot(*m_engine, std::move(bytes), std::nullopt));
}

Reply EmbeddedTransport::import_asset(std::string bytes,
                                      const std::multimap<std::string, std::string>& query) {
    return to_reply(protocol::post_assets(*m_engine, std::move(bytes), query,
                                          std::string("application/octet-stream"), std::nullopt,
                                          LIMITS));
}

Reply EmbeddedTransport::assets(const std::optional<std::string>& id) {
    return to_reply(id ? protocol::get_asset(*m_engine, *id) : protocol::get_assets(*m_engine));
}

Reply EmbeddedTransport::delete_asset(const std::string& id) {
    return to_reply(protocol::delete_asset(*m_engine, id, std::nullopt));
}

Reply EmbeddedTransport::put_asset(const std::string& id, std::string bytes,
                                   const std::multimap<std::string, std::string>& query) {
    return to_reply(protocol::put_asset(*m_engine, id, std::move(bytes), query,
                                        std::string("application/octet-stream"), std::nullopt,
                                        LIMITS));
}

}  // namespace strata::cli
