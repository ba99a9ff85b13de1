#pragma once
// Recovery at start: the newest valid snapshot, then every journal record after it, replayed
// through Engine::apply. A torn last record (a crash mid-write) is cut off and reported; damage
// anywhere else stops recovery with the file and offset, unless truncation was asked for.

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "engine/core/result.h"
#include "engine/durable/journal.h"

namespace strata {
class Engine;
}

namespace strata::durable {

/// How far a start has got, written by recovery and the server's first build, read by other
/// threads (the server's /readyz while it recovers). All fields are atomics.
struct RecoveryProgress {
    enum Phase : int { Opening, Snapshot, Journal, Building, Done };
    std::atomic<int> phase{Opening};
    std::atomic<uint64_t> version{0};  ///< the scene's version so far
    std::atomic<uint64_t> journal_bytes_total{0};
    std::atomic<uint64_t> journal_bytes_done{0};
    std::atomic<uint64_t> records_replayed{0};

    /// One line for people: the phase and how far it is.
    std::string describe() const;
};

struct RecoveryOptions {
    /// Where to report progress (optional; must outlive recover()).
    RecoveryProgress* progress = nullptr;
    /// Damage before the end: keep what precedes it, set the rest aside (`.damaged` files) and
    /// start, instead of refusing to (--recover-truncate).
    bool truncate_damage = false;
    /// Segments the loaded snapshot covers are kept (not replayed, not removed) and listed in
    /// RecoveryResult::segments: a store that keeps history for past versions (StoreOptions::
    /// keep_history_bytes) left them on purpose.
    bool keep_covered = false;
};

struct RecoveryResult {
    uint64_t version = 0;           ///< where the scene stands after recovery
    uint64_t snapshot_version = 0;  ///< the snapshot loaded (0: none)
    bool loaded_snapshot = false;
    uint64_t records_replayed = 0;
    uint64_t torn_truncated = 0;
    std::vector<SegmentInfo> segments;  ///< segments left on disk, oldest first (Journal::open)
    std::vector<std::string> notes;     ///< what recovery did that an operator should know
};

/// Loads `dir` into `engine`, which must be empty and have no journal attached.
Result<RecoveryResult> recover(const std::string& dir, Engine& engine,
                               const RecoveryOptions& options);

}  // namespace strata::durable
