#pragma once
// Recovery at start: the newest valid snapshot, then every journal record after it, replayed
// through Engine::apply. A torn last record (a crash mid-write) is cut off and reported; damage
// anywhere else stops recovery with the file and offset, unless truncation was asked for.

#include <string>
#include <vector>

#include "engine/core/result.h"
#include "engine/durable/journal.h"

namespace strata {
class Engine;
}

namespace strata::durable {

struct RecoveryOptions {
    /// Damage before the end: keep what precedes it, set the rest aside (`.damaged` files) and
    /// start, instead of refusing to (--recover-truncate).
    bool truncate_damage = false;
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
