#pragma once
// Everything strata-server can be told on its command line (see cli.cpp for flags and defaults).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace strata::server {

struct TokenTable;

struct ServerConfig {
    std::string host = "127.0.0.1";
    int port = 7070;          ///< 0: any free port (tests)
    std::size_t threads = 8;  ///< HTTP worker threads (rendering uses TBB's own pool)
    std::string data_dir;     ///< journal and snapshots (engine/durable); empty: memory only

    // Durability (engine/durable/durable_store.h), with --data only.
    std::string fsync = "always";       ///< always | batch | off
    int fsync_interval_ms = 100;        ///< batch: longest a written batch waits for its fsync
    uint64_t snapshot_threshold_kb = 64 * 1024;  ///< journal growth that triggers a snapshot
    uint64_t keep_history_mb = 0;  ///< older snapshots and journal kept for at_version reads
    bool recover_truncate = false;      ///< start past damage, setting the rest aside
    std::size_t max_body_bytes = 256ull << 20;
    uint64_t max_pixels = 16ull << 20;  ///< width * height of one render
    std::size_t max_json_depth = 64;
    std::size_t max_array_elements = 1u << 26;
    std::size_t max_json_values = 1u << 20;   ///< values in one JSON document (its DOM's size)
    std::size_t max_batch_edits = 1u << 20;   ///< edits in one batch, JSON or snapshot

    // The front end (reactor.h): every limit on what one client can hold.
    int header_timeout_s = 10;     ///< request line and headers, from the request's first byte
    int read_timeout_s = 30;       ///< the whole request, body included, from its first byte
    int write_timeout_s = 30;      ///< the whole response
    int keep_alive_timeout_s = 5;  ///< idle time between requests on a connection
    std::size_t max_keep_alive_requests = 1000;      ///< requests on one connection
    std::size_t max_header_bytes = 32 * 1024;        ///< request line and headers (431)
    std::size_t max_headers = 100;                   ///< header fields (431)
    std::size_t max_uri_bytes = 8000;                ///< request target (414)
    std::size_t max_connections = 1024;              ///< open connections in all
    std::size_t max_connections_per_client = 128;    ///< per client IP address
    std::size_t max_buffered_bytes = 1024ull << 20;  ///< unfinished request data in memory
    int listen_backlog = 1024;
    int render_timeout_s = 60;  ///< a render running longer is stopped (503)
    std::size_t max_stream_mb = 1024;  ///< what the views of open frame streams hold together
    int shutdown_grace_s = 3;   ///< SIGTERM: in-flight requests get this long, then renders stop
    int import_timeout_s = 60;  ///< an importer's child process is killed after this (422)
    uint32_t import_memory_mb = 2048;  ///< what an importer's child may allocate (422 beyond)

    // The scene budget (engine/scene/budget.h), checked when a batch is validated.
    uint64_t max_scene_triangles = 1ull << 24;
    uint64_t max_scene_vertices = 1ull << 24;
    uint64_t max_texture_mb = 256;  ///< decoded texels over all textures, in MiB
    /// About 1 KB of memory each (tests/bench/NOTES.md): 8 GB at the default, so that one bulk
    /// edit of a few bytes cannot take more memory than a modest machine has.
    uint64_t max_scene_instances = 1ull << 23;

    // Named scenes (named_scenes.h), beside the default one.
    std::size_t max_scenes = 64;
    /// The server-wide budget: what the budgets of all scenes, the default one's included, may
    /// add up to (a scene whose budget would take the sum beyond is not made); 0: no limit but
    /// --max-scenes.
    uint64_t max_total_triangles = 0;
    uint64_t max_total_vertices = 0;
    uint64_t max_total_instances = 0;
    uint64_t max_total_texture_mb = 0;

    // The undo history (engine/scene/edit_history.h).
    std::size_t undo_depth = 100;  ///< batches on each of the undo and redo stacks; 0: no undo
    uint64_t undo_mb = 256;        ///< MiB the inverse batches of both stacks may hold

    // The TLAS strategy (engine/accel/tlas.h) and the incremental strategy's policy.
    std::string tlas = "incremental";  ///< "incremental" or "embree"
    double tlas_max_dynamic_fraction = 0.10;
    uint32_t tlas_min_instances = 1024;
    bool tlas_background_merge = true;
    uint32_t tlas_array_min_instances = 65536;  ///< TlasPolicy's (cli_test checks they agree)

    // Replicas (server/replica/replica.h): the shared edit log, and read-your-writes waits.
    std::string log_url;              ///< redis://HOST:PORT/STREAM; empty: no shared log
    uint64_t log_snapshot_every = 1000;  ///< versions between snapshots stored in Redis; 0: none
    int log_write_timeout_ms = 5000;  ///< longest a write waits to be appended and applied
    int min_version_wait_ms = 5000;   ///< longest a read waits for its min_version
    /// Reads waiting for their min_version (held by the front end, not a worker): in all, and
    /// per client IP address. One more is answered 503 at once.
    std::size_t max_waiting_reads = 256;
    std::size_t max_waiting_reads_per_client = 16;

    // Frames across replicas (split_render.h).
    std::string peers;            ///< comma-separated http://host:port; empty: no split renders
    int peer_timeout_ms = 10000;  ///< longest a split render waits for one peer's band

    std::string token;  ///< bearer token; empty: no authentication (unless `tokens`)
    /// --tokens-file: tokens with roles per scene (auth.h); null: `token` alone, or none.
    std::shared_ptr<const TokenTable> tokens;
    /// Origins allowed cross-origin access (cors.h): "", "*" or a comma-separated list.
    std::string cors_origin;
    bool demo = false;        ///< start with the demo scene
    bool demo_reset = false;  ///< ... in place of the scene the data directory or log holds
};

}  // namespace strata::server
