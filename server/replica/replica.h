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

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "engine/engine.h"
#include "server/replica/redis_url.h"

namespace strata::durable {
class DurableStore;
}

namespace strata::replica {

class RedisConnection;
struct RedisReply;

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
    uint64_t snapshot_version = 0;       ///< newest snapshot this replica knows of
    uint64_t entries_trimmed = 0;        ///< entries this replica's snapshots trimmed
};

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

    uint64_t applied_version() const { return m_applied.load(); }
    ReplicaStatus status() const;
    /// Ready to serve: joined, not stopped.
    bool ready() const { return m_joined.load() && !m_stopped.load(); }

private:
    /// One entry of an XREAD reply, as the reader follows it.
    struct StreamEntry {
        const std::string& id;                ///< the stream entry id, "<version>-0"
        uint64_t version = 0;                 ///< from the id
        bool has_version = false;             ///< the id holds a version
        const std::string* record = nullptr;  ///< field 'r', the journal record; null if absent
        int64_t appended_ms = 0;              ///< field 't', unix ms of the append; 0 if absent
    };
    /// What the conditional append answered.
    struct AppendAnswer {
        bool appended = false;  ///< the log's head was still the base: the entry is in
        uint64_t head = 0;      ///< the entry's version once appended, else the log's version
    };

    Replica(const ReplicaOptions& options, Engine& engine);
    void reader_loop();
    /// After a (re)connection: the log's head, the snapshot to start from.
    Status on_connect(RedisConnection& c);
    /// Reads and applies one XREAD's worth; errors lose the connection.
    Status read_and_apply(RedisConnection& c);
    /// With nothing new to read: refreshes the log's head, and jumps to the snapshot when the
    /// log has moved on but no longer holds the entry after the applied version.
    Status refresh_head(RedisConnection& c);
    /// The id and fields of XREAD entry `e` (an id and a field list, at least).
    static StreamEntry read_stream_entry(const RedisReply& e);
    /// Stops loudly at an entry that is not a Strata entry or does not come after `applied`.
    Status check_entry_order(const StreamEntry& entry, uint64_t applied);
    /// Checks `entry` and applies it to the scene at `applied`, exactly the version it was
    /// appended for; stops loudly when it is poisoned.
    Status apply_entry(const StreamEntry& entry, uint64_t applied);
    /// Publishes `entry` as applied: wakes the waiters, updates the lag, joins when it was the
    /// join target, and wakes the snapshotter when its version is due a snapshot.
    void record_applied(const StreamEntry& entry);
    /// load_snapshot over the gap after `applied`, then joins if that caught the replica up.
    Status jump_to_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap);
    /// The log's head version. Stops loudly when the log was reset or rewritten: its version
    /// key is not a number or behind this replica, or its newest entry is not the head's.
    Result<uint64_t> read_log_head(RedisConnection& c);
    /// Stops loudly when the log's `head` is behind the applied version (Redis was reset or
    /// lost entries this replica applied).
    Status check_not_behind(uint64_t head);
    /// Whether the log still holds the entry after version `applied`.
    Result<bool> holds_entry_after(RedisConnection& c, uint64_t applied);
    /// Loads the stored snapshot in place of the scene at `applied` (0: an empty scene joining;
    /// else a jump over entries trimmed away, `gap` saying which). Stops loudly when the snapshot
    /// is not newer than `applied` or does not load; a Redis error only loses the connection.
    Status load_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap);
    void stop_loudly(const std::string& why);
    void set_log_version(uint64_t v);
    void mark_joined();
    void snapshot_loop();
    Status write_snapshot();
    /// The error a write gets from a stopped replica, saying why it stopped.
    Unexpected<Error> stopped_error() const;
    /// Waits until `deadline` for the reader to join the log; an error when the replica stopped
    /// or has not joined by then.
    Status wait_joined(std::chrono::steady_clock::time_point deadline);
    /// The applied version to validate a write at; with `expected` (If-Match), waits for it
    /// first, and any other version is a VersionMismatch.
    Result<uint64_t> validation_base(std::optional<uint64_t> expected,
                                     std::chrono::steady_clock::time_point deadline);
    /// Validates the batch of `entry` against the local scene at `base`: true when it holds,
    /// false to try again at a newer version the replica has applied since; an error when it
    /// is refused against the log's head too, or time ran out.
    Result<bool> validate_at(const std::string& entry, uint64_t base,
                             std::optional<uint64_t> expected,
                             std::chrono::steady_clock::time_point deadline);
    /// Appends `entry` as version `base` + 1 only while the log's head is still `base`.
    Result<AppendAnswer> append_at(const std::string& entry, uint64_t base);
    /// Counts the append of `version` (`count` edits) and waits until `deadline` for the reader
    /// to apply it.
    Result<ApplyResult> await_appended(uint64_t version, std::size_t count,
                                       std::chrono::steady_clock::time_point deadline);
    /// Counts an append refused because the log is at `head`. With `expected` (If-Match) that
    /// is the client's answer, a VersionMismatch; without, waits for the reader to catch up
    /// with `head` so that the write can try again.
    Status catch_up_after_conflict(uint64_t head, std::optional<uint64_t> expected,
                                   std::chrono::steady_clock::time_point deadline);
    /// The log's last version, read on the writer connection.
    Result<uint64_t> log_head();
    /// The writer connection, made on demand; null (and `error`) while Redis is unreachable.
    RedisConnection* writer(Error& error);
    bool sleep_for(std::chrono::milliseconds d);  ///< false once shutting down
    /// Waits until the applied version is at least `version`; false on timeout or when the
    /// replica stopped.
    bool wait_applied(uint64_t version, std::chrono::milliseconds timeout);

    const ReplicaOptions m_options;
    Engine& m_engine;

    std::atomic<uint64_t> m_applied{0};
    std::atomic<uint64_t> m_log_version{0};
    std::atomic<bool> m_joined{false};
    std::atomic<bool> m_stopped{false};
    std::atomic<bool> m_connected{false};
    std::atomic<bool> m_shutdown{false};
    std::atomic<int64_t> m_lag_since_ms{0};  ///< unix ms the oldest unapplied entry was appended
    uint64_t m_join_target = 0;              ///< reader thread only

    mutable std::mutex m_mutex;  ///< guards the fields below and pairs with m_cv
    std::condition_variable m_cv;
    std::string m_stop_reason;
    ReplicaStatus m_counters;  ///< the counting fields only

    std::mutex m_writer_mutex;
    std::unique_ptr<RedisConnection> m_writer;
    std::chrono::steady_clock::time_point m_writer_retry_at{};
    std::chrono::milliseconds m_writer_backoff{0};

    std::mutex m_snapshot_mutex;
    std::condition_variable m_snapshot_cv;
    bool m_snapshot_due = false;
    std::atomic<uint64_t> m_known_snapshot{0};

    std::thread m_reader;
    std::thread m_snapshotter;
};

}  // namespace strata::replica
