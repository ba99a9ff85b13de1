// strata-server: the engine behind JSON over HTTP. Flags: strata-server --help.

#include <sys/resource.h>

#include <atomic>
#include <csignal>
#include <thread>

#include <spdlog/spdlog.h>

#include "engine/core/memory_trim.h"
#include "engine/core/timer.h"
#include "engine/durable/durable_store.h"
#include "protocol/demo/demo_models.h"
#include "server/cli.h"
#include "server/healthcheck.h"
#include "server/log_sink.h"
#include "server/named_scenes.h"
#include "server/past_scenes.h"
#include "server/replica/replica.h"
#include "server/server.h"
#include "server/shutdown.h"

namespace {

using namespace strata;

/// Raises the soft limit on open files to the hard one: each connection holds a descriptor.
/// Returns the limit in force.
rlim_t raise_file_limit() {
    rlimit lim{};
    if (getrlimit(RLIMIT_NOFILE, &lim) != 0) return 1024;
    if (lim.rlim_cur < lim.rlim_max) {
        lim.rlim_cur = lim.rlim_max;
        setrlimit(RLIMIT_NOFILE, &lim);
        getrlimit(RLIMIT_NOFILE, &lim);
    }
    return lim.rlim_cur;
}

/// Locks and recovers --data into `engine`; null (and a logged reason) when it cannot.
std::unique_ptr<durable::DurableStore> open_data_dir(const server::ServerConfig& c,
                                                     Engine& engine,
                                                     durable::RecoveryProgress& progress,
                                                     bool& failed) {
    failed = false;
    if (c.data_dir.empty()) {
        spdlog::warn("no --data directory: the scene lives in memory only and is lost on exit");
        return nullptr;
    }
    durable::StoreOptions o = server::store_options(c, c.data_dir);
    o.recovery.progress = &progress;
    Stopwatch clock;
    auto store = durable::DurableStore::open(o, engine);
    if (!store) {
        spdlog::critical("cannot use the data directory: {}", store.error().message);
        failed = true;
        return nullptr;
    }
    const durable::RecoveryResult& r = store.value()->recovery();
    for (const std::string& note : r.notes) spdlog::warn("recovery: {}", note);
    spdlog::info(
        "data directory {}: recovered version {} ({}, {} journal records replayed) in {:.1f} ms; "
        "fsync {}",
        c.data_dir, r.version,
        r.loaded_snapshot ? "snapshot " + std::to_string(r.snapshot_version) : "no snapshot",
        r.records_replayed, clock.ms(), c.fsync);
    return std::move(store.value());
}

/// Makes writes fail with an error instead of killing the process, and lowers
/// --max-connections to what the open-file limit leaves room for.
void prepare_process(server::ServerConfig& c) {
    // Writes to a connection the client closed fail with EPIPE instead of killing the process.
    std::signal(SIGPIPE, SIG_IGN);
    // A file size limit (ulimit -f) makes journal writes fail with EFBIG instead of killing us.
    std::signal(SIGXFSZ, SIG_IGN);
    const rlim_t files = raise_file_limit();
    if (files != RLIM_INFINITY && files < c.max_connections + 64) {
        spdlog::warn(
            "only {} open files allowed (ulimit -n): lowering --max-connections from {} "
            "to {}",
            files, c.max_connections, files > 128 ? files - 64 : 64);
        c.max_connections = files > 128 ? std::size_t(files - 64) : 64;
    }
}

/// The engine with the scene budget and TLAS strategy of `c`; null (and a logged reason) when
/// it cannot start.
/// The default scene's engine, on an Embree device the named scenes share (identical meshes
/// then share their BLASes, engine/accel/blas_pool.h).
std::unique_ptr<Engine> create_engine(const server::ServerConfig& c) {
    EngineConfig config = server::engine_config(c);
    auto device = SharedEmbree::create(config.accel.embree_config);
    if (!device) {
        spdlog::critical("cannot start the engine: {}", device.error().describe());
        return nullptr;
    }
    config.accel.shared_device = std::move(device.value());
    auto engine = Engine::create(config);
    if (!engine) {
        spdlog::critical("cannot start the engine: {}", engine.error().describe());
        return nullptr;
    }
    return std::move(engine.value());
}

/// What /readyz says about the replica `f` (null without --log: ready): joined, not stopped,
/// and how far behind the edit log it is.
server::Readiness replica_readiness(const replica::Replica* f) {
    server::Readiness r;
    if (!f) return r;
    const replica::ReplicaStatus s = f->status();
    r.ready = s.joined && !s.stopped;
    r.detail = s.stopped ? "the replica stopped following the edit log: " + s.stop_reason
                         : "the replica is catching up with the edit log " + s.log + " (applied " +
                               std::to_string(s.applied_version) + " of " +
                               std::to_string(s.log_version) +
                               (s.connected ? ")" : "; Redis unreachable)");
    r.section = "replica";
    r.numbers = {{"applied_version", double(s.applied_version)},
                 {"log_version", double(s.log_version)},
                 {"lag_entries", double(s.lag_entries)},
                 {"lag_seconds", s.lag_seconds},
                 {"connected", s.connected ? 1.0 : 0.0}};
    return r;
}

/// Starts the graceful shutdown of `http` at the first SIGINT or SIGTERM. The process exits
/// --shutdown-grace plus two seconds later at the latest (in-flight renders are stopped at the
/// grace, the front end closes a second later, the rest is the journal and threads finishing).
void stop_on_signal(server::ShutdownSignals& signals, server::Server& http,
                    const server::ServerConfig& c) {
    const auto exit_after = std::chrono::seconds(c.shutdown_grace_s + 2);
    signals.start(
        [&http, &c](int signo) {
            spdlog::info(
                "{} received: finishing in-flight requests (renders still running after {} s "
                "are stopped; a second signal exits at once)",
                signo == SIGINT ? "SIGINT" : "SIGTERM", c.shutdown_grace_s);
            http.stop();
        },
        exit_after);
}

/// Logs where the server listens, how clients authenticate and where the viewer is.
void log_listening(const server::CommandLine& cl, int port) {
    spdlog::info("strata-server listening on http://{}:{} ({} threads, {})", cl.config.host, port,
                 cl.config.threads,
                 cl.token_source.empty() ? "no authentication"
                                         : "bearer token required, from " + cl.token_source);
    spdlog::info("viewer: open http://{}:{}/ in a browser{}", cl.config.host, port,
                 cl.token_source.empty() ? "" : " (it asks for the token once per tab)");
}

/// Follows the shared edit log (--log) from the `recovered` version (a snapshot jump goes
/// through `store`, when there is one) and hands the replica to the server and to /readyz.
std::unique_ptr<replica::Replica> follow_edit_log(const server::ServerConfig& c, Engine& engine,
                                                  durable::DurableStore* store, uint64_t recovered,
                                                  server::Server& http,
                                                  std::atomic<replica::Replica*>& follower) {
    replica::ReplicaOptions o;
    o.url = replica::parse_redis_url(c.log_url).value();  // checked by finish_config
    o.snapshot_every = c.log_snapshot_every;
    o.max_batch_edits = c.max_batch_edits;
    o.write_timeout = std::chrono::milliseconds(c.log_write_timeout_ms);
    o.store = store;
    auto follow = replica::Replica::start(o, engine);
    follower = follow.get();
    http.attach_replica(follow.get());
    spdlog::info("following the edit log {} from version {}", o.url.describe(), recovered);
    http.follow_scene_log(o);
    return follow;
}

/// The demo scene's batch, after a `clear` when `reset`; a logged reason when it cannot be
/// built.
Result<EditBatch> demo_scene(bool reset) {
    auto batch = demo::scene_with_models();
    if (!batch) {
        spdlog::critical("demo scene not built: {}", batch.error().describe());
        return batch;
    }
    if (reset) batch->edits.insert(batch->edits.begin(), Clear{});
    return batch;
}

/// Appends the demo scene to an empty edit log only (one replica's demo wins, the others find
/// it there), or with `reset` after whatever the log holds. False when the demo scene cannot be
/// built.
bool append_demo_scene(replica::Replica& follow, bool reset) {
    auto batch = demo_scene(reset);
    if (!batch) return false;
    auto applied = follow.append(std::move(batch.value()),
                                 reset ? std::nullopt : std::optional<uint64_t>(0));
    if (applied)
        spdlog::info("demo scene appended to the edit log (version {})", applied.value().version);
    else if (applied.error().code == ErrorCode::VersionMismatch)
        spdlog::info("--demo ignored: the edit log holds a scene already (--demo-reset "
                     "replaces it)");
    else
        spdlog::warn("demo scene not appended: {}", applied.error().message);
    return true;
}

/// Applies the demo scene to the engine (after a `clear` when `reset`). False when it cannot be
/// built or the engine rejects it.
bool apply_demo_scene(Engine& engine, bool reset) {
    auto batch = demo_scene(reset);
    if (!batch) return false;
    auto applied = engine.apply(std::move(batch.value()));
    if (!applied) {
        spdlog::critical("demo scene rejected: {}", applied.error().describe());
        return false;
    }
    spdlog::info("demo scene loaded (version {})", applied.value().version);
    return true;
}

/// Starts with the demo scene (--demo): through the edit log when following one, else in the
/// engine unless the data directory recovered a scene; with `reset` (--demo-reset) in place of
/// any scene. False when the server cannot go on.
bool load_demo_scene(replica::Replica* follow, Engine& engine, uint64_t recovered, bool reset) {
    if (follow) return append_demo_scene(*follow, reset);
    if (recovered != 0 && !reset) {
        spdlog::info(
            "--demo ignored: the data directory holds a scene (version {}); --demo-reset "
            "replaces it with the demo",
            recovered);
        return true;
    }
    return apply_demo_scene(engine, reset);
}

/// Builds the acceleration structures of the scene recovered at version `recovered`, before
/// the server is ready, telling /readyz and the data directory's stats about it.
void build_recovered_scene(Engine& engine, durable::DurableStore* store,
                           durable::RecoveryProgress& progress, uint64_t recovered) {
    progress.version = recovered;
    progress.phase = durable::RecoveryProgress::Building;
    Stopwatch clock;
    auto built = engine.commit();
    if (!built) spdlog::error("building the recovered scene failed: {}", built.error().describe());
    if (store) store->set_rebuild_seconds(clock.ms() / 1000.0);
    spdlog::info("recovered scene built in {:.1f} ms", clock.ms());
}

/// Serves until SIGTERM or SIGINT; returns the process exit code.
int serve(server::CommandLine& cl) {
    server::ShutdownSignals signals;  // before any thread starts, so that all inherit the mask
    prepare_process(cl.config);
    std::unique_ptr<Engine> engine = create_engine(cl.config);
    if (!engine) return 1;
    // Step: listen first. While the data directory is recovered and its scene built, /livez
    // answers 200, /readyz 503 with how far recovery got, everything else 503 with Retry-After.
    server::Server http(cl.config, *engine);
    auto port = http.bind();
    if (!port) {
        spdlog::critical("{}", port.error().message);
        return 1;
    }
    durable::RecoveryProgress progress;
    http.set_starting(true, [&progress] { return progress.describe(); });
    // With --log, /readyz also asks the replica: joined, not stopped, and how far behind.
    std::atomic<replica::Replica*> follower{nullptr};
    http.set_readiness([&follower] { return replica_readiness(follower.load()); });
    stop_on_signal(signals, http, cl.config);
    log_listening(cl, port.value());
    std::thread serving([&http] { http.listen(); });
    auto stop_serving = [&] {
        http.stop();
        serving.join();
    };

    // Step: the data directory, recovered while probes get their answers.
    bool data_failed = false;
    auto store = open_data_dir(cl.config, *engine, progress, data_failed);
    if (data_failed) {
        stop_serving();
        return 1;
    }
    http.attach_store(store.get());
    if (Status scenes = http.recover_scenes(); !scenes) {
        spdlog::critical("cannot recover the named scenes: {}", scenes.error().message);
        stop_serving();
        return 1;
    }
    const uint64_t recovered = engine->read([](const Scene& s) { return s.version(); });
    // Step: the shared edit log. The replica follows it from the recovered version (an empty
    // scene first loads the log's snapshot); every batch reaches the engine through it.
    std::unique_ptr<replica::Replica> follow;
    if (!cl.config.log_url.empty())
        follow = follow_edit_log(cl.config, *engine, store.get(), recovered, http, follower);
    const bool demo = cl.config.demo || cl.config.demo_reset;
    if (demo && !load_demo_scene(follow.get(), *engine, recovered, cl.config.demo_reset)) {
        stop_serving();
        return 1;
    }

    // Step: a recovered scene's acceleration structures, before the server is ready. A new
    // scene (empty, or the demo) is built by its first render, as without --data.
    if (recovered != 0) build_recovered_scene(*engine, store.get(), progress, recovered);
    progress.phase = durable::RecoveryProgress::Done;
    http.set_starting(false);
    serving.join();
    follow.reset();  // the reader stops before the journal and the engine go
    store.reset();   // the journal's last fsync, before the engine goes
    spdlog::info("stopped");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    auto parsed = server::parse_command_line(argc, argv);
    if (auto* code = std::get_if<int>(&parsed)) return *code;
    auto& cl = std::get<server::CommandLine>(parsed);
    if (cl.healthcheck) return server::run_healthcheck(cl.config.host, cl.config.port);
    fix_mmap_threshold();

    spdlog::set_default_logger(server::make_safe_logger("strata"));
    spdlog::set_level(spdlog::level::from_str(cl.log_level));
    spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ %v");

    if (const std::string problem = server::finish_config(cl); !problem.empty()) {
        spdlog::critical("{}", problem);
        return 2;
    }
    return serve(cl);
}
