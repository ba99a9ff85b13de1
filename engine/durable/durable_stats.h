#pragma once
// What the data directory reports (GET /v1/stats "durability", /metrics strata_durable_*): one
// table, DURABLE_COUNTERS, describes every number for both writers, the way ENGINE_COUNTERS does
// for the engine (engine/counters.h).

#include <array>
#include <cstdint>
#include <iterator>
#include <string>
#include <string_view>

#include "engine/core/stat_table.h"

namespace strata::durable {

/// How often the journal reaches the disk before a batch is acknowledged (--fsync).
enum class FsyncMode : uint8_t {
    Always,  ///< fsync before the answer; concurrent batches share one fsync (group commit)
    Batch,   ///< fsync at most every --fsync-interval-ms; a crash may lose that much
    Off,     ///< the OS writes back when it likes; a process crash loses nothing, a power cut may
};
const char* fsync_mode_name(FsyncMode m);

/// Fixed buckets of fsync latency, seconds (the last count is above every bound).
inline constexpr std::array<double, 12> FSYNC_BOUNDS = {
    0.0001, 0.00025, 0.0005, 0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1, 0.25, 1.0};

struct DurableStats {
    // Numbers in the table below.
    uint64_t journal_bytes = 0;    ///< bytes in the journal segments on disk now
    uint64_t journal_records = 0;  ///< records appended since start
    uint64_t journal_appended_bytes = 0;
    uint64_t fsyncs = 0;                 ///< fdatasync calls on journal segments (and directory)
    uint64_t batches_per_fsync_max = 0;  ///< largest group one fsync made durable
    uint64_t snapshots_written = 0;
    uint64_t snapshot_failures = 0;
    uint64_t last_snapshot_version = 0;
    uint64_t last_snapshot_bytes = 0;
    uint64_t last_snapshot_unix_ms = 0;  ///< 0: none written since start
    uint64_t recovered_version = 0;
    uint64_t recovered_records = 0;  ///< journal records replayed at start
    uint64_t torn_records_truncated = 0;
    double fsync_seconds = 0.0;
    double last_snapshot_seconds = 0.0;  ///< copy under the lock plus writing
    double last_snapshot_lock_ms = 0.0;  ///< how long the snapshot held the scene lock
    double recovery_seconds = 0.0;       ///< loading and replaying, before the rebuild
    double rebuild_seconds = 0.0;        ///< acceleration structures at start

    // Not in the table.
    FsyncMode mode = FsyncMode::Always;
    std::string directory;
    bool failed = false;              ///< the journal hit an fsync error and refuses batches
    std::string failure;              ///< why
    std::string last_snapshot_error;  ///< why the newest snapshot attempt failed; empty: it did not
    std::array<uint64_t, FSYNC_BOUNDS.size() + 1> fsync_buckets{};
};

/// One row per number (engine/core/stat_table.h): the `durability` JSON member and the Prometheus
/// series `strata_durable_<name>` (milliseconds as `_seconds`; cumulative ones `_total`).
using DurableCounterSpec = StatSpec<DurableStats>;

inline constexpr DurableCounterSpec DURABLE_COUNTERS[] = {
    {STRATA_STAT(DurableStats, journal_bytes), "Bytes in the journal segments on disk.",
     StatUnit::Bytes, false},
    {STRATA_STAT(DurableStats, journal_records), "Journal records appended since start.",
     StatUnit::Count, true},
    {STRATA_STAT(DurableStats, journal_appended_bytes), "Journal bytes appended since start.",
     StatUnit::Bytes, true},
    {STRATA_STAT(DurableStats, fsyncs), "fsync calls on the journal.", StatUnit::Count, true},
    {STRATA_STAT(DurableStats, batches_per_fsync_max),
     "Most batches one fsync made durable (group commit).", StatUnit::Count, false},
    {STRATA_STAT(DurableStats, snapshots_written), "Snapshots written since start.",
     StatUnit::Count, true},
    {STRATA_STAT(DurableStats, snapshot_failures), "Snapshots that could not be written.",
     StatUnit::Count, true},
    {STRATA_STAT(DurableStats, last_snapshot_version),
     "Scene version of the newest snapshot written since start.", StatUnit::Count, false},
    {STRATA_STAT(DurableStats, last_snapshot_bytes),
     "Size of the newest snapshot written since start.", StatUnit::Bytes, false},
    {STRATA_STAT(DurableStats, last_snapshot_unix_ms),
     "When the newest snapshot was written (Unix ms; 0: none).", StatUnit::Count, false},
    {STRATA_STAT(DurableStats, recovered_version),
     "Scene version recovered from the data directory at start.", StatUnit::Count, false},
    {STRATA_STAT(DurableStats, recovered_records), "Journal records replayed at start.",
     StatUnit::Count, false},
    {STRATA_STAT(DurableStats, torn_records_truncated),
     "Torn last records cut off the journal at start.", StatUnit::Count, false},
    {STRATA_STAT(DurableStats, fsync_seconds), "Time spent in journal fsyncs.", StatUnit::Seconds,
     true},
    {STRATA_STAT(DurableStats, last_snapshot_seconds),
     "Time the newest snapshot took (copy and write).", StatUnit::Seconds, false},
    {STRATA_STAT(DurableStats, last_snapshot_lock_ms),
     "Milliseconds the newest snapshot held the scene lock.", StatUnit::Milliseconds, false},
    {STRATA_STAT(DurableStats, recovery_seconds),
     "Time to load the snapshot and replay the journal at start.", StatUnit::Seconds, false},
    {STRATA_STAT(DurableStats, rebuild_seconds),
     "Time to build the acceleration structures at start.", StatUnit::Seconds, false},
};

}  // namespace strata::durable
