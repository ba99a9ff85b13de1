// GET /v1/scene and one object's state: /v1/scene/{meshes,instances,materials}/{id}.

#include "protocol/scene_json.h"
#include "server/context.h"
#include "server/http_util.h"
#include "server/router.h"

namespace strata::server {

namespace {

using ObjectToJson = std::optional<protocol::Json> (*)(const Scene&, std::string_view);

void get_object(ServerContext& ctx, const httplib::Request& req, httplib::Response& res,
                const char* kind, ObjectToJson to_json) {
    const std::string id = req.matches[1];
    // One read lock: the document and its version belong together.
    auto [doc, version] =
        ctx.engine.read([&](const Scene& s) { return std::pair(to_json(s, id), s.version()); });
    set_etag(res, version);
    if (!doc)
        return send_problem(
            res, protocol::make_problem(protocol::ProblemType::NotFound,
                                        std::string("no ") + kind + " with id '" + id + "'"));
    send_json(res, 200, *doc);
}

}  // namespace

void add_scene_routes(Router& router, ServerContext& ctx) {
    router.get("/v1/scene", [&ctx](const httplib::Request&, httplib::Response& res) {
        auto doc =
            ctx.engine.read([](const Scene& s) { return protocol::scene_summary_to_json(s); });
        set_etag(res, doc["version"].get<uint64_t>());
        send_json(res, 200, doc);
    });
    router.get(R"(/v1/scene/meshes/([^/]+))",
               [&ctx](const httplib::Request& req, httplib::Response& res) {
                   get_object(ctx, req, res, "mesh", protocol::mesh_to_json);
               });
    router.get(R"(/v1/scene/instances/([^/]+))",
               [&ctx](const httplib::Request& req, httplib::Response& res) {
                   get_object(ctx, req, res, "instance", protocol::instance_to_json);
               });
    router.get(R"(/v1/scene/materials/([^/]+))",
               [&ctx](const httplib::Request& req, httplib::Response& res) {
                   get_object(ctx, req, res, "material", protocol::material_to_json);
               });
}

}  // namespace strata::server
