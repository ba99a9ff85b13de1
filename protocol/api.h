#pragma once
// The transport-independent half of every /v1 endpoint: a request's body, query or id in; status,
// body, content type and headers out. strata-server's routes are thin adapters over these
// functions and `strata play --embedded` calls them in-process, so both answer the same reports,
// problem documents and headers, validated the same way. Nothing here includes an HTTP library;
// statuses and header names are plain data.

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/durable/durable_stats.h"
#include "engine/engine.h"
#include "protocol/assets/sandbox.h"
#include "protocol/json_document.h"
#include "protocol/problem.h"

namespace strata::protocol {

/// Limits applied to requests (strata-server's flags; the defaults are the flags' defaults).
struct ApiLimits {
    JsonLimits json;
    uint64_t max_pixels = 16ull << 20;  ///< width * height of one render (--max-pixels)
    int render_timeout_s = 0;  ///< a render running longer stops (--render-timeout); 0: none
    /// The engine's scene budget (--max-scene-*): imports size their reads by the room left.
    SceneBudget budget;
    /// Most edits in one batch, JSON or snapshot (--max-batch-edits).
    std::size_t max_batch_edits = std::size_t(1) << 20;
    /// Where POST and PUT /v1/assets run their importer (--import-timeout, --import-memory-mb).
    assets::SandboxLimits import_sandbox = {};
};

/// One endpoint's answer, ready for any transport.
struct ApiResponse {
    int status = 200;
    std::string content_type;  ///< application/json, application/problem+json, image/png, ...
    std::string body;          ///< JSON text or image bytes
    std::vector<std::pair<std::string, std::string>> headers;  ///< ETag, X-Strata-Rebuild, ...
    /// The commit this request ran (commit and render), for the caller's logs and metrics.
    std::optional<RebuildReport> commit;

    /// The value of header `name` (exact spelling), or "" when absent.
    std::string_view header(std::string_view name) const;
};

/// A JSON answer; like every JSON body Strata sends, it ends with a newline.
ApiResponse json_response(int status, const Json& body);
/// An application/problem+json answer with the problem's status (ends with a newline too).
ApiResponse problem_response(const Problem& problem);

/// For the endpoints whose body is JSON (edits, render, pick): nullopt when `content_type` may
/// carry JSON (absent, application/json, any +json type, and text/plain and
/// application/x-www-form-urlencoded, which curl and browsers send for a bare body); otherwise a
/// 415 unsupported-media-type naming it (multipart/form-data, images, ...).
std::optional<Problem> json_body_type_problem(std::optional<std::string_view> content_type);

/// The entity tag of a scene version: "N" with the quotes.
std::string etag(uint64_t version);
/// `r` with the ETag of `version`.
ApiResponse with_etag(ApiResponse r, uint64_t version);

/// What If-Match asks for: no constraint (absent or "*"), or one version.
struct IfMatch {
    std::optional<uint64_t> version;
};
/// Parses an If-Match value: `"N"`, `*`, or a bare N for curl users. Weak tags (W/"N") never
/// match (RFC 9110 uses strong comparison); a list of several tags is refused.
std::optional<IfMatch> parse_if_match(std::string_view value, Problem& problem);

/// Where the write endpoints send a checked batch with its If-Match version: by default straight
/// into the engine; a server following a shared edit log (server/replica) passes the log's
/// append, which answers once the batch is in the log and applied (Storage errors: 503).
using BatchApply = std::function<Result<ApplyResult>(EditBatch&&, std::optional<uint64_t>)>;

/// POST /v1/edits. `if_match` is the If-Match header when the request has one. The body is
/// consumed (freed once parsed).
ApiResponse post_edits(Engine& engine, std::string body, std::optional<std::string_view> if_match,
                       const ApiLimits& limits, const BatchApply* apply = nullptr);
/// POST /v1/undo (POST /v1/redo when `redo`): applies the inverse of the newest batch on the
/// undo (redo) stack as a new version, journaled and counted like POST /v1/edits (history_api.cpp).
/// With If-Match only at that version; without, a writer landing meanwhile makes it try again on
/// the newer scene. An empty stack is a 409 (nothing-to-undo).
ApiResponse post_undo(Engine& engine, bool redo, std::optional<std::string_view> if_match,
                      const BatchApply* apply = nullptr);
/// The wire name of a history entry's kind: "edit", "undo" or "redo".
const char* batch_kind_name(BatchKind kind);
/// GET /v1/history?limit&cursor: the versions the history holds, newest first, and the stacks.
ApiResponse get_history(const Engine& engine,
                        const std::multimap<std::string, std::string>& query);
/// An RFC 3339 time ("2026-11-27T17:02:03.456Z", an offset instead of Z) as Unix milliseconds;
/// nullopt when it is not one.
std::optional<int64_t> parse_rfc3339(std::string_view text);
/// The version a read with `at_time=text` answers: the newest version the history lists that
/// was made at or before that time. 400 for a malformed time; 404 for a time before the oldest
/// version the history lists (GET /v1/history: the versions since the scene was loaded, up to
/// its bound).
Parsed<uint64_t> version_at_time(const Engine& engine, std::string_view text);
/// POST /v1/commit.
ApiResponse post_commit(Engine& engine);
/// GET /v1/plan.
ApiResponse get_plan(const Engine& engine);
/// A frame rendered in bands by several processes: encoded exactly as one render of the same
/// request, and what became of each band (the X-Strata-Split header).
struct SplitFrame {
    EncodedFrame frame;
    std::string bands;
};
/// Renders `request` (checked, its cancel token carrying the render's deadline) in `split` bands
/// (server/split_render.h); the error names the field at fault.
using SplitRender = std::function<Result<SplitFrame>(const RenderRequest& request,
                                                     uint32_t split)>;

/// POST /v1/render: an empty body means every default. `cancel`, when given, stops the render
/// early (the client left, the server shuts down); the render's deadline is set on it. `split`:
/// how a request with `split` above 1 is rendered; without one such a request is a 422.
ApiResponse post_render(Engine& engine, std::string_view body, const ApiLimits& limits,
                        CancelToken* cancel = nullptr, const SplitRender* split = nullptr);
/// GET /v1/render with its query parameters.
ApiResponse get_render(Engine& engine, const std::multimap<std::string, std::string>& query,
                       const ApiLimits& limits, CancelToken* cancel = nullptr,
                       const SplitRender* split = nullptr);
/// GET /v1/scene.
ApiResponse get_scene(const Engine& engine);

/// The object kinds of GET /v1/scene/{meshes,instances,materials,groups,lights,textures}/{id}.
enum class SceneObject : uint8_t { Mesh, Instance, Material, Group, Light, Texture };
/// GET /v1/scene/{meshes,instances,materials,groups,lights,textures}/{id}.
ApiResponse get_scene_object(const Engine& engine, SceneObject kind, std::string_view id);
/// GET /v1/scene/{meshes,instances,materials,groups,lights}: one page of the collection
/// (scene_list.cpp).
ApiResponse get_scene_list(const Engine& engine, SceneObject kind,
                           const std::multimap<std::string, std::string>& query);
/// GET /v1/scene/groups/{id}/children: one page of a group's child groups, then its instances
/// (scene_tree.cpp).
ApiResponse get_group_children(const Engine& engine, std::string_view id,
                               const std::multimap<std::string, std::string>& query);
/// GET /v1/scene/tree: the scene graph nested `depth` levels, at most `max_nodes` nodes.
ApiResponse get_scene_tree(const Engine& engine,
                           const std::multimap<std::string, std::string>& query);

/// GET /v1/pick: what lies under one pixel (pick_api.cpp).
ApiResponse get_pick(Engine& engine, const std::multimap<std::string, std::string>& query);
/// POST /v1/pick: what lies under each of a list of pixels.
ApiResponse post_pick(Engine& engine, std::string_view body, const ApiLimits& limits);

/// GET /v1/stats; `durable`, when the server has a data directory, adds its "durability" member.
ApiResponse get_stats(const Engine& engine, const durable::DurableStats* durable = nullptr);

/// Longest scene name, in bytes.
inline constexpr std::size_t MAX_SCENE_NAME_BYTES = 64;
/// What a scene name may be, for error messages and the docs.
inline constexpr const char* SCENE_NAME_RULE =
    "1 to 64 characters: lowercase letters, digits, '-' and '_', starting with a letter or digit";
/// True for a name that SCENE_NAME_RULE allows (it is also a safe directory name).
bool valid_scene_name(std::string_view name);
/// PUT /v1/scenes/{scene}'s body: `{"budget": {"max_triangles", "max_vertices",
/// "max_instances", "max_texture_mb"}}`, every member optional. What it leaves out is
/// `ceiling`'s (the server's per-scene flags); a value above the ceiling is a 422 naming the
/// flag. An empty body is the ceiling itself.
Parsed<SceneBudget> parse_scene_settings(std::string_view body, const SceneBudget& ceiling,
                                         const JsonLimits& limits);
/// The members of a scene's budget, as the settings and the summary name them.
std::vector<std::string> scene_budget_members();
/// The settings as parse_scene_settings reads them back (the file a named scene keeps them in).
Json scene_settings_json(const SceneBudget& budget);
/// One scene as GET /v1/scenes lists it: name, version, totals, memory, budget.
Json scene_summary_json(std::string_view name, const Engine& engine, const SceneBudget& budget,
                        bool durable);

/// The content type of snapshot files (GET and POST /v1/scene/snapshot).
inline constexpr const char* SNAPSHOT_CONTENT_TYPE = "application/vnd.strata.snapshot";
/// GET /v1/scene/snapshot: the whole scene as a snapshot file (engine/durable/journal_format.h),
/// taken under one read lock; its ETag is the version it holds.
ApiResponse get_snapshot(const Engine& engine);
/// POST /v1/scene/snapshot: replaces the scene with the snapshot's, atomically, as one batch
/// (a Clear, then the snapshot's edits): a new version, journaled like any batch. The snapshot's
/// own version is not reused. `if_match` as for post_edits.
/// A snapshot of more than `max_edits` edits is 413, refused from its count before any edit is
/// decoded.
ApiResponse post_snapshot(Engine& engine, std::string body,
                          std::optional<std::string_view> if_match,
                          const BatchApply* apply = nullptr,
                          std::size_t max_edits = std::size_t(1) << 20);

/// POST /v1/assets: imports one model file, the body, as ONE batch: atomic, journaled and
/// counted like POST /v1/edits, If-Match honoured (assets_api.cpp). The format comes from
/// `?format=` or `content_type`; the query may also give `name`, `prefix` and `instance`.
ApiResponse post_assets(Engine& engine, std::string body,
                        const std::multimap<std::string, std::string>& query,
                        std::optional<std::string_view> content_type,
                        std::optional<std::string_view> if_match, const ApiLimits& limits,
                        const BatchApply* apply = nullptr);
/// GET /v1/assets: every asset (protocol/asset_index.h) with its file, counts and world bounds.
/// O(objects in the scene).
ApiResponse get_assets(const Engine& engine);
/// GET /v1/assets/{id}: one asset with the ids of everything it owns; 404 when no asset has it.
ApiResponse get_asset(const Engine& engine, std::string_view id);
/// DELETE /v1/assets/{id}: removes everything the asset owns in one batch, read and applied at
/// one version (without If-Match, read again when another writer landed in between). An object
/// outside the asset that still uses a part of it refuses the batch, naming both.
ApiResponse delete_asset(Engine& engine, std::string_view id,
                         std::optional<std::string_view> if_match,
                         const BatchApply* apply = nullptr);
/// PUT /v1/assets/{id}: imports the body as asset `id` in one batch that first removes the old
/// asset: the same ids where the structure is the same, the asset's group where the old one was
/// (transform, visibility, name, parent unless ?parent= is given), and textures, materials and
/// meshes whose content did not change kept as they are (no BLAS work for them). 200 when it
/// replaced an asset, 201 when it made one; the query is POST's without `prefix`.
ApiResponse put_asset(Engine& engine, std::string_view id, std::string body,
                      const std::multimap<std::string, std::string>& query,
                      std::optional<std::string_view> content_type,
                      std::optional<std::string_view> if_match, const ApiLimits& limits,
                      const BatchApply* apply = nullptr);

}  // namespace strata::protocol
