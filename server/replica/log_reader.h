#pragma once
// The replica's reader (replica.h, "One writer path"): on its own thread, reads the log in order
// (XREAD BLOCK) and applies each entry at exactly the version it was appended for; the one path
// by which batches reach the engine. It loads the stored snapshot to join with an empty scene,
// jumps to it over a trimmed gap, and stops the replica loudly at a poisoned entry, a gap no
// snapshot bridges, or a log reset or rewritten under it. Redis unreachable: it reconnects with
// back-off and catches up.

#include <cstdint>
#include <string>
#include <thread>

#include "engine/engine.h"
#include "server/replica/replica.h"
#include "server/replica/replica_state.h"
#include "server/replica/snapshot_writer.h"

namespace strata::replica {

class RedisConnection;
struct RedisReply;

class LogReader {
public:
    /// `snapshots`: told when a version due a snapshot was applied; may be null.
    LogReader(const ReplicaOptions& options, Engine& engine, ReplicaState& state,
              SnapshotWriter* snapshots)
        : m_options(options), m_engine(engine), m_state(state), m_snapshots(snapshots) {}

    void start();
    /// Waits for the thread; the state must be shutting down or stopped.
    void join();

private:
    /// One entry of an XREAD reply, as the reader follows it.
    struct StreamEntry {
        const std::string& id;                ///< the stream entry id, "<version>-0"
        uint64_t version = 0;                 ///< from the id
        bool has_version = false;             ///< the id holds a version
        const std::string* record = nullptr;  ///< field 'r', the journal record; null if absent
        int64_t appended_ms = 0;              ///< field 't', unix ms of the append; 0 if absent
    };

    void loop();
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
    /// join target, and tells the snapshotter when its version is due a snapshot.
    void record_applied(const StreamEntry& entry);
    /// load_snapshot over the gap after `applied`, then joins if that caught the replica up.
    Status jump_to_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap);
    /// The log's head version. Stops loudly when the log was reset or rewritten: its version
    /// key is not a number or behind this replica, or its newest entry is not the head's.
    Result<uint64_t> read_log_head(RedisConnection& c);
    /// Whether the log still holds the entry after version `applied`.
    Result<bool> holds_entry_after(RedisConnection& c, uint64_t applied);
    /// Loads the stored snapshot in place of the scene at `applied` (0: an empty scene joining;
    /// else a jump over entries trimmed away, `gap` saying which). Stops loudly when the snapshot
    /// is not newer than `applied` or does not load; a Redis error only loses the connection.
    Status load_snapshot(RedisConnection& c, uint64_t applied, const std::string& gap);

    const ReplicaOptions& m_options;
    Engine& m_engine;
    ReplicaState& m_state;
    SnapshotWriter* m_snapshots;
    uint64_t m_join_target = 0;
    std::thread m_thread;
};

}  // namespace strata::replica
