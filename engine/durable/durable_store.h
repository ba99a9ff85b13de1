#pragma once
// A data directory made live: the lock file, recovery at start, the journal attached to the
// engine, and the background snapshots that keep the journal short.
//
// Snapshots. When the journal has grown by `snapshot_threshold_bytes` since the last snapshot, a
// background thread takes a consistent copy of the scene under the scene's shared lock (edits wait
// for the copy, renders do not) and starts a new journal segment at that version in the same
// critical section; it writes the snapshot outside the lock (temp file, fsync, rename, fsync the
// directory) and only then removes the segments and snapshots it replaces.
//
// A snapshot that cannot be written (a full disk, a file size limit) changes nothing that matters:
// the journal keeps every record (its segments are only removed after a snapshot is durable), the
// failure is counted and described in the stats and passed to `on_snapshot_failure`, and the
// background thread tries again after `snapshot_retry_ms`, doubling up to 15 s.

#include <chrono>
#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include "engine/durable/durable_stats.h"
#include "engine/durable/journal.h"
#include "engine/durable/recovery.h"

namespace strata {
class Engine;
struct SnapshotReplace;
}

namespace strata::durable {

struct StoreOptions {
    std::string dir;
    JournalOptions journal;
    RecoveryOptions recovery;
    uint64_t snapshot_threshold_bytes = 64ull << 20;
    /// Bytes of older snapshots and journal segments kept after a snapshot covers them, so that
    /// past versions (past_version.h) reach further back: the oldest go first beyond it. 0: a
    /// snapshot removes everything it covers.
    uint64_t keep_history_bytes = 0;
    uint64_t snapshot_retry_ms = 1000;  ///< first retry after a failed background snapshot
    /// Told why a snapshot failed (the server logs it). Runs on the snapshot's thread.
    std::function<void(const std::string&)> on_snapshot_failure;
};

class DurableStore {
public:
    /// Creates `dir` if missing, locks it (a second server on the same directory is refused),
    /// recovers its scene into `engine` (which must be empty) and attaches the journal. Errors
    /// name the file and the cause.
    static Result<std::unique_ptr<DurableStore>> open(const StoreOptions& options, Engine& engine);
    /// Stops the snapshot thread, detaches the journal and fsyncs it.
    ~DurableStore();
    DurableStore(const DurableStore&) = delete;
    DurableStore& operator=(const DurableStore&) = delete;

    const RecoveryResult& recovery() const { return m_recovery; }
    const std::string& directory() const { return m_options.dir; }

    /// Writes a snapshot now (the background thread does this by itself past the threshold).
    Status snapshot_now();

    /// Replaces the engine's scene with `snapshot` (journal_format.h's snapshot bytes, as a shared
    /// edit log stores them) through Engine::replace_with_snapshot, durably: the bytes are written
    /// as this directory's snapshot of their version before the scenes are swapped, the journal
    /// continues in a segment starting at that version, and the older snapshots and segments are
    /// then removed. A crash at any point recovers either the old scene or the new one. On error
    /// the scene is unchanged and the file is removed again.
    Result<SnapshotReplace> replace_scene(std::string_view snapshot);

    /// Records how long the acceleration structures took to build after recovery.
    void set_rebuild_seconds(double seconds);

    /// Every number for GET /v1/stats and /metrics.
    DurableStats stats() const;

private:
    DurableStore(const StoreOptions& options, Engine& engine);
    void snapshot_loop();
    Status write_snapshot();
    /// After a durable snapshot of `version`: removes the segments and snapshots it covers, but
    /// those history_start() keeps.
    void remove_covered(uint64_t version);
    /// The oldest version whose snapshot, with the segments after it up to `version`, fits
    /// keep_history_bytes (`version` itself when nothing older fits or nothing is kept).
    uint64_t history_start(uint64_t version) const;

    StoreOptions m_options;
    Engine& m_engine;
    int m_lock_fd = -1;
    RecoveryResult m_recovery;
    std::unique_ptr<Journal> m_journal;

    std::mutex m_snapshot_mutex;  ///< one snapshot at a time (background or snapshot_now)
    mutable std::mutex m_stats_mutex;
    DurableStats m_stats;  ///< the store's own fields (snapshots, recovery)

    std::mutex m_loop_mutex;
    std::condition_variable m_loop_cv;
    bool m_stop = false;
    // After a failed background snapshot (snapshot thread only): when to try again.
    bool m_retry = false;
    std::chrono::steady_clock::time_point m_retry_at;
    std::chrono::milliseconds m_retry_delay{0};
    std::thread m_thread;
};

}  // namespace strata::durable
