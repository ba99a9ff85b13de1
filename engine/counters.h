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

#include "engine/core/stat_table.h"

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
    uint64_t clusters_rebuilt = 0;
    uint64_t clusters_refit = 0;
    uint64_t renders = 0;
    uint64_t rays_traced = 0;
    uint64_t picks = 0;
    uint64_t world_transforms = 0;
    double commit_seconds = 0.0;
    double render_seconds = 0.0;
    double tlas_merge_seconds = 0.0;
};

/// One row per field (engine/core/stat_table.h): the JSON member and the Prometheus counter
/// `strata_<name>_total`.
using CounterSpec = StatSpec<EngineCounters>;

inline constexpr CounterSpec ENGINE_COUNTERS[] = {
    {STRATA_STAT(EngineCounters, batches_applied), "Edit batches applied."},
    {STRATA_STAT(EngineCounters, batches_rejected),
     "Edit batches refused (invalid, or If-Match found another version)."},
    {STRATA_STAT(EngineCounters, edits_applied), "Edits applied (in applied batches)."},
    {STRATA_STAT(EngineCounters, commits), "Commits run (explicit, and before each render)."},
    {STRATA_STAT(EngineCounters, noop_commits),
     "Commits that found no acceleration-structure work."},
    {STRATA_STAT(EngineCounters, blas_rebuilds), "BLAS builds."},
    {STRATA_STAT(EngineCounters, blas_refits), "BLAS refits."},
    {STRATA_STAT(EngineCounters, tlas_updates), "TLAS updates."},
    {STRATA_STAT(EngineCounters, tlas_rebuilds), "TLAS full rebuilds."},
    {STRATA_STAT(EngineCounters, tlas_static_rebuilds),
     "Commits in which the incremental TLAS rebuilt its static tier itself (small scene, dynamic "
     "tier over its limit, first build, or asked for)."},
    {STRATA_STAT(EngineCounters, tlas_merges), "Background TLAS merges swapped in at a commit."},
    {STRATA_STAT(EngineCounters, tlas_merges_cancelled),
     "Background TLAS merges abandoned (a BLAS they read changed, or a commit rebuilt the static "
     "tier first)."},
    {STRATA_STAT(EngineCounters, primitives_built), "Triangles built into BLASes."},
    {STRATA_STAT(EngineCounters, primitives_refit), "Triangles refit in BLASes."},
    {STRATA_STAT(EngineCounters, clusters_rebuilt),
     "Clusters of clustered BLASes built or rebuilt (whole builds count all their clusters)."},
    {STRATA_STAT(EngineCounters, clusters_refit), "Clusters of clustered BLASes refit."},
    {STRATA_STAT(EngineCounters, renders), "Launches that traced rays (frames rendered)."},
    {STRATA_STAT(EngineCounters, rays_traced),
     "Rays traced by launches and picks: camera, shadow and bounce rays."},
    {STRATA_STAT(EngineCounters, picks),
     "Picks answered (each traces one ray per pixel asked about)."},
    {STRATA_STAT(EngineCounters, world_transforms),
     "World transforms recomputed (groups and instances below moved, reparented, shown or hidden "
     "groups, and edited instances)."},
    {STRATA_STAT(EngineCounters, commit_seconds), "Wall time spent in commits.", StatUnit::Seconds},
    {STRATA_STAT(EngineCounters, render_seconds),
     "Wall time spent tracing and shading in launches.", StatUnit::Seconds},
    {STRATA_STAT(EngineCounters, tlas_merge_seconds),
     "Background build time of the TLAS merges swapped in (wall).", StatUnit::Seconds},
};

// Every field is 8 bytes; a field without a row (or a row too many) changes one side only.
static_assert(sizeof(EngineCounters) == std::size(ENGINE_COUNTERS) * 8,
              "every EngineCounters field needs exactly one row in ENGINE_COUNTERS");

}  // namespace strata
