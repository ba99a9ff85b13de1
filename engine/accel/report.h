#pragma once
// What a commit did (or, for a plan, would do). Cumulative counters are in engine/counters.h.

#include <cstdint>
#include <string>
#include <vector>

#include "engine/accel/tlas.h"

namespace strata {

enum class TlasAction : uint8_t { None, Update, Rebuild };

/// Why a BLAS is rebuilt or refit. Each has a stable wire name (build_reason_name).
enum class BuildReason : uint8_t {
    Added,             ///< rebuild: first build of a new mesh
    TopologyChanged,   ///< rebuild: triangles (or vertex count) replaced
    RebuildRequested,  ///< rebuild: mark_dirty {mesh, rebuild}
    RefitNotAllowed,   ///< rebuild: positions moved but the mesh's build options forbid refit
    BoundsGrowth,      ///< rebuild: refit policy, mesh bounds grew too much since the last build
    TriangleGrowth,    ///< rebuild: refit policy, triangles stretched too much since the build
    RefitLimit,        ///< rebuild: refit policy, too many refits since the last build
    Clustered,         ///< rebuild: a big mesh's first local edit; rebuilt as clusters
    Shared,            ///< no build: another engine's identical BLAS is held (blas_pool.h)
    Unshared,          ///< rebuild: the mesh of a BLAS shared with another engine changed
    PositionsChanged,  ///< refit: vertex positions moved
    RefitRequested,    ///< refit: mark_dirty {mesh, refit}
    TrianglesReplaced,  ///< clusters re-made: a local topology edit on a clustered BLAS
    KeysChanged,        ///< rebuild: vertex keys (motion_positions) added or removed
};
/// The last BuildReason: names and schemas list them all up to it.
inline constexpr BuildReason LAST_BUILD_REASON = BuildReason::KeysChanged;

const char* tlas_action_name(TlasAction a);
const char* build_reason_name(BuildReason r);

/// One BLAS that was (or would be) rebuilt or refit.
struct MeshBuildEntry {
    std::string mesh;  ///< client id
    BuildReason reason = BuildReason::Added;
    std::string detail;  ///< human-readable: the measured drift against its limit, etc.
    uint64_t primitives = 0;  ///< triangles built or refit (a clustered refit: its clusters')
    double ms = 0.0;
    /// Clusters of a clustered BLAS (0: one geometry for the whole mesh; see clustered_blas.h),
    /// and how many of them this commit refit and rebuilt.
    uint32_t clusters = 0;
    uint32_t clusters_refit = 0;
    uint32_t clusters_rebuilt = 0;
    /// Memory of the BLAS after the build (rebuilds only), and for a compacted mesh its memory
    /// at full size, measured by the build's first pass (0 otherwise).
    int64_t bytes = 0;
    int64_t uncompacted_bytes = 0;
};

/// The compacted BLASes of a scene (BuildOptions::compact): how many, and their memory at full
/// size and compacted.
struct CompactionTotals {
    uint64_t meshes = 0;
    int64_t uncompacted_bytes = 0;
    int64_t bytes = 0;

    friend bool operator==(const CompactionTotals&, const CompactionTotals&) = default;
};

/// Phase wall times of one commit, in milliseconds.
struct CommitPhases {
    double plan_ms = 0.0;  ///< dirty-list walk and refit-policy metrics
    double blas_ms = 0.0;  ///< all BLAS builds, refits and releases
    double tlas_ms = 0.0;  ///< the TLAS update or rebuild
    double sync_ms = 0.0;  ///< copying shading data (materials, camera, lights) for launches
    double total_ms = 0.0;
};

/// The rebuild report of one commit. For a plan, times and memory are zero and `planned` is true.
struct RebuildReport {
    uint64_t version = 0;
    bool planned = false;
    TlasAction tlas_action = TlasAction::None;
    uint64_t tlas_instances = 0;  ///< instances the TLAS holds after the commit
    TlasTiers tlas;               ///< the strategy's tiers after the commit
    std::vector<MeshBuildEntry> rebuilt;
    std::vector<MeshBuildEntry> refit;
    std::vector<std::string> released;  ///< meshes whose BLAS was freed (removed meshes)
    uint32_t blas_rebuilds = 0;
    uint32_t blas_refits = 0;
    uint64_t primitives_built = 0;
    uint64_t primitives_refit = 0;
    uint64_t clusters_rebuilt = 0;  ///< clusters of clustered BLASes built or rebuilt
    uint64_t clusters_refit = 0;    ///< clusters of clustered BLASes refit
    /// World transforms (groups and instances) recomputed by the flattening of the batches this
    /// commit covers: what group moves cost before the TLAS.
    uint64_t world_transforms = 0;
    /// Instances handed to the TLAS (changed, or their BLAS changed): a group move hands over
    /// the instances below the group, and no others.
    uint64_t instances_changed = 0;
    int64_t memory_blas_bytes = 0;  ///< bytes Embree holds for BLASes, after the commit
    int64_t memory_tlas_bytes = 0;  ///< bytes Embree holds for the TLAS, after the commit
    CompactionTotals compaction;    ///< the compacted BLASes, after the commit
    CommitPhases phases;

    /// True when the commit did no acceleration-structure work at all.
    bool no_accel_work() const {
        return tlas_action == TlasAction::None && rebuilt.empty() && refit.empty() &&
               released.empty() && !tlas.merge_swapped;
    }
    /// One line: "v12 tlas=update(3) rebuilds=1 refits=0 prims=4096 ms=1.25".
    std::string summary() const;
};

}  // namespace strata
