// Every /v1 route and /metrics: thin adapters over protocol/api.h, which does the work for the
// server and for `strata play --embedded` alike. What stays here is HTTP: reading the request,
// and the server's own logs and metrics. Each route is registered with its description
// (protocol/openapi.h), which GET /v1/openapi.json serves.

#include <mutex>

#include <spdlog/spdlog.h>

#include "engine/core/timer.h"
#include "engine/durable/durable_store.h"
#include "protocol/api.h"
#include "server/context.h"
#include "server/front_end_counters.h"
#include "server/named_scenes.h"
#include "server/past_version_query.h"
#include "server/replica/replica.h"
#include "server/route_table.h"
#include "server/stream_hub.h"
#include "strata/version.h"

namespace strata::server {

namespace {

using Query = std::multimap<std::string, std::string>;
using protocol::ok_json;
using protocol::ParamDoc;
using protocol::problem;
using protocol::ResponseDoc;
using protocol::RouteDoc;

const char* const U64 = R"({"type": "integer", "minimum": 0})";
const char* const BOOLEAN = R"({"type": "boolean"})";

/// If-Match on the write endpoints (protocol/api.h, parse_if_match).
ParamDoc if_match() {
    return {.name = "If-Match",
            .in = "header",
            .description =
                "apply only if the scene is at this version: \"N\" (or N); absent or *: "
                "unconditionally; W/\"N\" never matches"};
}
ResponseDoc version_mismatch() {
    return problem(412,
                   "If-Match names another version (nothing changed); the ETag is the "
                   "current version",
                   {"ETag"});
}
ResponseDoc not_applied() {
    return problem(503,
                   "the journal or the edit log could not take the batch: nothing was applied");
}

/// An API answer whose commit, if it ran one, is logged and measured.
protocol::ApiResponse committed(ServerContext& ctx, protocol::ApiResponse&& answer,
                                const char* cause) {
    if (answer.commit) {
        ctx.metrics.commit_seconds.observe(answer.commit->phases.total_ms / 1000.0);
        spdlog::info("commit ({}) {}", cause, answer.commit->summary());
    }
    return std::move(answer);
}

/// Renders with `render`, observing the duration of successful renders (commit, tracing and
/// encoding).
/// A past version's engine (`at_version`) is not the server's: its first build is not logged or
/// measured as the scene's commit.
template <class Render>
protocol::ApiResponse rendered(ServerContext& ctx, const Engine& engine, Render&& render) {
    Stopwatch clock;
    protocol::ApiResponse answer = render();
    if (&engine != &ctx.engine) return answer;
    if (answer.status == 200) ctx.metrics.render_seconds.observe(clock.ms() / 1000.0);
    return committed(ctx, std::move(answer), "render");
}

/// The detail of a min_version wait that timed out: how far behind this server is.
std::string behind_detail(ServerContext& ctx, uint64_t wanted, uint64_t version) {
    std::string detail = "this server is at version " + std::to_string(version) +
                         ", behind min_version " + std::to_string(wanted) + " after waiting " +
                         std::to_string(ctx.config.min_version_wait_ms) + " ms";
    if (!ctx.replica) return detail;
    const replica::ReplicaStatus st = ctx.replica->status();
    char lag[160];
    std::snprintf(lag, sizeof lag,
                  " (replica lag: %llu entries, %.3f s behind the log at version %llu%s)",
                  static_cast<unsigned long long>(st.lag_entries), st.lag_seconds,
                  static_cast<unsigned long long>(st.log_version),
                  st.stopped      ? "; the replica has stopped"
                  : !st.connected ? "; Redis unreachable"
                                  : "");
    return detail + lag;
}

/// Read-your-writes across replicas: a read with `min_version` (query) or X-Strata-Min-Version
/// (header) runs once this server has applied that version. The front end holds the request
/// until then, at most --min-version-wait-ms (reactor.h), so a worker only checks: a malformed
/// value is 400, a version still not reached 503 whose detail names the lag. Takes min_version
/// out of the request's query.
std::optional<protocol::ApiResponse> check_min_version(ServerContext& ctx, HttpRequest& req) {
    const std::optional<HttpRequest::MinVersion> asked = req.min_version();
    req.query.erase("min_version");
    if (!asked) return std::nullopt;
    if (!asked->valid) {
        protocol::Problem p = protocol::make_problem(
            protocol::ProblemType::InvalidRequest,
            "min_version must be a scene version (a whole number), not '" +
                asked->text.substr(0, 40) + "'");
        p.pointer = "min_version";
        return protocol::problem_response(p);
    }
    const uint64_t version = ctx.engine.version();
    if (version >= asked->version) return std::nullopt;
    protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
        protocol::ProblemType::Unavailable, behind_detail(ctx, asked->version, version)));
    r.headers.emplace_back("Retry-After", "1");
    return r;
}

/// What check_min_version adds to a route's description.
void describe_min_version(RouteDoc& doc) {
    const char* what =
        "read once this server has applied this scene version (read your own "
        "write on another replica); waits at most --min-version-wait-ms";
    doc.parameters.push_back({.name = "min_version", .description = what, .schema = U64});
    doc.parameters.push_back(
        {.name = "X-Strata-Min-Version", .in = "header", .description = what, .schema = U64});
    doc.responses.push_back(problem(400, "min_version is not a whole number"));
    doc.responses.push_back(
        problem(503,
                "the server did not reach min_version in time (the detail names the lag), or too "
                "many reads wait for theirs (--max-waiting-reads)",
                {"Retry-After"}));
}

/// A read of the scene at `at_version` (taken out of the query), or of the live scene without
/// it: `handler` gets the engine at that version (past_scenes.h).
using EngineHandler = std::function<Reply(Engine&, RouteCall&)>;

Endpoint at_version(ServerContext& ctx, RouteDoc doc, EngineHandler handler) {
    describe_past_version(doc,
                          "loaded from the data directory's newest snapshot before it and its "
                          "journal (the first request of a version pays that load and a full "
                          "build; the last two versions asked for stay loaded)");
    return {std::move(doc), [&ctx, handler = std::move(handler)](RouteCall& call) -> Reply {
                auto asked = asked_version(ctx.engine, call.request.query);
                if (!asked) return std::move(asked.error());
                if (!asked.value()) return handler(ctx.engine, call);
                auto engine = ctx.past->at(ctx.engine, ctx.store, *asked.value());
                if (!engine) return past_version_problem(engine.error());
                return handler(*engine.value(), call);
            }};
}

/// A route whose handler runs once `min_version`, if asked for, is reached.
Endpoint after_min_version(ServerContext& ctx, Endpoint e) {
    describe_min_version(e.doc);
    e.handler = [&ctx, handler = std::move(e.handler)](RouteCall& call) -> Reply {
        if (auto refusal = check_min_version(ctx, call.request)) return std::move(*refusal);
        return handler(call);
    };
    return e;
}

/// A read of the scene that waits for `min_version` and may ask for `at_version`.
Endpoint versioned_read(ServerContext& ctx, RouteDoc doc, EngineHandler handler) {
    return after_min_version(ctx, at_version(ctx, std::move(doc), std::move(handler)));
}

/// A POST route whose body is JSON: other body types are 415 before the handler runs.
Endpoint json_body(Endpoint e) {
    e.doc.responses.push_back(problem(
        415,
        "a Content-Type that cannot carry JSON (multipart/form-data, an image, ...); none, "
        "any JSON type, text/plain and application/x-www-form-urlencoded are read as JSON"));
    e.handler = [handler = std::move(e.handler)](RouteCall& call) -> Reply {
        if (auto problem =
                protocol::json_body_type_problem(call.request.header_value("Content-Type")))
            return *problem;
        return handler(call);
    };
    return e;
}

/// A collection of scene objects: its path, the schema of its documents and the filters its
/// listing takes besides limit and cursor (scene_list.cpp).
struct Collection {
    const char* path;
    protocol::SceneObject kind;
    const char* schema;
    std::vector<ParamDoc> filters;
};

ParamDoc parent_filter() {
    return {.name = "parent",
            .description =
                "only the direct children of this group; empty (parent=) for those "
                "at the root"};
}

std::vector<Collection> collections() {
    using protocol::SceneObject;
    return {{"meshes", SceneObject::Mesh, "Mesh", {}},
            {"instances",
             SceneObject::Instance,
             "Instance",
             {{.name = "mesh", .description = "only the instances of this mesh"},
              {.name = "visible",
               .description = "only the instances whose own flag is (not) set",
               .schema = BOOLEAN},
              parent_filter()}},
            {"materials", SceneObject::Material, "Material", {}},
            {"groups", SceneObject::Group, "Group", {parent_filter()}},
            {"lights", SceneObject::Light, "Light", {}},
            {"textures", SceneObject::Texture, "Texture", {}}};
}

/// limit and cursor, as every listing takes them.
std::vector<ParamDoc> page_parameters() {
    return {{.name = "limit",
             .description = "items per page (default 100)",
             .schema = R"({"type": "integer", "minimum": 1, "maximum": 10000, "default": 100})"},
            {.name = "cursor",
             .description = "the next_cursor of the previous page: opaque, valid for its "
                            "collection only"}};
}

void add_scene_object_routes(RouteTable& routes, ServerContext& ctx, const Collection& c) {
    const std::string path = std::string("/v1/scene/") + c.path;
    const std::string one = std::string(c.schema);
    std::vector<ParamDoc> parameters = page_parameters();
    parameters.insert(parameters.end(), c.filters.begin(), c.filters.end());
    std::vector<ResponseDoc> answers = {
        ok_json(one + "Page", "one page, every item read at the page's version"),
        problem(400, "an unknown, repeated or malformed parameter (the pointer names it)")};
    if (!c.filters.empty())
        answers.push_back(
            problem(404, "a filter names no object (the pointer names it)", {"ETag"}));
    const protocol::SceneObject kind = c.kind;
    routes.get(path,
               versioned_read(ctx,
                              {.summary = "List the " + std::string(c.path) + ", a page at a time",
                               .tag = "scene",
                               .parameters = std::move(parameters),
                               .responses = std::move(answers)},
                              [kind](Engine& engine, RouteCall& call) {
                                  return protocol::get_scene_list(engine, kind, call.request.query);
                              }));
    // The path keeps reserved characters percent-encoded (request_target.h): an id holding '/'
    // arrives as one segment, decoded by the route table.
    routes.get(
        path + "/{id}",
        versioned_read(ctx,
                       {.summary = "One " + one + " document",
                        .tag = "scene",
                        .responses = {ok_json(one,
                                              "its state at the version in the "
                                              "ETag"),
                                      problem(404, "no object of this kind has the id", {"ETag"})}},
                       [kind](Engine& engine, RouteCall& call) {
                           return protocol::get_scene_object(engine, kind, call.params[0]);
                       }));
}

/// What GET /metrics reads: the numbers of every part of the server that exists.
MetricsSnapshot metrics_snapshot(const ServerContext& ctx) {
    MetricsSnapshot s;
    const Engine& engine = ctx.engine;
    s.engine = engine.counters();
    std::tie(s.scene_version, s.scene) =
        engine.read([](const Scene& scene) { return std::pair(scene.version(), scene.counts()); });
    s.blas_bytes = uint64_t(engine.memory_bytes(MemoryCategory::Blas));
    s.tlas_bytes = uint64_t(engine.memory_bytes(MemoryCategory::Tlas));
    s.tiers = engine.last_report().tlas;
    s.responses = ctx.metrics.responses();
    s.commit_seconds = ctx.metrics.commit_seconds.counts();
    s.render_seconds = ctx.metrics.render_seconds.counts();
    s.front_end = ctx.front_end;
    if (ctx.store) s.durable = ctx.store->stats();
    if (ctx.replica) s.replica = ctx.replica->status();
    if (ctx.streams) s.streams = ctx.streams->stats();
    if (ctx.scenes) {
        if (const auto& device = ctx.scenes->shared_device())
            s.shared_blases = device->pool()->stats();
        s.named_scenes.emplace();
        for (const auto& scene : ctx.scenes->list()) {
            const auto [version, totals] = scene->engine().read(
                [](const Scene& sc) { return std::pair(sc.version(), sc.mesh_totals()); });
            s.named_scenes->push_back(
                {scene->name(), version, totals.instances, totals.triangles,
                 uint64_t(std::max<int64_t>(scene->engine().memory_bytes(MemoryCategory::Blas),
                                            0))});
        }
    }
    return s;
}

void add_history_routes(RouteTable& routes, ServerContext& ctx) {
    for (const bool redo : {false, true}) {
        routes.post(
            redo ? "/v1/redo" : "/v1/undo",
            {{.summary = redo ? "Redo the newest undone batch" : "Undo the newest batch",
              .description =
                  redo ? "Applies the batch that the newest undo took back, again, as a new "
                         "version. Possible until a new edit lands (which empties the redo "
                         "stack); no body."
                       : "Applies the inverse of the newest batch on the undo stack as a new "
                         "version: journaled, counted and replicated like POST /v1/edits, and "
                         "kept across restarts back to the newest snapshot. Repeat to go further "
                         "back (at most --undo-depth batches). No body.",
              .tag = "edits",
              .parameters = {if_match()},
              .responses = {ok_json(redo ? "RedoResult" : "UndoResult",
                                    "applied: the new version and the version taken back"),
                            version_mismatch(),
                            problem(409, redo ? "nothing undone since the last edit"
                                              : "no batch left to take back"),
                            problem(413, "the inverse would take the scene over a budget "
                                         "lowered since"),
                            problem(422, "the inverse no longer applies"),
                            not_applied()}},
             [&ctx, redo](RouteCall& call) {
                 return protocol::post_undo(ctx.engine, redo,
                                            call.request.header_value("If-Match"),
                                            ctx.batch_apply());
             }});
    }
    routes.get(
        "/v1/history",
        after_min_version(
            ctx,
            {{.summary = "The versions of the scene, newest first, and the undo and redo stacks",
              .tag = "edits",
              .parameters = {{.name = "limit",
                              .description = "most entries in the page",
                              .schema = R"({"type": "integer", "minimum": 1, "maximum": 1000, )"
                                        R"("default": 50})"},
                             {.name = "cursor",
                              .description = "the next_cursor of the previous page"}},
              .responses = {ok_json("History", "one page"),
                            problem(400, "a malformed or unknown query parameter")}},
             [&ctx](RouteCall& call) {
                 return protocol::get_history(ctx.engine, call.request.query);
             }}));
}

void add_write_routes(RouteTable& routes, ServerContext& ctx) {
    routes.post(
        "/v1/edits",
        json_body({{.summary = "Apply an edit batch, atomically",
                    .description = "The batch is validated whole against the scene, each edit as "
                                   "the earlier ones leave it, before anything is applied; the "
                                   "version then grows by one. Edits only mark what changed: no "
                                   "acceleration structure is touched until the next commit.",
                    .tag = "edits",
                    .parameters = {if_match()},
                    .body = "EditBatch",
                    .body_required = true,
                    .responses = {ok_json("EditResult", "applied: the new version and the edits"),
                                  problem(400,
                                          "the body is not JSON or does not match the "
                                          "schema (pointer names where)"),
                                  version_mismatch(),
                                  problem(413,
                                          "an array over --max-array-elements, a mesh over "
                                          "2^28 vertices or triangles, a texture or a scene "
                                          "over its budget (--max-scene-*, --max-texture-mb)"),
                                  problem(422,
                                          "the batch matches the schema but cannot be "
                                          "applied (edit_index and pointer name the edit)"),
                                  not_applied()}},
                   [&ctx](RouteCall& call) {
                       HttpRequest& req = call.request;
                       return protocol::post_edits(ctx.engine, std::move(req.body),
                                                   req.header_value("If-Match"), ctx.api_limits,
                                                   ctx.batch_apply());
                   }}));
    add_history_routes(routes, ctx);
    routes.post("/v1/commit",
                {{.summary = "Commit: bring the acceleration structures in line with the scene",
                  .description = "The least work, like a launch without rays; no body.",
                  .tag = "edits",
                  .responses = {ok_json("Report",
                                        "the rebuild report of the commit it ran; the "
                                        "ETag is the committed version")}},
                 [&ctx](RouteCall&) {
                     return committed(ctx, protocol::post_commit(ctx.engine), "commit");
                 }});
}

/// The body types POST and PUT /v1/assets read.
std::vector<std::string> model_media() {
    std::vector<std::string> types = assets::media_type_names();
    types.insert(types.end(), {"application/x-tar", "application/octet-stream"});
    return types;
}

/// An import's 413.
ResponseDoc model_too_large() {
    return problem(413, "the model takes the scene over its budget, or its importer needs more "
                        "than --import-memory-mb");
}

/// The query of POST /v1/assets (`prefix` too) or PUT /v1/assets/{id}, and If-Match.
std::vector<ParamDoc> import_parameters(const char* name_doc, const char* parent_doc,
                                        bool prefix) {
    protocol::Json formats = protocol::Json::array();
    for (int f = 0; f <= int(assets::LAST_ASSET_FORMAT); ++f)
        formats.push_back(assets::format_name(assets::AssetFormat(f)));
    formats.push_back("tar");
    std::vector<ParamDoc> out = {
        {.name = "format",
         .description = "the file's format; tar: an archive of one model and the files it names",
         .schema = protocol::Json{{"enum", formats}}.dump()},
        {.name = "name", .description = name_doc}};
    if (prefix)
        out.push_back({.name = "prefix",
                       .description = "every id created starts with it (default: name's stem)"});
    out.push_back({.name = "parent", .description = parent_doc});
    out.push_back({.name = "instance",
                   .description = "false: meshes and materials only (the asset's group stays "
                                  "empty)",
                   .schema = R"({"type": "boolean", "default": true})"});
    out.push_back(if_match());
    return out;
}

void add_import_routes(RouteTable& routes, ServerContext& ctx) {
    routes.post(
        "/v1/assets",
        {{.summary = "Import a model file (glTF, OBJ, PLY, or a tar archive with its side files)",
          .description = "As one batch: atomic, journaled and versioned like POST /v1/edits. The "
                         "format comes from ?format=, else the Content-Type, else ?name='s "
                         "extension.",
          .tag = "edits",
          .parameters = import_parameters(
              "the file's name: for problems, the asset's `file` and the default prefix",
              "the group the asset's group joins (default: the root)", true),
          .body_media = model_media(),
          .body_required = true,
          .responses = {ok_json("AssetResult", "imported: the ids it created and the new version"),
                        problem(400, "an unknown format or a malformed query parameter"),
                        version_mismatch(),
                        model_too_large(),
                        problem(422,
                                "the file is malformed or uses what Strata does not import "
                                "(file and element say where), or its sandboxed importer "
                                "crashed, hung or ran past --import-timeout"),
                        not_applied()}},
         [&ctx](RouteCall& call) {
             HttpRequest& req = call.request;
             return protocol::post_assets(
                 ctx.engine, std::move(req.body), req.query, req.header_value("Content-Type"),
                 req.header_value("If-Match"), ctx.api_limits, ctx.batch_apply());
         }});
}

void add_asset_read_routes(RouteTable& routes, ServerContext& ctx) {
    const char* owns = "An asset is a group with `asset` set (what POST /v1/assets makes) and every "
                       "object whose id begins with its id and a '.'.";
    routes.get("/v1/assets",
               versioned_read(ctx,
                              {.summary = "List the imported assets with their counts and bounds",
                               .description = owns,
                               .tag = "edits",
                               .responses = {ok_json("AssetList", "every asset, by id")}},
                              [](Engine& engine, RouteCall&) {
                                  return protocol::get_assets(engine);
                              }));
    routes.get("/v1/assets/{id}",
               versioned_read(ctx,
                              {.summary = "One asset with the ids of everything it owns",
                               .description = owns,
                               .tag = "edits",
                               .responses = {ok_json("Asset", "the asset at the ETag's version"),
                                             problem(404, "no asset has the id", {"ETag"})}},
                              [](Engine& engine, RouteCall& call) {
                                  return protocol::get_asset(engine, call.params[0]);
                              }));
}

void add_asset_write_routes(RouteTable& routes, ServerContext& ctx) {
    routes.add(
        "DELETE", "/v1/assets/{id}",
        {{.summary = "Delete an asset: everything it owns, in one batch",
          .description = "Read and removed at one version (without If-Match, read again when "
                         "another writer lands in between). Journaled and undoable like any "
                         "batch.",
          .tag = "edits",
          .parameters = {if_match()},
          .responses = {ok_json("AssetDeleteResult", "deleted: the ids removed"),
                        problem(404, "no asset has the id", {"ETag"}), version_mismatch(),
                        problem(422,
                                "an object outside the asset still uses one of its meshes, "
                                "materials or textures, or sits in one of its groups"),
                        not_applied()}},
         [&ctx](RouteCall& call) {
             return protocol::delete_asset(ctx.engine, call.params[0],
                                           call.request.header_value("If-Match"),
                                           ctx.batch_apply());
         }});
    routes.add(
        "PUT", "/v1/assets/{id}",
        {{.summary = "Re-import an asset in place (or import it under this id)",
          .description = "One batch removes the old asset and imports the body with the same "
                         "ids where the structure is the same; the asset's group keeps its "
                         "transform, visibility, name and parent; textures, materials and "
                         "meshes whose content did not change are kept (no BLAS work).",
          .tag = "edits",
          .parameters = import_parameters(
              "the file's name: for problems and the asset's `file`",
              "the group the asset's group joins (default: where it was, else the root)", false),
          .body_media = model_media(),
          .body_required = true,
          .responses = {ok_json("AssetReplaceResult", "replaced: what was made, kept and removed"),
                        {.status = 201,
                         .description = "no asset had the id: imported as a new one",
                         .schema = "AssetReplaceResult",
                         .headers = {"ETag"}},
                        problem(400, "an unknown format or a malformed query parameter"),
                        version_mismatch(),
                        model_too_large(),
                        problem(422,
                                "the file is malformed or unsupported, its sandboxed importer "
                                "crashed or ran out of time, or an object outside the old "
                                "asset still uses a part it removes"),
                        not_applied()}},
         [&ctx](RouteCall& call) {
             HttpRequest& req = call.request;
             return protocol::put_asset(ctx.engine, call.params[0], std::move(req.body),
                                        req.query, req.header_value("Content-Type"),
                                        req.header_value("If-Match"), ctx.api_limits,
                                        ctx.batch_apply());
         }});
}

void add_snapshot_routes(RouteTable& routes, ServerContext& ctx) {
    routes.get(
        "/v1/scene/snapshot",
        versioned_read(ctx,
                       {.summary = "The whole scene as a snapshot file",
                        .description = "The data directory's snapshot format, taken "
                                       "under one read lock.",
                        .tag = "scene",
                        .responses = {{.status = 200,
                                       .description = "the snapshot; its ETag is the "
                                                      "version it holds",
                                       .media = {protocol::SNAPSHOT_CONTENT_TYPE},
                                       .headers = {"ETag", "Content-Disposition"}}}},
                       [](Engine& engine, RouteCall&) { return protocol::get_snapshot(engine); }));
    routes.post(
        "/v1/scene/snapshot",
        {{.summary = "Replace the scene with a snapshot's, atomically",
          .description = "One batch (a clear, then the snapshot's objects): a new version, "
                         "journaled like any batch; the snapshot's own version is not reused.",
          .tag = "edits",
          .parameters = {if_match()},
          .body_media = {protocol::SNAPSHOT_CONTENT_TYPE},
          .body_required = true,
          .responses = {ok_json("SnapshotResult", "loaded: the new version"),
                        problem(400, "the body is not a whole, undamaged snapshot"),
                        version_mismatch(),
                        problem(413, "the snapshot's scene is over the budget, or holds more "
                                     "edits than --max-batch-edits"),
                        problem(422, "the snapshot's scene cannot be loaded"), not_applied()}},
         [&ctx](RouteCall& call) {
             HttpRequest& req = call.request;
             return protocol::post_snapshot(ctx.engine, std::move(req.body),
                                            req.header_value("If-Match"), ctx.batch_apply(),
                                            ctx.api_limits.max_batch_edits);
         }});
}

/// What POST and GET /v1/render answer.
std::vector<ResponseDoc> render_answers() {
    return {{.status = 200,
             .description = "the frame; its ETag is the version it shows",
             .media = {"image/png", "image/x-exr", "application/x-npz"},
             .headers = {"ETag", "X-Strata-Rebuild", "X-Strata-Report", "X-Strata-Samples",
                         "Cache-Control", "X-Strata-Split"}},
            problem(400, "a member or parameter does not match the schema, or is unknown"),
            problem(413, "width * height over --max-pixels (pointer /width)"),
            problem(422,
                    "a value the renderer cannot use (an AOV with PNG, a band outside the "
                    "frame, a split without --peers, a camera with up along the view)"),
            problem(503,
                    "the render ran past --render-timeout (deadline-exceeded), or the "
                    "server is shutting down")};
}

Reply get_render(ServerContext& ctx, Engine& engine, RouteCall& call) {
    if (call.request.method == "HEAD") {
        // Its headers (ETag, size, rebuild summary) exist only once the frame is rendered.
        protocol::ApiResponse r = protocol::problem_response(protocol::make_problem(
            protocol::ProblemType::MethodNotAllowed,
            "HEAD /v1/render would have to render the frame to know its headers; use GET or "
            "POST"));
        r.headers.emplace_back("Allow", "GET, POST");
        return r;
    }
    return rendered(ctx, engine, [&] {
        return protocol::get_render(engine, call.request.query, ctx.api_limits,
                                    call.context.cancel, ctx.split());
    });
}

void add_render_routes(RouteTable& routes, ServerContext& ctx) {
    const char* commits =
        "Commits pending edits (as POST /v1/commit), traces and encodes one "
        "frame; an empty body means every default.";
    routes.post("/v1/render",
                json_body(versioned_read(ctx,
                                         {.summary = "Render one frame",
                                          .description = commits,
                                          .tag = "render",
                                          .body = "RenderRequest",
                                          .responses = render_answers()},
                                         [&ctx](Engine& engine, RouteCall& call) {
                                             return rendered(ctx, engine, [&] {
                                                 return protocol::post_render(
                                                     engine, call.request.body, ctx.api_limits,
                                                     call.context.cancel, ctx.split());
                                             });
                                         })));
    RouteDoc get = {.summary = "Render one frame, asked for in the query",
                    .description =
                        "The members of POST /v1/render's body as parameters: the "
                        "camera override's as the camera's fields (eye, target, up, "
                        "fov_y_deg, shutter_open, shutter_close), lists "
                        "comma-separated. HEAD is 405: the headers exist only once "
                        "the frame is rendered.",
                    .tag = "render",
                    .parameters = protocol::query_parameters("RenderRequest"),
                    .responses = render_answers(),
                    .query_token = true};
    get.responses.push_back(problem(405, "HEAD: use GET or POST", {"Allow"}));
    routes.get("/v1/render",
               versioned_read(ctx, std::move(get), [&ctx](Engine& engine, RouteCall& call) {
                   return get_render(ctx, engine, call);
               }));
}

void add_pick_routes(RouteTable& routes, ServerContext& ctx) {
    const char* rays =
        "One ray through each pixel's centre, exactly the ray a render of the "
        "same size and camera traces there; pending edits are committed first.";
    const auto answers = [](const char* schema) -> std::vector<ResponseDoc> {
        return {ok_json(schema,
                        "what lies under the pixels (null: nothing), at the version "
                        "the rays saw"),
                problem(400, "a member or parameter does not match the schema"),
                problem(422, "a pixel outside the image, or an unusable camera")};
    };
    routes.get("/v1/pick", versioned_read(ctx,
                                          {.summary = "What lies under one pixel",
                                           .description = rays,
                                           .tag = "render",
                                           .parameters = protocol::query_parameters("PickQuery"),
                                           .responses = answers("PickResult")},
                                          [](Engine& engine, RouteCall& call) {
                                              return protocol::get_pick(engine, call.request.query);
                                          }));
    routes.post("/v1/pick",
                json_body(versioned_read(ctx,
                                         {.summary = "What lies under each of a list of pixels",
                                          .description = rays,
                                          .tag = "render",
                                          .body = "PickRequest",
                                          .body_required = true,
                                          .responses = answers("PickResults")},
                                         [&ctx](Engine& engine, RouteCall& call) {
                                             return protocol::post_pick(engine, call.request.body,
                                                                        ctx.api_limits);
                                         })));
}

void add_scene_routes(RouteTable& routes, ServerContext& ctx) {
    routes.get("/v1/plan", {{.summary = "What the next commit would do, without doing it",
                             .tag = "edits",
                             .responses = {ok_json("Report",
                                                   "a planned report (no time members); its ETag "
                                                   "is the version planned")}},
                            [&ctx](RouteCall&) { return protocol::get_plan(ctx.engine); }});
    routes.get(
        "/v1/scene",
        versioned_read(ctx,
                       {.summary = "The scene: version, counts, bounds, camera and lighting",
                        .tag = "scene",
                        .responses = {ok_json("Scene", "the summary")}},
                       [](Engine& engine, RouteCall&) { return protocol::get_scene(engine); }));
    for (const Collection& c : collections()) add_scene_object_routes(routes, ctx, c);
}

void add_graph_routes(RouteTable& routes, ServerContext& ctx) {
    const ResponseDoc bad = problem(400, "an unknown, repeated or malformed parameter");
    routes.get("/v1/scene/groups/{id}/children",
               at_version(ctx,
                          {.summary = "A group's direct children, a page at a time: groups, then "
                                      "instances",
                           .tag = "scene",
                           .parameters = page_parameters(),
                           .responses = {ok_json("ChildrenPage", "one page, each item with its "
                                                                 "kind"),
                                         bad, problem(404, "no group has the id", {"ETag"})}},
                          [](Engine& engine, RouteCall& call) {
                              return protocol::get_group_children(engine, call.params[0],
                                                                  call.request.query);
                          }));
    const std::string depth = R"({"type": "integer", "minimum": 0, "maximum": )" +
                              std::to_string(MAX_GROUP_DEPTH) + R"(, "default": 1})";
    routes.get("/v1/scene/tree",
               at_version(ctx,
                          {.summary = "The scene graph nested a few levels deep, for outline panels",
                           .tag = "scene",
                           .parameters = {{.name = "depth",
                                           .description = "levels of groups nested",
                                           .schema = depth},
                                          {.name = "max_nodes",
                                           .description = "most nodes in the answer (truncated "
                                                          "says whether it cut the tree short)",
                                           .schema = R"({"type": "integer", "minimum": 1, )"
                                                     R"("maximum": 10000, "default": 1000})"},
                                          {.name = "group",
                                           .description = "start at this group, not the root"}},
                           .responses = {ok_json("SceneTree", "the tree"), bad,
                                         problem(404, "group= names no group", {"ETag"})}},
                          [](Engine& engine, RouteCall& call) {
                              return protocol::get_scene_tree(engine, call.request.query);
                          }));
}

void add_status_routes(RouteTable& routes, ServerContext& ctx) {
    routes.get("/v1/stats", {{.summary = "Cumulative counters, the last commit's report, memory "
                                         "and durability",
                              .tag = "status",
                              .responses = {ok_json("Stats",
                                                    "the numbers, at the current "
                                                    "version")}},
                             [&ctx](RouteCall&) {
                                 if (!ctx.store) return protocol::get_stats(ctx.engine);
                                 const durable::DurableStats durable = ctx.store->stats();
                                 return protocol::get_stats(ctx.engine, &durable);
                             }});
    routes.get("/metrics", {{.summary = "Prometheus metrics (text format 0.0.4)",
                             .tag = "status",
                             .responses = {{.status = 200,
                                            .description = "every series of the registry",
                                            .media = {"text/plain"}}}},
                            [&ctx](RouteCall&) {
                                protocol::ApiResponse r;
                                r.content_type = "text/plain; version=0.0.4; charset=utf-8";
                                r.body = prometheus_text(metrics_snapshot(ctx));
                                return r;
                            }});
}

/// GET /v1/openapi.json: the description of every route of `routes`, generated at the first
/// request (every route is registered by then) and kept.
void add_description_route(RouteTable& routes) {
    struct Cached {
        std::once_flag once;
        std::string text;
    };
    auto cached = std::make_shared<Cached>();
    routes.get("/v1/openapi.json",
               {{.summary = "This API's OpenAPI 3.1 description",
                 .tag = "status",
                 .responses = {{.status = 200,
                                .description = "the description, generated from the route "
                                               "table",
                                .media = {"application/json"}}}},
                [&routes, cached](RouteCall&) {
                    std::call_once(cached->once, [&] {
                        cached->text =
                            protocol::openapi_document(routes.listing(), VERSION).dump() + "\n";
                    });
                    protocol::ApiResponse r;
                    r.content_type = "application/json";
                    r.body = cached->text;
                    return r;
                }});
}

/// /livez and /readyz, which the front end answers before the table (request_reader.cpp).
void describe_health_routes(RouteTable& routes) {
    const char* never =
        "Answered by the front end without a worker, on connections beyond the "
        "connection limits too; no token needed.";
    routes.describe("GET", "/livez",
                    {.summary = "Liveness: 200 while the process serves HTTP",
                     .description = never,
                     .tag = "status",
                     .responses = {ok_json("Health", "{\"status\": \"ok\"}", {})},
                     .open = true});
    routes.describe(
        "GET", "/readyz",
        {.summary = "Readiness: 200 once the scene is loaded and its structures built",
         .description = never,
         .tag = "status",
         .responses = {ok_json("Health", "ready (with --log, the replica's numbers)", {}),
                       problem(503,
                               "starting (the detail says how far recovery got), shutting "
                               "down, or a replica that has not caught up or stopped",
                               {"Retry-After"})},
         .open = true});
}

}  // namespace

void add_api_routes(RouteTable& routes, ServerContext& ctx) {
    add_write_routes(routes, ctx);
    add_import_routes(routes, ctx);
    add_asset_read_routes(routes, ctx);
    add_asset_write_routes(routes, ctx);
    add_snapshot_routes(routes, ctx);
    add_render_routes(routes, ctx);
    add_pick_routes(routes, ctx);
    add_scene_routes(routes, ctx);
    add_graph_routes(routes, ctx);
    add_status_routes(routes, ctx);
    add_description_route(routes);
    describe_health_routes(routes);
}

}  // namespace strata::server
