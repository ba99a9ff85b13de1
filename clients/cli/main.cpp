// strata: the command-line client. `strata --help` and clients/cli/README.md list the commands.
//
// Exit codes: 0 success; 1 a script expectation failed; 2 bad usage, script or input file;
// 3 Strata refused a request or could not be reached.

#include <unistd.h>

#include <functional>
#include <iostream>
#include <memory>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "clients/cli/commands.h"
#include "clients/cli/embedded_transport.h"
#include "clients/cli/http_transport.h"
#include "clients/cli/play_output.h"
#include "clients/cli/script_runner.h"
#include "strata/version.h"

namespace {

using namespace strata::cli;

constexpr int USAGE = 2;
constexpr int UNREACHABLE = 3;

struct PlayArgs {
    std::string script;
    bool embedded = false;
    bool demo = false;
    bool budgets = false;
    bool quiet = false;
    bool no_progress = false;
    uint64_t max_repeat = 0;
    std::string out_dir;
};

int play_script(const PlayArgs& a, const HttpOptions& http, bool json) {
    auto script = load_script_file(a.script);
    if (!script) {
        std::cerr << "strata: " << a.script << ": " << script.error().describe() << '\n';
        return USAGE;
    }
    std::unique_ptr<Transport> transport;
    if (a.embedded) {
        auto t = EmbeddedTransport::create(a.demo);
        if (!t) {
            std::cerr << "strata: " << t.error().message << '\n';
            return UNREACHABLE;
        }
        transport = std::move(t.value());
    } else {
        auto t = HttpTransport::create(http);
        if (!t) {
            std::cerr << "strata: " << t.error().message << '\n';
            return USAGE;
        }
        transport = std::move(t.value());
    }
    PlayOptions options;
    options.budgets = a.budgets;
    if (a.max_repeat) options.max_repeat = a.max_repeat;
    options.out_dir = a.out_dir;
    std::unique_ptr<PlayObserver> observer;
    if (json) {
        observer = std::make_unique<JsonObserver>(std::cout);
    } else {
        TableOptions table;
        table.rows = !a.quiet;
        table.progress = !a.no_progress && isatty(STDERR_FILENO);
        observer =
            std::make_unique<TableObserver>(std::cout, std::cerr, transport->describe(), table);
    }
    return exit_code(play(script.value(), *transport, options, *observer).verdict);
}

/// What a one-shot subcommand runs against the server once the command line is parsed.
using Action = std::function<int(Transport&, const Console&)>;
/// The one-shot subcommands and their actions; a subcommand comes before its parent, so that the
/// first parsed one is the one the user named.
using Actions = std::vector<std::pair<CLI::App*, Action>>;

/// A "x,y,z" option as three numbers.
CLI::Option* add_vec3(CLI::App* app, const char* name, std::vector<double>& v, const char* help) {
    return app->add_option(name, v, help)->delimiter(',')->expected(3);
}

/// --eye, --target, --up and --fov: a camera for this one request.
/// --time: the scene time a launch shows its animated instances at (the scene keeps its own).
void add_time_option(CLI::App* app, std::optional<double>& time) {
    app->add_option("--time", time,
                    "Show animated instances at this scene time, in seconds (this launch only)");
}

void add_camera_options(CLI::App* app, CameraOverride& camera) {
    add_vec3(app, "--eye", camera.eye, "Camera override: eye position x,y,z");
    add_vec3(app, "--target", camera.target, "Camera override: target x,y,z");
    add_vec3(app, "--up", camera.up, "Camera override: up vector x,y,z");
    app->add_option("--fov", camera.fov_y_deg, "Camera override: vertical field of view");
}

void add_global_options(CLI::App& app, HttpOptions& http, bool& json) {
    app.add_option("--server", http.url, "Server URL, scheme://host[:port]")
        ->envname("STRATA_SERVER")
        ->capture_default_str();
    app.add_option("--token", http.token, "Bearer token for a server started with --token-file")
        ->envname("STRATA_TOKEN");
    app.add_option("--scene", http.scene,
                   "Work on this named scene (/v1/scenes/NAME/...) instead of the default one")
        ->envname("STRATA_SCENE");
    app.add_option("--timeout", http.timeout_s, "Seconds to wait for the server")
        ->check(CLI::Range(1, 86400))
        ->capture_default_str();
    app.add_flag("--json", json, "Print answers as JSON (one object per line for play)");
    app.set_version_flag("--version", std::string("strata ") + strata::VERSION,
                         "Print the version and exit");
}

CLI::App* add_play(CLI::App& app, PlayArgs& play) {
    CLI::App* cmd = app.add_subcommand(
        "play", "Play a script (JSON Lines, protocol/scripts.md) and check its expectations");
    cmd->add_option("script", play.script, "Script file, or - for standard input")->required();
    cmd->add_flag("--embedded", play.embedded,
                  "Play against an in-process engine instead of a server");
    cmd->add_flag("--demo", play.demo, "With --embedded: start from the demo scene");
    cmd->add_flag("--budgets", play.budgets,
                  "Also check the time budget max_ms (max_primitives_built is always checked)");
    cmd->add_option("--max-repeat", play.max_repeat,
                    "Play at most N iterations of each repeat step (quick checks)")
        ->check(CLI::PositiveNumber);
    cmd->add_option("--out-dir", play.out_dir,
                    "Directory for the frames of relative \"out\" paths (default: .)");
    cmd->add_flag("-q,--quiet", play.quiet, "No per-step table, only the verdict");
    cmd->add_flag("--no-progress", play.no_progress, "No progress bar");
    return cmd;
}

void add_edit(CLI::App& app, Actions& actions) {
    struct Args {
        std::string file, if_match;
    };
    auto a = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("edit", "Apply a batch of edits from a file");
    cmd->add_option("file", a->file, "JSON file: {\"edits\": [...]} or [...]; - for stdin")
        ->required();
    cmd->add_option("--if-match", a->if_match, "Apply only at this scene version");
    actions.emplace_back(cmd, [a](Transport& t, const Console& c) {
        return run_edit(t, c, a->file,
                        a->if_match.empty() ? std::nullopt : std::optional(a->if_match));
    });
}

void add_history(CLI::App& app, Actions& actions) {
    for (const bool redo : {false, true}) {
        auto if_match = std::make_shared<std::string>();
        CLI::App* cmd = app.add_subcommand(
            redo ? "redo" : "undo",
            redo ? "Apply again the batch the newest undo took back" : "Take back the newest batch");
        cmd->add_option("--if-match", *if_match, "Only at this scene version");
        actions.emplace_back(cmd, [if_match, redo](Transport& t, const Console& c) {
            return run_undo(t, c, redo,
                            if_match->empty() ? std::nullopt : std::optional(*if_match));
        });
    }
    auto a = std::make_shared<HistoryArgs>();
    CLI::App* cmd = app.add_subcommand("history", "List the scene's versions, newest first");
    cmd->add_option("--page-size", a->page_size, "Versions per request (1 to 1000)")
        ->check(CLI::Range(1, 1000));
    cmd->add_option("--max", a->max_items, "Stop after this many versions");
    actions.emplace_back(cmd, [a](Transport& t, const Console& c) { return run_history(t, c, *a); });
}

void add_scenes(CLI::App& app, Actions& actions) {
    CLI::App* scenes = app.add_subcommand(
        "scenes", "List the server's scenes; create or delete named scenes");
    auto create = std::make_shared<SceneCreateArgs>();
    CLI::App* create_cmd =
        scenes->add_subcommand("create", "Create a named scene (or find the one that exists)");
    create_cmd->add_option("name", create->name, "The scene's name")->required();
    create_cmd->add_option("--max-triangles", create->max_triangles, "Its triangle budget");
    create_cmd->add_option("--max-vertices", create->max_vertices, "Its vertex budget");
    create_cmd->add_option("--max-instances", create->max_instances, "Its instance budget");
    create_cmd->add_option("--max-texture-mb", create->max_texture_mb, "Its texture budget, MiB");
    actions.emplace_back(create_cmd, [create](Transport& t, const Console& c) {
        return run_scene_create(t, c, *create);
    });
    auto name = std::make_shared<std::string>();
    CLI::App* delete_cmd =
        scenes->add_subcommand("delete", "Delete a named scene with its history and files");
    delete_cmd->add_option("name", *name, "The scene's name")->required();
    actions.emplace_back(delete_cmd, [name](Transport& t, const Console& c) {
        return run_scene_delete(t, c, *name);
    });
    actions.emplace_back(scenes, run_scenes);
}

void add_render(CLI::App& app, Actions& actions) {
    auto a = std::make_shared<RenderArgs>();
    CLI::App* cmd = app.add_subcommand("render", "Render a frame and save it");
    cmd->add_option("-o,--out", a->out, "Output file (.png, .exr or .npz)")->required();
    cmd->add_option("--width", a->width, "Width in pixels");
    cmd->add_option("--height", a->height, "Height in pixels");
    cmd->add_option("--spp", a->spp, "Samples per pixel");
    cmd->add_option("--format", a->format, "png, exr or npz (default: from --out)")
        ->check(CLI::IsMember({"png", "exr", "npz"}));
    cmd->add_option("--aovs", a->aovs,
                    "EXR layers or NPZ arrays, comma-separated (depth,normal,...)")
        ->delimiter(',');
    cmd->add_option("--compression", a->compression, "EXR compression: none, zip, piz");
    cmd->add_option("--exposure", a->exposure, "Exposure in EV stops");
    cmd->add_flag("--accumulate", a->accumulate,
                  "Accumulate samples while the scene does not change");
    cmd->add_option("--filter", a->filter, "Denoise: atrous or none (default: none)")
        ->check(CLI::IsMember({"atrous", "none"}));
    cmd->add_option("--split", a->split,
                    "Render in N horizontal bands on this server and its --peers (1 to 16)")
        ->check(CLI::Range(1, 16));
    add_camera_options(cmd, a->camera);
    add_time_option(cmd, a->time);
    cmd->add_option("--frame-group", a->frame_group,
                    "Aim the camera at this group's instances (from the scene camera's direction)");
    cmd->add_option("--frame-instance", a->frame_instance, "Aim the camera at this instance");
    actions.emplace_back(cmd, [a](Transport& t, const Console& c) { return run_render(t, c, *a); });
}

/// commit, plan and stats: no arguments of their own.
void add_reports(CLI::App& app, Actions& actions) {
    actions.emplace_back(app.add_subcommand("commit", "Run a commit and print its report"),
                         run_commit);
    actions.emplace_back(app.add_subcommand("plan", "Print what the next commit would do"),
                         run_plan);
    actions.emplace_back(app.add_subcommand("stats", "Print counters and the last report"),
                         run_stats);
}

void add_scene_list(CLI::App* scene, Actions& actions) {
    auto a = std::make_shared<SceneListArgs>();
    CLI::App* cmd = scene->add_subcommand(
        "list", "List meshes, instances, materials, groups, lights or textures, one per line");
    cmd->add_option("collection", a->collection,
                    "meshes, instances, materials, groups, lights or textures")
        ->required()
        ->check(CLI::IsMember(scene_collections()));
    cmd->add_option("--page-size", a->page_size, "Objects per request (1 to 10000)")
        ->check(CLI::Range(1, 10000));
    cmd->add_option("--max", a->max_items, "Stop after this many objects");
    cmd->add_option("--mesh", a->mesh, "Instances: only those of this mesh");
    cmd->add_option("--visible", a->visible, "Instances: only visible (true) or hidden");
    cmd->add_option("--parent", a->parent,
                    "Instances, groups: only children of this group (\"\" for the root)");
    actions.emplace_back(cmd,
                         [a](Transport& t, const Console& c) { return run_scene_list(t, c, *a); });
}

/// scene, with list, get and tree under it.
void add_scene(CLI::App& app, Actions& actions) {
    CLI::App* scene =
        app.add_subcommand("scene", "Print the scene summary (the whole document with --json)");
    scene->require_subcommand(0, 1);
    add_scene_list(scene, actions);
    auto get = std::make_shared<std::pair<std::string, std::string>>();
    CLI::App* get_cmd = scene->add_subcommand("get", "Print one object's document");
    get_cmd->add_option("kind", get->first, "mesh, instance, material, group, light or texture")
        ->required()
        ->check(CLI::IsMember({"mesh", "instance", "material", "group", "light", "texture"}));
    get_cmd->add_option("id", get->second, "The object's id")->required();
    actions.emplace_back(get_cmd, [get](Transport& t, const Console& c) {
        return run_scene_get(t, c, get->first, get->second);
    });
    auto tree = std::make_shared<SceneTreeArgs>();
    CLI::App* tree_cmd = scene->add_subcommand("tree", "Print the scene graph as an outline");
    tree_cmd->add_option("--depth", tree->depth, "Group levels to expand (0 to 64)")
        ->check(CLI::Range(0, 64));
    tree_cmd->add_option("--max-nodes", tree->max_nodes, "Most nodes to print (1 to 10000)")
        ->check(CLI::Range(1, 10000));
    tree_cmd->add_option("--group", tree->group, "Only the subtree of this group");
    actions.emplace_back(
        tree_cmd, [tree](Transport& t, const Console& c) { return run_scene_tree(t, c, *tree); });
    actions.emplace_back(scene, run_scene);
}

void add_pick(CLI::App& app, Actions& actions) {
    auto a = std::make_shared<PickArgs>();
    CLI::App* cmd = app.add_subcommand("pick", "Print what lies under one pixel");
    cmd->add_option("x", a->x, "Column, 0 at the left")->required();
    cmd->add_option("y", a->y, "Row, 0 at the top")->required();
    cmd->add_option("--width", a->width, "Width of the frame the pixel belongs to")->required();
    cmd->add_option("--height", a->height, "Height of that frame")->required();
    add_camera_options(cmd, a->camera);
    add_time_option(cmd, a->time);
    actions.emplace_back(cmd, [a](Transport& t, const Console& c) { return run_pick(t, c, *a); });
}

void add_snapshot(CLI::App& app, Actions& actions) {
    auto file = std::make_shared<std::string>();
    auto version = std::make_shared<std::optional<uint64_t>>();
    CLI::App* cmd =
        app.add_subcommand("snapshot", "Save the server's scene to a file, or load one into it");
    cmd->require_subcommand(1);
    CLI::App* save = cmd->add_subcommand(
        "save", "Save the whole scene (GET /v1/scene/snapshot) to FILE (- for stdout)");
    save->add_option("file", *file, "Snapshot file to write")->required();
    auto time = std::make_shared<std::optional<std::string>>();
    auto version_option = save->add_option("--version,--at-version", *version,
                                           "The scene as it was at this version (the server's "
                                           "data directory must still hold it)");
    save->add_option("--at-time", *time,
                     "The scene as it was at this time (RFC 3339, e.g. 2026-11-28T04:00:00Z): "
                     "the newest version made by then")
        ->excludes(version_option);
    CLI::App* load = cmd->add_subcommand(
        "load", "Replace the server's scene with FILE's (POST /v1/scene/snapshot; - for stdin)");
    load->add_option("file", *file, "Snapshot file to read")->required();
    actions.emplace_back(
        save, [file, version, time](Transport& t, const Console& c) {
            return run_snapshot_save(t, c, *file, *version, *time);
        });
    actions.emplace_back(
        load, [file](Transport& t, const Console& c) { return run_snapshot_load(t, c, *file); });
}

void add_import(CLI::App& app, Actions& actions) {
    auto a = std::make_shared<ImportArgs>();
    CLI::App* cmd =
        app.add_subcommand("import", "Import a model file: glTF, OBJ, PLY, FBX, COLLADA, STL, ... "
                                     "(POST /v1/assets)");
    cmd->add_option("file", a->file, "Model file (.glb, .gltf, .obj, .ply, .fbx, .dae, .stl, ...)")
        ->required();
    cmd->add_option("--prefix", a->prefix,
                    "Id prefix of what it creates (default: the file name's stem)");
    cmd->add_option("--parent", a->parent,
                    "Group to put the asset's group under (default: the root)");
    cmd->add_option("--format", a->format,
                    "glb, gltf, obj, ply, fbx, dae, stl, ... (default: from the extension)");
    auto no_instance = std::make_shared<bool>(false);
    cmd->add_flag("--no-instance", *no_instance, "Create meshes and materials only");
    actions.emplace_back(cmd, [a, no_instance](Transport& t, const Console& c) {
        a->instance = !*no_instance;
        return run_import(t, c, *a);
    });
}

void add_assets(CLI::App& app, Actions& actions) {
    CLI::App* assets = app.add_subcommand(
        "assets", "List imported assets; show, delete or re-import one (/v1/assets)");
    auto id = std::make_shared<std::string>();
    CLI::App* show = assets->add_subcommand("show", "One asset with the ids of what it owns");
    show->add_option("id", *id, "The asset's id (its group's)")->required();
    actions.emplace_back(
        show, [id](Transport& t, const Console& c) { return run_asset_show(t, c, *id); });
    CLI::App* remove =
        assets->add_subcommand("delete", "Remove everything an asset owns, in one batch");
    remove->add_option("id", *id, "The asset's id")->required();
    actions.emplace_back(
        remove, [id](Transport& t, const Console& c) { return run_asset_delete(t, c, *id); });
    auto a = std::make_shared<ImportArgs>();
    CLI::App* reimport = assets->add_subcommand(
        "reimport", "Import FILE in place of an asset: same ids, what did not change kept");
    reimport->add_option("id", *id, "The asset's id")->required();
    reimport->add_option("file", a->file, "Model file (.glb, .gltf, .obj, .ply, .fbx, ...)")
        ->required();
    reimport->add_option("--parent", a->parent,
                         "Group to put the asset's group under (default: where it was)");
    reimport->add_option("--format", a->format,
                         "glb, gltf, obj, ply, fbx, dae, stl, ... (default: from the extension)");
    auto no_instance = std::make_shared<bool>(false);
    reimport->add_flag("--no-instance", *no_instance, "Create meshes and materials only");
    actions.emplace_back(reimport, [id, a, no_instance](Transport& t, const Console& c) {
        a->instance = !*no_instance;
        return run_asset_reimport(t, c, *id, *a);
    });
    actions.emplace_back(assets, run_assets);
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "strata: play scripts against Strata and talk to a strata-server "
        "(see clients/cli/README.md)"};
    app.require_subcommand(1);
    app.fallthrough();
    HttpOptions http;
    bool json = false;
    add_global_options(app, http, json);
    PlayArgs play;
    CLI::App* play_cmd = add_play(app, play);
    Actions actions;
    add_edit(app, actions);
    add_history(app, actions);
    add_scenes(app, actions);
    add_assets(app, actions);
    add_render(app, actions);
    add_reports(app, actions);
    add_scene(app, actions);
    add_pick(app, actions);
    add_snapshot(app, actions);
    add_import(app, actions);

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --version exit 0; every usage error exits 2, whatever CLI11 numbers it.
        return app.exit(e) == 0 ? 0 : USAGE;
    }
    if (play.embedded && !http.scene.empty()) {
        std::cerr << "strata: --scene needs a server; the embedded engine holds one scene\n";
        return USAGE;
    }
    if (!play.embedded && play.demo) {
        std::cerr << "strata: --demo only applies with --embedded\n";
        return USAGE;
    }
    if (play_cmd->parsed()) return play_script(play, http, json);

    auto transport = HttpTransport::create(http);
    if (!transport) {
        std::cerr << "strata: " << transport.error().message << '\n';
        return USAGE;
    }
    const Console console{std::cout, std::cerr, json};
    for (const auto& [cmd, action] : actions)
        if (cmd->parsed()) return action(*transport.value(), console);
    return USAGE;
}
