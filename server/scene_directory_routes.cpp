// GET /v1/scenes, and GET, PUT and DELETE /v1/scenes/{scene}: the directory of named scenes
// (named_scenes.h). Every other /v1 route also exists under /v1/scenes/{scene}/ (application.cpp
// dispatches it); describe_scene_routes lists those for the OpenAPI description.

#include "protocol/api.h"
#include "server/auth.h"
#include "server/context.h"
#include "server/named_scenes.h"
#include "server/route_table.h"

namespace strata::server {

namespace {

using protocol::ok_json;
using protocol::problem;
using protocol::ProblemType;

constexpr const char* DEFAULT_SCENE = "default";

/// The scene's summary (GET /v1/scenes/{scene}), with its version as the ETag.
protocol::ApiResponse summary(std::string_view name, const Engine& engine,
                              const SceneBudget& budget, bool durable, int status = 200) {
    return protocol::with_etag(
        protocol::json_response(status,
                                protocol::scene_summary_json(name, engine, budget, durable)),
        engine.version());
}

protocol::ApiResponse default_summary(const ServerContext& ctx, int status = 200) {
    return summary(DEFAULT_SCENE, ctx.engine, ctx.api_limits.budget, ctx.store != nullptr,
                   status);
}

protocol::ParamDoc scene_parameter() {
    return {.name = "scene",
            .in = "path",
            .description = std::string("the scene's name: ") + protocol::SCENE_NAME_RULE +
                           "; \"default\" is the scene the paths without /v1/scenes/{scene} "
                           "serve"};
}

/// Every scene `grants` may read (all without a tokens file), the default one first.
Reply list_scenes(const ServerContext& ctx, const SceneDirectory& scenes, const Grants* grants) {
    const auto visible = [grants](std::string_view name) {
        return !grants || grants->in(name) >= Role::Read;
    };
    protocol::Json list = protocol::Json::array();
    if (visible(DEFAULT_SCENE))
        list.push_back(protocol::scene_summary_json(DEFAULT_SCENE, ctx.engine,
                                                    ctx.api_limits.budget, ctx.store != nullptr));
    for (const auto& scene : scenes.list()) {
        if (!visible(scene->name())) continue;
        list.push_back(protocol::scene_summary_json(scene->name(), scene->engine(),
                                                    scene->budget(), scene->durable()));
    }
    return protocol::json_response(200, {{"scenes", std::move(list)}});
}

Reply get_scene(const ServerContext& ctx, SceneDirectory& scenes, const std::string& name) {
    if (name == DEFAULT_SCENE) return default_summary(ctx);
    const auto scene = scenes.find(name);
    if (!scene) return unknown_scene(name);
    return summary(name, scene->engine(), scene->budget(), scene->durable());
}

Reply put_scene(const ServerContext& ctx, SceneDirectory& scenes, const std::string& name,
                std::string_view body) {
    if (!protocol::valid_scene_name(name)) {
        protocol::Problem p = protocol::make_problem(
            ProblemType::InvalidRequest, "'" + name.substr(0, 80) +
                                             "' is not a scene name: " + protocol::SCENE_NAME_RULE);
        p.pointer = "/scene";
        return p;
    }
    auto budget = protocol::parse_scene_settings(body, scenes.default_budget(),
                                                 ctx.api_limits.json);
    if (!budget) return budget.error();
    if (name == DEFAULT_SCENE) {
        if (!same_budget(budget.value(), ctx.api_limits.budget))
            return protocol::make_problem(ProblemType::SceneConflict,
                                          "the default scene's budget is the server's "
                                          "--max-scene-* flags; it cannot be changed");
        return default_summary(ctx);
    }
    auto made = scenes.create(name, budget.value());
    if (!made) return made.error();
    const auto& [scene, created] = made.value();
    return summary(name, scene->engine(), scene->budget(), scene->durable(), created ? 201 : 200);
}

Reply delete_scene(SceneDirectory& scenes, const std::string& name) {
    if (name == DEFAULT_SCENE)
        return protocol::make_problem(ProblemType::SceneConflict,
                                      "the default scene cannot be deleted; a `clear` edit "
                                      "empties it");
    auto removed = scenes.remove(name);
    if (!removed) return removed.error();
    if (!removed.value()) return unknown_scene(name);
    protocol::ApiResponse r;
    r.status = 204;
    return r;
}

}  // namespace

protocol::Problem unknown_scene(std::string_view name) {
    protocol::Problem p = protocol::make_problem(
        ProblemType::NotFound, "no scene named '" + std::string(name.substr(0, 80)) + "'");
    p.pointer = "/scene";
    return p;
}

bool scene_route(std::string_view route) {
    return route != "/v1/openapi.json" && route != "/v1/scenes" &&
           route.substr(0, 11) != "/v1/scenes/";
}

void add_scene_directory_routes(RouteTable& routes, ServerContext& ctx, SceneDirectory& scenes) {
    const protocol::ResponseDoc missing = problem(404, "no scene has this name");
    routes.get("/v1/scenes",
               {{.summary = "The scenes this server holds: the default one, then the named ones",
                 .tag = "scenes",
                 .responses = {ok_json("SceneList", "every scene's summary", {})}},
                [&ctx, &scenes](RouteCall& call) {
                    return list_scenes(ctx, scenes, call.context.grants);
                }});
    routes.get("/v1/scenes/{scene}",
               {{.summary = "One scene's summary: version, totals, memory and budget",
                 .tag = "scenes",
                 .parameters = {scene_parameter()},
                 .responses = {ok_json("SceneSummary", "the summary"), missing}},
                [&ctx, &scenes](RouteCall& call) {
                    return get_scene(ctx, scenes, call.params[0]);
                }});
    routes.add(
        "PUT", "/v1/scenes/{scene}",
        {{.summary = "Create a named scene (empty), or find the one that exists",
          .description =
              "Idempotent. Every /v1 route then also exists under /v1/scenes/{scene}/, for this "
              "scene alone: its own version, journal and snapshots (--data/scenes/{scene}/), "
              "undo history, streams and past versions. The body may lower the scene's budget "
              "below the server's --max-scene-* flags. With --log the scene is the shared edit "
              "log's: every server on the log holds it, and its edits go to its own stream.",
          .tag = "scenes",
          .parameters = {scene_parameter()},
          .body = "SceneSettings",
          .responses = {ok_json("SceneSummary", "the scene existed already, with this budget"),
                        {.status = 201,
                         .description = "created",
                         .schema = "SceneSummary",
                         .headers = {"ETag"}},
                        problem(400, "not a scene name, or a body that does not match the schema"),
                        problem(409, "the scene exists with another budget, or an earlier "
                                     "scene of this name is still being deleted or replaced"),
                        problem(413, "the server holds --max-scenes named scenes already, or the "
                                     "scenes' budgets would add up to more than --max-total-*"),
                        problem(422, "a budget above the server's flag (the pointer names it)"),
                        problem(503, "the data directory could not take the scene, or (--log) "
                                     "Redis is unreachable")}},
         [&ctx, &scenes](RouteCall& call) {
             return put_scene(ctx, scenes, call.params[0], call.request.body);
         }});
    routes.add("DELETE", "/v1/scenes/{scene}",
               {{.summary = "Delete a named scene: its objects, history and files",
                 .description = "Requests already running on the scene finish; later ones get "
                                "404. Its memory and files are freed when the last of them ends. "
                                "With --log, every server on the log deletes it.",
                 .tag = "scenes",
                 .parameters = {scene_parameter()},
                 .responses = {{.status = 204, .description = "deleted"},
                               missing,
                               problem(409, "the default scene is never deleted"),
                               problem(503, "(--log) Redis is unreachable: nothing was "
                                            "deleted")}},
                [&scenes](RouteCall& call) { return delete_scene(scenes, call.params[0]); }});
}

void describe_scene_routes(RouteTable& routes) {
    // Copied out first: describing adds to the listing.
    std::vector<std::pair<std::string, std::pair<std::string, protocol::RouteDoc>>> scoped;
    for (const protocol::RouteListing& route : routes.listing()) {
        if (route.pattern.substr(0, 4) != "/v1/" || !scene_route(route.pattern)) continue;
        protocol::RouteDoc doc = *route.doc;
        doc.parameters.insert(doc.parameters.begin(), scene_parameter());
        doc.responses.push_back(problem(404, "no scene has this name"));
        doc.summary += " (in a named scene)";
        scoped.push_back({route.method, {"/v1/scenes/{scene}/" + route.pattern.substr(4),
                                         std::move(doc)}});
    }
    for (auto& [method, route] : scoped)
        routes.describe(method, route.first, std::move(route.second));
}

}  // namespace strata::server
