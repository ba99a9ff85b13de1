#pragma once
// The engine's cumulative counters and the one table that describes them. Every writer (the
// JSON of GET /v1/stats, the Prometheus text of /metrics, the generated list in
// protocol/README.md) walks ENGINE_COUNTERS, so a new counter is one field here plus one row in
// the table; a static_assert below refuses a field without a row.
//
// Counting costs nothing on hot paths: launches and commits count into locals and add them under
// the engine's stats lock once (pbrt-v4's STAT_COUNTER idea: merged, not shared, while working).

#include <cstdint>
#include <iterator>
#include <string_view>

namespace strata {

/// Counters since the engine started.
struct EngineCounters {
    uint64_t batches_applied = 0;
    uint64_t batches_rejected = 0;
    uint64_t edits_applied = 0;
    uint64_t commits = 0;
    uint64_t noop_commits = 0;
    uint64_t blas_rebuilds = 0;
    uint64_t blas_refits = 0;
    uint64_t tlas_updates = 0;
    uint64_t tlas_rebuilds = 0;
    uint64_t tlas_static_rebuilds = 0;
    uint64_t tlas_merges = 0;
    uint64_t tlas_merges_cancelled = 0;
    uint64_t primitives_built = 0;
    uint64_t primitives_refit = 0;
    uint64_t renders = 0;
    uint64_t rays_traced = 0;
    uint64_t picks = 0;
    uint64_t world_transforms = 0;
    double commit_seconds = 0.0;
    double render_seconds = 0.0;
    double tlas_merge_seconds = 0.0;
};

/// What a counter counts, for writers that name or scale by it.
enum class CounterUnit : uint8_t { Count, Seconds };

/// One row of the table: the wire name (JSON member; Prometheus `strata_<name>_total`), a help
/// sentence, the unit and the field.
struct CounterSpec {
    std::string_view name;
    std::string_view help;
    CounterUnit unit;
    uint64_t EngineCounters::*count = nullptr;  ///< for CounterUnit::Count
    double EngineCounters::*seconds = nullptr;  ///< for CounterUnit::Seconds

    /// The counter's value in `c`, as a double (exact below 2^53).
    double value(const EngineCounters& c) const {
        return unit == CounterUnit::Count ? double(c.*count) : c.*seconds;
    }
};

inline constexpr CounterSpec ENGINE_COUNTERS[] = {
    {"batches_applied", "Edit batches applied.", CounterUnit::Count,
     &EngineCounters::batches_applied},
    {"batches_rejected", "Edit batches refused (invalid, or If-Match found another version).",
     CounterUnit::Count, &EngineCounters::batches_rejected},
    {"edits_applied", "Edits applied (in applied batches).", CounterUnit::Count,
     &EngineCounters::edits_applied},
    {"commits", "Commits run (explicit, and before each render).", CounterUnit::Count,
     &EngineCounters::commits},
    {"noop_commits", "Commits that found no acceleration-structure work.", CounterUnit::Count,
     &EngineCounters::noop_commits},
    {"blas_rebuilds", "BLAS builds.", CounterUnit::Count, &EngineCounters::blas_rebuilds},
    {"blas_refits", "BLAS refits.", CounterUnit::Count, &EngineCounters::blas_refits},
    {"tlas_updates", "TLAS updates.", CounterUnit::Count, &EngineCounters::tlas_updates},
    {"tlas_rebuilds", "TLAS full rebuilds.", CounterUnit::Count, &EngineCounters::tlas_rebuilds},
    {"tlas_static_rebuilds",
     "Commits in which the incremental TLAS rebuilt its static tier itself (small scene, "
     "dynamic tier over its limit, first build, or asked for).",
     CounterUnit::Count, &EngineCounters::tlas_static_rebuilds},
    {"tlas_merges", "Background TLAS merges swapped in at a commit.", CounterUnit::Count,
     &EngineCounters::tlas_merges},
    {"tlas_merges_cancelled",
     "Background TLAS merges abandoned (a BLAS they read changed, or a commit rebuilt the static "
     "tier first).",
     CounterUnit::Count, &EngineCounters::tlas_merges_cancelled},
    {"primitives_built", "Triangles built into BLASes.", CounterUnit::Count,
     &EngineCounters::primitives_built},
    {"primitives_refit", "Triangles refit in BLASes.", CounterUnit::Count,
     &EngineCounters::primitives_refit},
    {"renders", "Launches that traced rays (frames rendered).", CounterUnit::Count,
     &EngineCounters::renders},
    {"rays_traced", "Rays traced by launches and picks: camera, shadow and bounce rays.", CounterUnit::Count,
     &EngineCounters::rays_traced},
    {"picks", "Picks answered (each traces one ray per pixel asked about).", CounterUnit::Count,
     &EngineCounters::picks},
    {"world_transforms",
     "World transforms recomputed (groups and instances below moved, reparented, shown or hidden "
     "groups, and edited instances).",
     CounterUnit::Count, &EngineCounters::world_transforms},
    {"commit_seconds", "Wall time spent in commits.", CounterUnit::Seconds, nullptr,
     &EngineCounters::commit_seconds},
    {"render_seconds", "Wall time spent tracing and shading in launches.", CounterUnit::Seconds,
     nullptr, &EngineCounters::render_seconds},
    {"tlas_merge_seconds", "Background build time of the TLAS merges swapped in (wall).",
     CounterUnit::Seconds, nullptr, &EngineCounters::tlas_merge_seconds},
};

// Every field is 8 bytes; a field without a row (or a row too many) changes one side only.
static_assert(sizeof(EngineCounters) == std::size(ENGINE_COUNTERS) * 8,
              "every EngineCounters field needs exactly one row in ENGINE_COUNTERS");

}  // namespace strata
