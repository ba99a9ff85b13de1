#pragma once
// A replica: this server's engine following the shared edit log, a Redis stream.
//
// One writer path. Every batch reaches the engine through the reader thread, which reads the
// stream in order (XREAD BLOCK) and applies each entry at exactly the version it was appended
// for, this replica's own batches included. append() only validates a batch against the local
// scene at version V, appends it with a Lua script that succeeds only while the stream's last
// version is still V, and waits until the reader has applied it. Since every replica applies the
// same entries in the same order from the same state, all hold the same scene at each version.
//
// Failures. An entry that fails its checksum or does not apply (a poisoned entry), a gap in the
// versions that no snapshot bridges, or a log that ends before this replica's version stop the
// replica loudly: it applies nothing more, /readyz answers 503 with the reason, writes 503, and
// the reason is logged and exported. So does a log that was reset or rewritten under it (its
// version key behind this replica's version or gone, its newest entry not the head's), found
// by the reader within a second or by the next write at once. A write never retries past the
// write deadline. Redis unreachable: writes fail with a Storage error (503),
// reads and renders of the applied version go on, and the reader reconnects with backoff (50 ms
// doubling to 2 s) and catches up.
//
// Snapshots and trimming. Every `snapshot_every` versions a background thread stores a snapshot
// of the scene (journal_format.h's snapshot bytes) in the hash `<stream>:snapshot`, replacing an
// older one, and trims the stream below the snapshot it replaced (XTRIM MINID): the log keeps the
// entries since the previous snapshot, so a replica that had reached it can still follow. A new
// replica with an empty scene loads the snapshot and follows the stream from its version.
//
// Snapshot jumps. A replica that holds a scene at version A while the entries after A were
// trimmed (it was stopped, or restarted on a data directory that recovered A) and the stored
// snapshot is at S > A replaces its whole scene with the snapshot's (Engine::replace_with_snapshot,
// or DurableStore::replace_scene when the server has --data, so that the directory then holds S)
// and follows from S + 1. It jumps only over a real gap: the entry after A is gone and the
// snapshot is newer than A. A snapshot that does not load stops the replica with the old scene.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "engine/engine.h"
#include "server/replica/redis_url.h"

namespace strata::durable {
class DurableStore;
}

namespace strata::replica {

struct ReplicaOptions {
    RedisUrl url;
    /// The longest a write may take to be appended and applied here (conflicts retried meanwhile).
    std::chrono::milliseconds write_timeout{5000};
    /// Versions between snapshots stored in Redis; 0: this replica writes none.
    uint64_t snapshot_every = 1000;
    /// Most edits an entry may hold (--max-batch-edits): a larger one stops the replica.
    std::size_t max_batch_edits = std::size_t(1) << 20;
    /// The server's data directory (--data), if any: a snapshot jump goes through it, so that
    /// the directory holds the snapshot's version afterwards. Must outlive the replica.
    durable::DurableStore* store = nullptr;
};

/// What /readyz, /metrics and GET /v1/stats say about the replica.
struct ReplicaStatus {
    std::string log;          ///< redis://host:port/stream
    bool connected = false;   ///< the reader holds a connection now
    bool joined = false;      ///< caught up once with the log as it was at start
    bool stopped = false;     ///< stopped for good (see stop_reason)
    std::string stop_reason;  ///< why: a poisoned entry, a gap, a log behind this replica
    uint64_t applied_version = 0;
    uint64_t log_version = 0;  ///< the newest version this replica knows the log has
    uint64_t lag_entries = 0;  ///< log_version - applied_version
    double lag_seconds = 0.0;  ///< how long the oldest unapplied entry has waited (0: none)
    uint64_t entries_applied = 0;
    uint64_t appends = 0;                  ///< batches this replica appended
    uint64_t append_conflicts = 0;         ///< appends refused because the log had moved on
    uint64_t reconnects = 0;               ///< connections the reader made after losing one
    uint64_t snapshot_loaded_version = 0;  ///< the newest Redis snapshot this replica loaded
    uint64_t snapshot_jumps = 0;  ///< scenes replaced by a newer snapshot over a trimmed gap
    uint64_t snapshots_written = 0;
    uint64_t snapshot_version = 0;  ///< newest snapshot this replica knows of
    uint64_t entries_trimmed = 0;   ///< entries this replica's snapshots trimmed
};

class ReplicaState;
class LogReader;
class LogWriter;
class SnapshotWriter;

/// The replica's parts, each with one job: the reader (log_reader.h), the write path
/// (log_writer.h) and the snapshotter (snapshot_writer.h), around the state they share
/// (replica_state.h).
class Replica {
public:
    /// Starts following the log into `engine` (its version is where following starts; an empty
    /// engine first loads the log's snapshot, if there is one). Redis need not be reachable yet.
    static std::unique_ptr<Replica> start(const ReplicaOptions& options, Engine& engine);
    /// Stops the threads.
    ~Replica();
    Replica(const Replica&) = delete;
    Replica& operator=(const Replica&) = delete;

    /// Validates `batch` at the applied version, appends it to the log and returns once this
    /// replica has applied it. With `expected` (If-Match), a log at another version is a
    /// VersionMismatch; without, the batch is revalidated and retried after catching up. Redis
    /// unreachable, a stopped replica or a timeout: a Storage error saying which.
    Result<ApplyResult> append(EditBatch&& batch, std::optional<uint64_t> expected);

    /// Stops following quietly, without waiting for the threads (the destructor joins them):
    /// for a scene whose log is being deleted. Appends fail from now on.
    void stop();

    uint64_t applied_version() const;
    ReplicaStatus status() const;
    /// Ready to serve: joined, not stopped.
    bool ready() const;

private:
    Replica(const ReplicaOptions& options, Engine& engine);

    const ReplicaOptions m_options;
    std::unique_ptr<ReplicaState> m_state;
    std::unique_ptr<SnapshotWriter> m_snapshots;  ///< null when snapshot_every is 0
    std::unique_ptr<LogWriter> m_writer;
    std::unique_ptr<LogReader> m_reader;
};

}  // namespace strata::replica
