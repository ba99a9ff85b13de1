// strata: the command-line client. `strata --help` and clients/cli/README.md list the commands.
//
// Exit codes: 0 success; 1 a script expectation failed; 2 bad usage, script or input file;
// 3 Strata refused a request or could not be reached.

#include <unistd.h>

#include <iostream>
#include <memory>

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

/// A "x,y,z" option as three numbers.
CLI::Option* add_vec3(CLI::App* app, const char* name, std::vector<double>& v, const char* help) {
    return app->add_option(name, v, help)->delimiter(',')->expected(3);
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
    app.add_option("--server", http.url, "Server URL, scheme://host[:port]")
        ->envname("STRATA_SERVER")
        ->capture_default_str();
    app.add_option("--token", http.token, "Bearer token for a server started with --token-file")
        ->envname("STRATA_TOKEN");
    app.add_option("--timeout", http.timeout_s, "Seconds to wait for the server")
        ->check(CLI::Range(1, 86400))
        ->capture_default_str();
    app.add_flag("--json", json, "Print answers as JSON (one object per line for play)");
    app.set_version_flag("--version", std::string("strata ") + strata::VERSION,
                         "Print the version and exit");

    PlayArgs play;
    CLI::App* play_cmd = app.add_subcommand(
        "play", "Play a script (JSON Lines, protocol/scripts.md) and check its expectations");
    play_cmd->add_option("script", play.script, "Script file, or - for standard input")->required();
    play_cmd->add_flag("--embedded", play.embedded,
                       "Play against an in-process engine instead of a server");
    play_cmd->add_flag("--demo", play.demo, "With --embedded: start from the demo scene");
    play_cmd->add_flag(
        "--budgets", play.budgets,
        "Also check the time budget max_ms (max_primitives_built is always checked)");
    play_cmd
        ->add_option("--max-repeat", play.max_repeat,
                     "Play at most N iterations of each repeat step (quick checks)")
        ->check(CLI::PositiveNumber);
    play_cmd->add_option("--out-dir", play.out_dir,
                         "Directory for the frames of relative \"out\" paths (default: .)");
    play_cmd->add_flag("-q,--quiet", play.quiet, "No per-step table, only the verdict");
    play_cmd->add_flag("--no-progress", play.no_progress, "No progress bar");

    std::string edit_file;
    std::string if_match;
    CLI::App* edit_cmd = app.add_subcommand("edit", "Apply a batch of edits from a file");
    edit_cmd->add_option("file", edit_file, "JSON file: {\"edits\": [...]} or [...]; - for stdin")
        ->required();
    edit_cmd->add_option("--if-match", if_match, "Apply only at this scene version");

    RenderArgs render;
    CLI::App* render_cmd = app.add_subcommand("render", "Render a frame and save it");
    render_cmd->add_option("-o,--out", render.out, "Output file (.png or .exr)")->required();
    render_cmd->add_option("--width", render.width, "Width in pixels");
    render_cmd->add_option("--height", render.height, "Height in pixels");
    render_cmd->add_option("--spp", render.spp, "Samples per pixel");
    render_cmd->add_option("--format", render.format, "png or exr (default: from --out)")
        ->check(CLI::IsMember({"png", "exr"}));
    render_cmd->add_option("--aovs", render.aovs, "EXR layers, comma-separated (depth,normal,...)")
        ->delimiter(',');
    render_cmd->add_option("--compression", render.compression, "EXR compression: none, zip, piz");
    render_cmd->add_option("--exposure", render.exposure, "Exposure in EV stops");
    render_cmd->add_flag("--accumulate", render.accumulate,
                         "Accumulate samples while the scene does not change");
    add_vec3(render_cmd, "--eye", render.eye, "Camera override: eye position x,y,z");
    add_vec3(render_cmd, "--target", render.target, "Camera override: target x,y,z");
    add_vec3(render_cmd, "--up", render.up, "Camera override: up vector x,y,z");
    render_cmd->add_option("--fov", render.fov_y_deg, "Camera override: vertical field of view");

    CLI::App* commit_cmd = app.add_subcommand("commit", "Run a commit and print its report");
    CLI::App* plan_cmd = app.add_subcommand("plan", "Print what the next commit would do");
    CLI::App* stats_cmd = app.add_subcommand("stats", "Print counters and the last report");
    CLI::App* scene_cmd = app.add_subcommand("scene", "Print the scene summary");
    scene_cmd->require_subcommand(0, 1);
    SceneListArgs list;
    CLI::App* list_cmd = scene_cmd->add_subcommand(
        "list", "List meshes, instances, materials, groups, lights or textures, one per line");
    list_cmd
        ->add_option("collection", list.collection,
                     "meshes, instances, materials, groups, lights or textures")
        ->required()
        ->check(CLI::IsMember(scene_collections()));
    list_cmd->add_option("--page-size", list.page_size, "Objects per request (1 to 10000)")
        ->check(CLI::Range(1, 10000));
    list_cmd->add_option("--max", list.max_items, "Stop after this many objects");
    list_cmd->add_option("--mesh", list.mesh, "Instances: only those of this mesh");
    list_cmd->add_option("--visible", list.visible, "Instances: only visible (true) or hidden");
    list_cmd->add_option("--parent", list.parent,
                         "Instances, groups: only children of this group (\"\" for the root)");
    std::string get_kind, get_id;
    CLI::App* get_cmd = scene_cmd->add_subcommand("get", "Print one object's document");
    get_cmd->add_option("kind", get_kind, "mesh, instance, material, group, light or texture")
        ->required()
        ->check(CLI::IsMember({"mesh", "instance", "material", "group", "light", "texture"}));
    get_cmd->add_option("id", get_id, "The object's id")->required();
    SceneTreeArgs tree;
    CLI::App* tree_cmd = scene_cmd->add_subcommand("tree", "Print the scene graph as an outline");
    tree_cmd->add_option("--depth", tree.depth, "Group levels to expand (0 to 64)")
        ->check(CLI::Range(0, 64));
    tree_cmd->add_option("--max-nodes", tree.max_nodes, "Most nodes to print (1 to 10000)")
        ->check(CLI::Range(1, 10000));
    tree_cmd->add_option("--group", tree.group, "Only the subtree of this group");
    PickArgs pick;
    CLI::App* pick_cmd = app.add_subcommand("pick", "Print what lies under one pixel");
    pick_cmd->add_option("x", pick.x, "Column, 0 at the left")->required();
    pick_cmd->add_option("y", pick.y, "Row, 0 at the top")->required();
    pick_cmd->add_option("--width", pick.width, "Width of the frame the pixel belongs to")
        ->required();
    pick_cmd->add_option("--height", pick.height, "Height of that frame")->required();

    std::string snapshot_file;
    CLI::App* snapshot_cmd =
        app.add_subcommand("snapshot", "Save the server's scene to a file, or load one into it");
    snapshot_cmd->require_subcommand(1);
    CLI::App* snapshot_save = snapshot_cmd->add_subcommand(
        "save", "Save the whole scene (GET /v1/scene/snapshot) to FILE (- for stdout)");
    snapshot_save->add_option("file", snapshot_file, "Snapshot file to write")->required();
    CLI::App* snapshot_load = snapshot_cmd->add_subcommand(
        "load", "Replace the server's scene with FILE's (POST /v1/scene/snapshot; - for stdin)");
    snapshot_load->add_option("file", snapshot_file, "Snapshot file to read")->required();

    ImportArgs import_args;
    CLI::App* import_cmd =
        app.add_subcommand("import", "Import a glTF, OBJ or PLY file (POST /v1/assets)");
    import_cmd->add_option("file", import_args.file, "Model file (.glb, .gltf, .obj, .ply)")
        ->required();
    import_cmd->add_option("--prefix", import_args.prefix,
                           "Id prefix of what it creates (default: the file name's stem)");
    import_cmd->add_option("--parent", import_args.parent,
                           "Group to put the asset's group under (default: the root)");
    import_cmd->add_option("--format", import_args.format,
                           "glb, gltf, obj or ply (default: from the extension)");
    bool no_instance = false;
    import_cmd->add_flag("--no-instance", no_instance, "Create meshes and materials only");

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        // --help and --version exit 0; every usage error exits 2, whatever CLI11 numbers it.
        return app.exit(e) == 0 ? 0 : USAGE;
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
    Transport& t = *transport.value();
    const Console console{std::cout, std::cerr, json};
    if (edit_cmd->parsed())
        return run_edit(t, console, edit_file,
                        if_match.empty() ? std::nullopt : std::optional(if_match));
    if (render_cmd->parsed()) return run_render(t, console, render);
    if (commit_cmd->parsed()) return run_commit(t, console);
    if (plan_cmd->parsed()) return run_plan(t, console);
    if (stats_cmd->parsed()) return run_stats(t, console);
    if (list_cmd->parsed()) return run_scene_list(t, console, list);
    if (get_cmd->parsed()) return run_scene_get(t, console, get_kind, get_id);
    if (tree_cmd->parsed()) return run_scene_tree(t, console, tree);
    if (scene_cmd->parsed()) return run_scene(t, console);
    if (pick_cmd->parsed()) return run_pick(t, console, pick);
    if (snapshot_save->parsed()) return run_snapshot_save(t, console, snapshot_file);
    if (snapshot_load->parsed()) return run_snapshot_load(t, console, snapshot_file);
    if (import_cmd->parsed()) {
        import_args.instance = !no_instance;
        return run_import(t, console, import_args);
    }
    return USAGE;
}
