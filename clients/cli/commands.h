#pragma once
// The one-shot subcommands of `strata`: edit, undo, redo, history, render, commit, plan, stats
// and scene. Each sends
// one request, prints the answer for people (or as JSON with --json) and returns the exit code:
// 0 done, 2 bad input, 3 Strata refused the request or could not be reached.

#include <cstdint>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "clients/cli/json.h"
#include "clients/cli/transport.h"

namespace strata::cli {

/// Exit codes: done, bad input, Strata refused the request or could not be reached.
inline constexpr int OK = 0;
inline constexpr int BAD_INPUT = 2;
inline constexpr int REFUSED = 3;

/// Where output goes.
struct Console {
    std::ostream& out;
    std::ostream& err;
    bool json = false;  ///< print answers as JSON, for scripts
};

/// Prints why a request failed; returns the exit code for it.
int refused(const Console& c, const Transport& t, const char* what, const Reply& reply);

/// The JSON of a 2xx answer, or nullopt having printed why not (and set `code` to the exit code).
std::optional<Json> json_answer(const Console& c, const Transport& t, const std::string& what,
                                const Reply& reply, int& code);

/// `strata edit FILE|-`: the file holds {"edits": [...]} or just the array.
int run_edit(Transport& t, const Console& c, const std::string& file,
             const std::optional<std::string>& if_match);

/// A camera for one render or pick only; members left empty come from the scene camera.
struct CameraOverride {
    std::vector<double> eye, target, up;  ///< 3 numbers each, or empty
    std::optional<double> fov_y_deg;
};
/// The request's "camera" member for `camera`; an empty object when nothing is overridden.
Json camera_json(const CameraOverride& camera);

/// Everything `strata render` can ask for; unset members are left to the server's defaults.
struct RenderArgs {
    std::string out;  ///< where to save the image; its extension picks the format
    std::optional<uint32_t> width, height, spp;
    std::optional<std::string> format, compression;
    std::vector<std::string> aovs;
    std::optional<double> exposure;
    bool accumulate = false;
    std::optional<std::string> filter;  ///< "atrous" or "none"
    std::optional<uint32_t> split;      ///< bands over this server and its peers
    CameraOverride camera;
    std::optional<std::string> frame_group, frame_instance;  ///< aim at one of them (`frame`)
    std::optional<double> time;  ///< the scene time the animated instances show (`time`)
};
/// The POST /v1/render body for `args` (format from the file name unless given); nullopt and a
/// message when the arguments contradict each other.
std::optional<std::string> render_body(const RenderArgs& args, std::string& error);
/// `strata render -o FILE ...`.
int run_render(Transport& t, const Console& c, const RenderArgs& args);

/// `strata scenes` (scenes_commands.cpp): every scene on the server, one line each (one JSON
/// object each with --json).
int run_scenes(Transport& t, const Console& c);
/// `strata scenes create NAME`: PUT /v1/scenes/NAME, with the budget limits given.
struct SceneCreateArgs {
    std::string name;
    std::optional<uint64_t> max_triangles, max_vertices, max_instances, max_texture_mb;
};
int run_scene_create(Transport& t, const Console& c, const SceneCreateArgs& args);
/// `strata scenes delete NAME`: DELETE /v1/scenes/NAME.
int run_scene_delete(Transport& t, const Console& c, const std::string& name);

/// `strata undo` and `strata redo` (history_commands.cpp).
int run_undo(Transport& t, const Console& c, bool redo, const std::optional<std::string>& if_match);

struct HistoryArgs {
    uint32_t page_size = 100;           ///< versions per request
    std::optional<uint64_t> max_items;  ///< stop after this many
};
/// `strata history`: the versions the server holds, newest first, one line each (one JSON
/// document per line with --json), following cursors.
int run_history(Transport& t, const Console& c, const HistoryArgs& args);

/// `strata commit` and `strata plan`.
int run_commit(Transport& t, const Console& c);
int run_plan(Transport& t, const Console& c);
/// `strata stats`.
int run_stats(Transport& t, const Console& c);
/// `strata scene`: a summary of GET /v1/scene and GET /v1/stats, one line per fact (the whole
/// GET /v1/scene document with --json).
int run_scene(Transport& t, const Console& c);

/// The collections `strata scene list` can walk: meshes, instances, materials, groups.
const std::vector<std::string>& scene_collections();

struct SceneListArgs {
    std::string collection;
    uint32_t page_size = 1000;               ///< items per request
    std::optional<uint64_t> max_items;       ///< stop after this many
    std::optional<std::string> mesh;         ///< instances of this mesh only
    std::optional<bool> visible;             ///< only visible (true) or hidden (false) instances
    std::optional<std::string> parent;       ///< children of this group only ("" the root)
};
/// `strata scene list COLLECTION`: every page, following cursors; one line per object (one JSON
/// document per line with --json).
int run_scene_list(Transport& t, const Console& c, const SceneListArgs& args);
/// `strata scene get KIND ID`: KIND is mesh, instance, material or group.
int run_scene_get(Transport& t, const Console& c, const std::string& kind, const std::string& id);

struct SceneTreeArgs {
    uint32_t depth = 8;
    uint32_t max_nodes = 1000;
    std::optional<std::string> group;  ///< the subtree of this group; the whole scene when unset
};
/// `strata scene tree`: the scene graph as an indented outline (the document with --json).
int run_scene_tree(Transport& t, const Console& c, const SceneTreeArgs& args);

struct PickArgs {
    uint32_t x = 0, y = 0;
    uint32_t width = 0, height = 0;
    CameraOverride camera;
    std::optional<double> time;  ///< as a render's
};
/// `strata pick X Y --width W --height H`: what lies under that pixel of a W x H frame, seen from
/// the scene camera or from `camera`.
int run_pick(Transport& t, const Console& c, const PickArgs& args);
/// `strata snapshot save FILE`: the server's scene into a snapshot file (- for stdout); the file
/// is written whole or not at all (a temporary file renamed).
/// `at_version`, or `at_time` (RFC 3339): the scene as it was then.
int run_snapshot_save(Transport& t, const Console& c, const std::string& file,
                      std::optional<uint64_t> at_version = std::nullopt,
                      const std::optional<std::string>& at_time = std::nullopt);
/// What `strata import` sends.
struct ImportArgs {
    std::string file;
    std::string prefix;  ///< "": the server's default (the file name's stem)
    std::string format;  ///< "": from the file name's extension
    std::string parent;  ///< "": the asset's group goes to the root
    bool instance = true;
};
/// `strata import FILE [--prefix P] [--parent G] [--format F] [--no-instance]`: POST /v1/assets with the
/// file's bytes; prints the ids created and the new version, and the server's warnings on stderr.
int run_import(Transport& t, const Console& c, const ImportArgs& args);
/// The bytes and query of an upload of `args.file` (packed with its side files unless
/// `args.format` is given); BAD_INPUT having said why when a file cannot be read.
int pack_upload(const Console& c, const ImportArgs& args, std::string& bytes,
                std::multimap<std::string, std::string>& query);

/// Prints an import answer's warnings on stderr, one line each.
void print_warnings(const Console& c, const Json& answer);

/// `strata assets` (asset_commands.cpp): every asset, one line each (one JSON object each with
/// --json): id, file, counts and bounds.
int run_assets(Transport& t, const Console& c);
/// `strata assets show ID`: GET /v1/assets/ID, with the ids of everything it owns.
int run_asset_show(Transport& t, const Console& c, const std::string& id);
/// `strata assets delete ID`: DELETE /v1/assets/ID.
int run_asset_delete(Transport& t, const Console& c, const std::string& id);
/// `strata assets reimport ID FILE [--parent G] [--format F] [--no-instance]`: PUT
/// /v1/assets/ID with the file (args.prefix unused); prints what was kept and removed.
int run_asset_reimport(Transport& t, const Console& c, const std::string& id,
                       const ImportArgs& args);

/// `strata snapshot load FILE`: replaces the server's scene with the file's (- for stdin).
int run_snapshot_load(Transport& t, const Console& c, const std::string& file);

/// A rebuild report for people: a summary line, then one line per rebuilt, refit or released
/// mesh.
std::string format_report(const Json& report);
/// format_report's summary line alone: version, TLAS action, rebuilds, refits, primitives, ms.
std::string report_summary(const Json& report);

}  // namespace strata::cli
