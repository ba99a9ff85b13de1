#pragma once
// The write-ahead journal: applied batches appended to segment files in the data directory
// (journal_format.h), made durable according to the fsync mode.
//
// Ordering. append() runs under the engine's exclusive scene lock, right after the batch passed
// every check and before the scene lets go of its undo log: records land in version order, and a
// failed write rolls the batch back (nothing applied, nothing acknowledged). rotate() runs under
// the scene's shared lock, so no append is in flight while a snapshot's consistent copy is taken
// and the next segment starts exactly after it.
//
// Group commit (--fsync always). wait_durable() runs after the scene lock is released. The first
// waiter to find no fsync running becomes the leader: it notes how far the journal is written,
// fsyncs outside the mutex, and wakes everyone that point covers. Batches appended meanwhile wait
// for the next leader, so N concurrent batches cost about one fsync, not N.

#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/result.h"
#include "engine/durable/durable_stats.h"
#include "engine/durable/journal_format.h"

namespace strata::durable {

struct JournalOptions {
    FsyncMode mode = FsyncMode::Always;
    int fsync_interval_ms = 100;  ///< Batch mode: the longest a written record waits for fsync
};

/// A segment file on disk.
struct SegmentInfo {
    uint64_t base = 0;
    std::string path;
    uint64_t bytes = 0;
};

class Journal {
public:
    /// Opens the journal in `dir` for records after `version`. `segments` are the segments
    /// recovery left on disk, oldest first: the newest (valid up to its end) is appended to; with
    /// none, `journal-<version>.log` is created. Older ones are dropped after snapshots.
    static Result<std::unique_ptr<Journal>> open(const std::string& dir, uint64_t version,
                                                 const JournalOptions& options,
                                                 std::vector<SegmentInfo> segments);
    ~Journal();
    Journal(const Journal&) = delete;
    Journal& operator=(const Journal&) = delete;

    /// Under the scene's exclusive lock: stamps `record` with `version` and writes it. Returns
    /// the position wait_durable() needs. On failure nothing of the record stays in the file.
    Result<uint64_t> append(PendingRecord& record, uint64_t version);

    /// After the scene lock is released: returns once the record ending at `position` is as
    /// durable as the mode promises (Always: fsynced). An fsync failure is final: this and every
    /// later batch get a Storage error.
    Status wait_durable(uint64_t position);

    /// Under the scene lock (shared is enough): later records go to a new segment whose base is
    /// `version`, the scene's version now.
    Status rotate(uint64_t version);

    /// Removes segments whose records all precede `version` (a durable snapshot covers them).
    void drop_segments_before(uint64_t version);

    /// Bytes appended since the last rotate() (what decides the next snapshot).
    uint64_t bytes_since_rotation() const;

    /// fsyncs whatever is written (a graceful stop), whatever the mode.
    Status flush();

    /// Adds the journal's numbers to `stats`.
    void add_stats(DurableStats& stats) const;

    const JournalOptions& options() const { return m_options; }

private:
    struct File;
    Journal(std::string dir, const JournalOptions& options);
    Result<std::shared_ptr<File>> create_segment(uint64_t base);
    /// Leader's work: fsyncs up to the written position. Called with `lock` held; releases it
    /// while syncing.
    void sync_as_leader(std::unique_lock<std::mutex>& lock);
    void background_sync_loop();

    const std::string m_dir;
    const JournalOptions m_options;

    mutable std::mutex m_mutex;
    std::condition_variable m_synced_cv;
    std::shared_ptr<File> m_current;
    std::vector<std::shared_ptr<File>> m_retired;  ///< rotated out, not yet fsynced
    std::vector<SegmentInfo> m_segments;           ///< every segment on disk, oldest first
    bool m_dir_dirty = false;                      ///< a segment was created since the last sync
    uint64_t m_written = 0;  ///< position: bytes appended since open, over all segments
    uint64_t m_synced = 0;   ///< position known durable
    uint64_t m_records_written = 0;
    uint64_t m_records_synced = 0;
    bool m_syncing = false;
    std::string m_failure;  ///< non-empty: an fsync failed; the journal takes no more
    uint64_t m_since_rotation = 0;
    DurableStats m_stats;  ///< the counters the journal keeps

    std::thread m_background;  ///< Batch mode's periodic fsync
    std::condition_variable m_stop_cv;
    bool m_stop = false;
};

}  // namespace strata::durable
