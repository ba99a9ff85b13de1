#pragma once
// A past version of a data directory's scene, loaded read-only beside the live one: the newest
// snapshot at or before it, then the journal's records after that snapshot up to it, replayed
// into a fresh engine. Nothing in the directory is written, locked or removed, and the live
// engine is not touched: reads and renders of an older version (`at_version=N`) use the engine
// this returns.
//
// What it reaches: the versions from the oldest snapshot the directory still holds (or 0 when
// no snapshot was ever written) to the newest record. A background snapshot removes the files it
// covers, so the history it reaches moves forward with them (--snapshot-threshold-kb).
//
// What it costs: reading that snapshot and those journal files, decoding the snapshot's scene and
// applying every record up to the version; the caller's first commit then builds every
// acceleration structure, as after a restart.

#include <cstdint>
#include <memory>
#include <string>

#include "engine/core/result.h"
#include "engine/engine.h"

namespace strata::durable {

/// What load_past_version() did.
struct PastVersionLoad {
    uint64_t snapshot_version = 0;  ///< the snapshot it started from (0: none)
    uint64_t records_replayed = 0;
    uint64_t journal_bytes = 0;  ///< of the segments it read
    double load_ms = 0.0;
};

/// The scene of `dir` at `version` in a new engine made with `config` (its undo history is
/// turned off). OutOfRange when the directory no longer (or not yet) holds that version, with the
/// range it holds; Storage when a file cannot be read or is damaged.
Result<std::unique_ptr<Engine>> load_past_version(const std::string& dir, uint64_t version,
                                                  EngineConfig config,
                                                  PastVersionLoad* load = nullptr);

}  // namespace strata::durable
