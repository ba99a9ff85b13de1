#include "server/cli.h"

#include <cctype>
#include <cstdlib>
#include <string_view>
#include <thread>

#include <CLI/CLI.hpp>

#include "server/auth.h"
#include "server/cors.h"
#include "server/listener.h"
#include "server/replica/redis_url.h"
#include "server/split_render.h"
#include "strata/version.h"

namespace strata::server {

namespace {

/// Where the server listens and how many requests it handles at once.
void add_network_options(CLI::App& app, ServerConfig& c) {
    app.add_option("--host", c.host,
                   "Address to listen on; a non-loopback one needs a token (--token-file or "
                   "STRATA_TOKEN) or --insecure");
    app.add_option("--port", c.port, "TCP port (0: any free port)")->check(CLI::Range(0, 65535));
    app.add_option("--threads", c.threads,
                   "HTTP worker threads, i.e. requests handled at once (rendering uses every core "
                   "through TBB regardless)")
        ->check(CLI::Range(1, 1024));
}

/// The data directory: where the journal and snapshots go and how hard they are kept.
void add_durability_options(CLI::App& app, ServerConfig& c) {
    app.add_option("--data", c.data_dir,
                   "Data directory: every acknowledged edit batch is journaled there and the scene "
                   "is snapshotted in the background; a restart recovers it. Created if missing; "
                   "one server per directory (a lock file). Empty: the scene lives in memory "
                   "only");
    app.add_option("--fsync", c.fsync,
                   "When the journal reaches the disk: 'always' before each answer (concurrent "
                   "batches share an fsync), 'batch' at most every --fsync-interval-ms (a crash "
                   "of the machine may lose that much acknowledged work), 'off' when the OS "
                   "decides (a process crash loses nothing, a power cut may)")
        ->check(CLI::IsMember({"always", "batch", "off"}));
    app.add_option("--fsync-interval-ms", c.fsync_interval_ms,
                   "With --fsync batch: the longest an acknowledged batch waits for its fsync")
        ->check(CLI::Range(1, 60000));
    app.add_option("--snapshot-threshold-kb", c.snapshot_threshold_kb,
                   "Journal growth, in KiB, after which a snapshot is written in the background "
                   "and the journal before it removed")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 30));
    app.add_option("--keep-history-mb", c.keep_history_mb,
                   "MiB of older snapshots and journal a snapshot leaves in the data directory, "
                   "so that at_version reads and renders reach further back (0: it removes "
                   "everything it covers)")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 30));
    app.add_flag("--recover-truncate", c.recover_truncate,
                 "At start, if the journal or a snapshot is damaged before its end, keep what "
                 "precedes the damage, set the rest aside (*.damaged) and start, instead of "
                 "refusing to");
}

/// Scaling out: the shared edit log replicas follow, and the peers split renders go to.
void add_replication_options(CLI::App& app, ServerConfig& c) {
    app.add_option("--log", c.log_url,
                   "Shared edit log, redis://HOST:PORT/STREAM: this server becomes a replica that "
                   "appends its batches to the Redis stream and applies every batch from it in "
                   "order (see README, Scaling out). Empty: batches apply locally only");
    app.add_option("--log-snapshot-every", c.log_snapshot_every,
                   "With --log: every this many versions a snapshot of the scene is stored in "
                   "Redis for joining replicas (and for replicas that fell behind the trimmed "
                   "stream, which jump to it), and the stream is trimmed below the previous one "
                   "(0: this replica stores none)")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 40));
    app.add_option("--log-write-timeout-ms", c.log_write_timeout_ms,
                   "With --log: longest a batch may take to be appended and applied here "
                   "(503 beyond)")
        ->check(CLI::Range(100, 600000));
    app.add_option("--min-version-wait-ms", c.min_version_wait_ms,
                   "Longest a read with min_version (or X-Strata-Min-Version) waits for this "
                   "server to reach that version (503 beyond). The front end holds waiting "
                   "reads, not a worker")
        ->check(CLI::Range(0, 600000));
    app.add_option("--max-waiting-reads", c.max_waiting_reads,
                   "Reads waiting for their min_version at once, over all clients (one more is "
                   "answered 503 with Retry-After)")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 20));
    app.add_option("--max-waiting-reads-per-client", c.max_waiting_reads_per_client,
                   "Reads waiting for their min_version at once from one client IP address")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 20));
    app.add_option("--peers", c.peers,
                   "Other servers holding the same scene (replicas of the same --log), as "
                   "comma-separated http://host:port: GET /v1/render?split=N renders horizontal "
                   "bands of the frame on this server and N-1 of them and answers the frame one "
                   "render gives, byte for byte; a peer that is down, slow or at another version "
                   "has its band rendered here. Peers get this server's token. Empty: no split");
    app.add_option("--peer-timeout-ms", c.peer_timeout_ms,
                   "With --peers: longest a split render waits for one peer's band before "
                   "rendering it here")
        ->check(CLI::Range(50, 600000));
}

/// How large a request's body, frame and JSON may be. `max_body_mb` receives --max-body-mb,
/// which the config holds in bytes.
void add_request_limit_options(CLI::App& app, ServerConfig& c, std::size_t& max_body_mb) {
    app.add_option("--max-body-mb", max_body_mb, "Largest request body, in MiB (413 beyond)")
        ->check(CLI::Range(1, 4096));
    app.add_option("--max-pixels", c.max_pixels,
                   "Largest width * height of one render (413 beyond)")
        ->check(CLI::Range(uint64_t(1), uint64_t(64) << 20));
    app.add_option("--max-json-depth", c.max_json_depth,
                   "Deepest JSON nesting accepted (400 beyond)")
        ->check(CLI::Range(4, 1024));
    app.add_option("--max-array-elements", c.max_array_elements,
                   "Most elements in one JSON array (413 beyond)")
        ->check(CLI::Range(std::size_t(16), std::size_t(1) << 30));
    app.add_option("--max-json-values", c.max_json_values,
                   "Most values in one JSON document, long arrays of numbers not counted: what "
                   "bounds a request's parsed memory, about 100 bytes a value (413 beyond)")
        ->check(CLI::Range(std::size_t(1024), std::size_t(1) << 30));
    app.add_option("--max-batch-edits", c.max_batch_edits,
                   "Most edits in one batch, POST /v1/edits or a snapshot upload (413 beyond)")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 30));
}

/// What one connection, and all of them together, may take: timeouts, head sizes, counts and
/// buffered data. `max_buffered_mb` receives --max-buffered-mb, which the config holds in bytes.
void add_connection_options(CLI::App& app, ServerConfig& c, std::size_t& max_buffered_mb) {
    app.add_option("--header-timeout", c.header_timeout_s,
                   "Seconds a client has to send a request's line and headers, from its first "
                   "byte (408 beyond)")
        ->check(CLI::Range(1, 3600));
    app.add_option("--read-timeout", c.read_timeout_s,
                   "Seconds a client has to send a whole request, body included, from its first "
                   "byte (408 beyond)")
        ->check(CLI::Range(1, 3600));
    app.add_option("--write-timeout", c.write_timeout_s,
                   "Seconds a client has to take a whole response before it is dropped")
        ->check(CLI::Range(1, 3600));
    app.add_option("--keep-alive-timeout", c.keep_alive_timeout_s,
                   "Seconds an idle connection stays open between requests")
        ->check(CLI::Range(1, 3600));
    app.add_option("--max-keep-alive-requests", c.max_keep_alive_requests,
                   "Requests served on one connection before it is closed")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 30));
    app.add_option("--max-header-bytes", c.max_header_bytes,
                   "Largest request line and headers together, in bytes (431 beyond)")
        ->check(CLI::Range(std::size_t(1024), std::size_t(1) << 20));
    app.add_option("--max-headers", c.max_headers, "Most header fields in a request (431 beyond)")
        ->check(CLI::Range(std::size_t(8), std::size_t(10000)));
    app.add_option("--max-uri-bytes", c.max_uri_bytes,
                   "Longest request target, in bytes (414 beyond)")
        ->check(CLI::Range(std::size_t(256), MAX_URI_BYTES));
    app.add_option("--max-connections", c.max_connections,
                   "Most client connections open at once (beyond it, and beyond the per-client "
                   "limit, a few more connections are served /livez and /readyz only)")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 20));
    app.add_option("--max-connections-per-client", c.max_connections_per_client,
                   "Most connections open at once from one client IP address (behind a reverse "
                   "proxy, every client is the proxy)")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 20));
    app.add_option("--max-buffered-mb", max_buffered_mb,
                   "Most unfinished request data held in memory over all connections, in MiB "
                   "(503 beyond)")
        ->check(CLI::Range(1, 1 << 20));
    app.add_option("--listen-backlog", c.listen_backlog,
                   "Connections the kernel queues before the server accepts them")
        ->check(CLI::Range(1, 1 << 16));
}

/// How long renders may run, also at shutdown, and how large the scene may grow.
void add_render_limit_options(CLI::App& app, ServerConfig& c) {
    app.add_option("--render-timeout", c.render_timeout_s,
                   "Seconds a render may run before it is stopped (503 deadline-exceeded)")
        ->check(CLI::Range(1, 86400));
    app.add_option("--max-stream-mb", c.max_stream_mb,
                   "MiB the views of open frame streams (GET /v1/stream) may hold together, 8 "
                   "bytes a pixel each; a stream that would open a view beyond it gets 503")
        ->check(CLI::Range(std::size_t(1), std::size_t(1) << 20));
    app.add_option("--import-timeout", c.import_timeout_s,
                   "Seconds of wall-clock and of CPU time an import's sandboxed importer may "
                   "take (POST and PUT /v1/assets; 422 naming the file beyond)")
        ->check(CLI::Range(1, 3600));
    app.add_option("--import-memory-mb", c.import_memory_mb,
                   "MiB an import's sandboxed importer may allocate (422 beyond)")
        ->check(CLI::Range(16u, 1u << 20));
    app.add_option("--shutdown-grace", c.shutdown_grace_s,
                   "Seconds in-flight requests get after SIGTERM before renders are stopped")
        ->check(CLI::Range(0, 3600));
    app.add_option("--max-scene-triangles", c.max_scene_triangles,
                   "Most triangles over the scene's meshes (an edit batch beyond it: 413)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 32));
    app.add_option("--max-scene-vertices", c.max_scene_vertices,
                   "Most vertices over the scene's meshes, each vertex key (motion_positions) "
                   "counting as one (an edit batch beyond it: 413)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 32));
    app.add_option("--max-scene-instances", c.max_scene_instances,
                   "Most instances in the scene, about 1 KB of memory each (an edit batch "
                   "beyond it: 413)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 32));
    app.add_option("--max-texture-mb", c.max_texture_mb,
                   "Most texture memory in MiB: decoded texels (6 bytes each) and the image "
                   "files kept with them (add_texture beyond it: 413)")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 20));
    app.add_option("--max-scenes", c.max_scenes,
                   "Most named scenes (PUT /v1/scenes/NAME) beside the default one; each has "
                   "the --max-scene-* budget, or a smaller one of its own (beyond it: 413)")
        ->check(CLI::Range(std::size_t(0), std::size_t(4096)));
    app.add_option("--max-total-triangles", c.max_total_triangles,
                   "Server-wide budget: what the triangle budgets of all scenes, the default "
                   "one's included, may add up to; a named scene that would take the sum beyond "
                   "is not made (413). 0: no limit")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 40));
    app.add_option("--max-total-vertices", c.max_total_vertices,
                   "Server-wide budget of vertices, as --max-total-triangles")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 40));
    app.add_option("--max-total-instances", c.max_total_instances,
                   "Server-wide budget of instances, as --max-total-triangles")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 40));
    app.add_option("--max-total-texture-mb", c.max_total_texture_mb,
                   "Server-wide budget of texture MiB, as --max-total-triangles")
        ->check(CLI::Range(uint64_t(0), uint64_t(1) << 30));
    app.add_option("--undo-depth", c.undo_depth,
                   "Batches POST /v1/undo can take back in a row (and redo); 0 turns undo off")
        ->check(CLI::Range(std::size_t(0), std::size_t(100000)));
    app.add_option("--undo-mb", c.undo_mb,
                   "MiB the undo and redo stacks may hold; a batch whose inverse is larger "
                   "(a clear of a big scene) cannot be undone, nor anything before it")
        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 20));
}

/// Who may call the API: the bearer token, the loopback rule's override and CORS origins.
void add_access_options(CLI::App& app, CommandLine& cl) {
    app.add_option("--token-file", cl.token_file,
                   "File holding a bearer token; then every endpoint but /livez and /readyz needs "
                   "'Authorization: Bearer <token>'. Or give the token itself in STRATA_TOKEN")
        ->check(CLI::ExistingFile);
    app.add_option("--tokens-file", cl.tokens_file,
                   "File of several tokens, each with its roles per scene: lines 'TOKEN "
                   "SCENE:ROLE ...' (SCENE a name, default or *; ROLE read, edit or admin; see "
                   "protocol/README.md). Instead of --token-file")
        ->check(CLI::ExistingFile);
    app.add_flag("--insecure", cl.insecure, "Allow a non-loopback --host without a token");
    app.add_option("--cors-origin", cl.config.cors_origin,
                   "Origins whose pages may call the API (CORS): a comma-separated list such as "
                   "'https://viewer.example.org,http://localhost:8000', or '*' for any; empty: "
                   "none. Preflights (OPTIONS) from them are answered; the token is still "
                   "required");
}

/// The scene the server starts with and how its top-level acceleration structure is kept.
void add_scene_options(CLI::App& app, ServerConfig& c) {
    app.add_flag("--demo", c.demo,
                 "Start with the demo scene (ignored when the data directory or the edit log "
                 "holds a scene)");
    app.add_flag("--demo-reset", c.demo_reset,
                 "Start with the demo scene in place of whatever the data directory or the edit "
                 "log holds: one batch (clear, then the demo) applied as the next version, so the "
                 "old scene stays in the journal's history");
    app.add_option("--tlas", c.tlas,
                   "TLAS strategy: incremental (a commit costs what its instance edits touch) or "
                   "embree (Embree rebuilds its whole instance BVH on any change; the reference)")
        ->check(CLI::IsMember({"incremental", "embree"}));
    app.add_option("--tlas-max-dynamic-fraction", c.tlas_max_dynamic_fraction,
                   "Incremental TLAS: a commit rebuilds the static tier itself when more than this "
                   "fraction of the instances would be in the dynamic tier")
        ->check(CLI::Range(0.0, 1.0));
    app.add_option("--tlas-min-instances", c.tlas_min_instances,
                   "Incremental TLAS: scenes with fewer instances keep no dynamic tier (a full "
                   "build is that cheap)")
        ->check(CLI::Range(uint32_t(0), uint32_t(1) << 30));
    app.add_option("--tlas-background-merge", c.tlas_background_merge,
                   "Incremental TLAS: rebuild the static tier with the edits in the background "
                   "and swap it in at a later commit (true or false)");
    app.add_option("--tlas-array-min-instances", c.tlas_array_min_instances,
                   "Incremental TLAS: a static tier of at least this many instances is one "
                   "instance array instead of an Embree geometry per instance (less memory, "
                   "faster rays in big scenes); scenes with motion keys never use one");
}

/// Lets every option added so far but --help also come from the environment, --x-y from
/// STRATA_X_Y (containers are configured that way); the command line wins.
void add_environment_variables(CLI::App& app) {
    for (CLI::Option* opt : app.get_options()) {
        if (opt->get_lnames().empty() || opt->get_lnames().front() == "help") continue;
        std::string name = "STRATA_" + opt->get_lnames().front();
        for (char& ch : name)
            ch = ch == '-' ? '_' : char(std::toupper(static_cast<unsigned char>(ch)));
        opt->envname(name);
    }
}

/// --version and --healthcheck: they answer one invocation instead of starting a server.
void add_invocation_options(CLI::App& app, CommandLine& cl) {
    app.set_version_flag("--version", std::string("strata-server ") + VERSION,
                         "Print the version and exit");
    app.add_flag("--healthcheck", cl.healthcheck,
                 "Start no server: GET /readyz on --host (a wildcard address means 127.0.0.1 or "
                 "::1) and --port, exit 0 on 200 and 1 otherwise");
}

}  // namespace

std::variant<CommandLine, int> parse_command_line(int argc, char** argv) {
    CommandLine cl;
    ServerConfig& c = cl.config;
    c.threads = std::max(8u, std::thread::hardware_concurrency());
    std::size_t max_body_mb = c.max_body_bytes >> 20;
    std::size_t max_buffered_mb = c.max_buffered_bytes >> 20;

    CLI::App app{
        "strata-server: a dynamic ray-tracing scene server (JSON over HTTP; see "
        "protocol/README.md)"};
    app.option_defaults()->always_capture_default();
    add_network_options(app, c);
    add_durability_options(app, c);
    add_replication_options(app, c);
    add_request_limit_options(app, c, max_body_mb);
    add_connection_options(app, c, max_buffered_mb);
    add_render_limit_options(app, c);
    add_access_options(app, cl);
    add_scene_options(app, c);
    app.add_option("--log-level", cl.log_level, "trace, debug, info, warn, error, critical or off")
        ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "critical", "off"}));
    // Every option above can also come from the environment. --help, --version and
    // --healthcheck are about one invocation, so they have no variable.
    add_environment_variables(app);
    add_invocation_options(app, cl);
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    c.max_body_bytes = max_body_mb << 20;
    c.max_buffered_bytes = max_buffered_mb << 20;
    return cl;
}

std::string finish_config(CommandLine& cl) {
    const char* env_token = std::getenv(TOKEN_ENV);
    // Set but empty is a mistake (an unset secret in a compose file), never "no token".
    const bool has_env_token = env_token != nullptr;
    if (!cl.token_file.empty()) {
        if (has_env_token)
            return std::string("both a token file (--token-file or STRATA_TOKEN_FILE) and ") +
                   TOKEN_ENV + " are set; give the token one way only";
        auto token = read_token_file(cl.token_file);
        if (!token) return token.error().message;
        cl.config.token = std::move(token.value());
        cl.token_source = "token file '" + cl.token_file + "'";
    } else if (has_env_token) {
        if (std::string_view(env_token).find_first_not_of(" \t\r\n") == std::string_view::npos)
            return std::string(TOKEN_ENV) +
                   " is set but empty: give the token, or unset the variable to serve without "
                   "one (loopback only)";
        auto token = parse_token(env_token, TOKEN_ENV);
        if (!token) return token.error().message;
        cl.config.token = std::move(token.value());
        cl.token_source = TOKEN_ENV;
    }
    if (!cl.tokens_file.empty()) {
        if (!cl.config.token.empty())
            return "both --tokens-file and a single token (--token-file, STRATA_TOKEN_FILE or "
                   "STRATA_TOKEN) are given; give one";
        if (!cl.config.peers.empty())
            return "--peers needs the one token the servers share (--token-file), not "
                   "--tokens-file";
        auto table = read_token_table(cl.tokens_file);
        if (!table) return table.error().message;
        cl.config.tokens = std::make_shared<const TokenTable>(std::move(table.value()));
        cl.token_source = "tokens file '" + cl.tokens_file + "' (" +
                          std::to_string(cl.config.tokens->entries.size()) + " tokens)";
    }
    if (!cl.config.log_url.empty()) {
        auto url = replica::parse_redis_url(cl.config.log_url);
        if (!url) return url.error().message;
    }
    if (auto peers = parse_peers(cl.config.peers); !peers) return peers.error().message;
    if (auto cors = CorsPolicy::parse(cl.config.cors_origin); !cors) return cors.error().message;
    // Resolved first: an unknown name is an error of its own, not "non-loopback".
    auto addresses = resolve_host(cl.config.host);
    if (!addresses) return addresses.error().message;
    bool loopback = !addresses.value().empty();
    for (const std::string& a : addresses.value()) loopback = loopback && is_loopback_host(a);
    if (cl.config.token.empty() && !cl.config.tokens && !cl.insecure && !loopback)
        return "refusing to listen on non-loopback address '" + cl.config.host +
               "' without a token: give --token-file, STRATA_TOKEN_FILE or STRATA_TOKEN (or "
               "--insecure, STRATA_INSECURE=1, to allow it)";
    return {};
}

}  // namespace strata::server
