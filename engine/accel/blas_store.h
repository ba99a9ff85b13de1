#pragma once
// One bottom-level acceleration structure (an Embree scene holding one triangle geometry) per
// mesh slot. Any number of instances share it. Geometry lives in Embree-owned buffers that only
// the commit writes, so edits never touch what a launch is tracing.
//
// Build options map onto Embree as follows (Embree honours a per-geometry quality only in a
// scene of quality LOW, and only REFIT-quality geometry is refit on a vertex-only change):
//
//   allow_refit  prefer       scene quality, flags  geometry quality  builder
//   true         either       LOW, DYNAMIC          REFIT             SAH, then refit in place
//   false        fast_trace   HIGH                  HIGH              SAH with spatial splits
//   false        fast_build   LOW, DYNAMIC          LOW               Morton
//
// `compact` (OptiX's compaction) adds a second pass to every build: the BVH is built as above and
// measured, then rebuilt in place with RTC_SCENE_FLAG_COMPACT (Embree's indexed triangle layout,
// no spatial splits), and the full build's memory is freed. The record keeps both sizes; refits
// stay in the compact layout. Measured on a 1M-triangle sphere (tests/bench/NOTES.md,
// "Compaction"): 26-37% less memory, traces 6-11% slower, builds up to twice as long. A compacted
// mesh is never clustered.
//
// On a device shared with other engines (embree_device.h), a whole BLAS is shared with them
// when their meshes are identical (blas_pool.h): a build that finds one holds it instead, and a
// store never changes a shared BLAS (a rebuild lets go of it, a refit of one others hold builds
// a copy first).
//
// Points and curves (mesh_kind.h) get one geometry of Embree's sphere or curve type, its vertex
// buffer holding x y z and the radius (float4); a curve mesh's index buffer holds each segment's
// first control vertex. They are neither clustered nor shared; a rebuild makes a new geometry.
//
// A big mesh that allows refit is clustered (ClusterPolicy, clustered_blas.h): its BLAS scene
// holds one REFIT-quality geometry per cluster instead of one for the whole mesh, so a vertex
// edit refits the clusters it touches. Hits on it report a cluster and a triangle within it;
// mesh_triangle() maps them back to the mesh's own numbering.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "engine/accel/blas_pool.h"
#include "engine/accel/cluster_layout.h"
#include "engine/accel/clustered_blas.h"
#include "engine/accel/embree_device.h"
#include "engine/accel/refit_policy.h"
#include "engine/accel/report.h"
#include "engine/core/handle.h"
#include "engine/core/result.h"
#include "engine/scene/scene.h"

struct RTCSceneTy;
struct RTCGeometryTy;

namespace strata {

/// State of one built BLAS.
struct BlasRecord {
    std::string mesh_id;  ///< kept for reports after the mesh itself is removed
    RTCSceneTy* scene = nullptr;
    RTCGeometryTy* geometry = nullptr;             ///< the whole mesh; null when clustered
    std::unique_ptr<ClusteredBlas> clusters;       ///< the clusters; null when not clustered
    uint32_t generation = 0;  ///< generation of the mesh handle it was built for
    uint32_t vertex_count = 0;
    uint32_t triangle_count = 0;
    uint32_t keys = 1;  ///< the whole geometry's time steps (MeshRecord::motion_keys)
    BuildOptions options;
    BuildBaseline baseline;  ///< drift reference for the refit policy
    int64_t bytes = 0;       ///< Embree memory its builds and refits allocated (not shared)
    /// For a compacted BLAS: its memory at full size, measured at its last build (0 otherwise).
    int64_t uncompacted_bytes = 0;
    /// The pooled BLAS it holds (scene and geometry are its), or null (blas_pool.h).
    std::shared_ptr<SharedBlas> shared;
    bool adopted = false;  ///< its last build held another engine's BLAS instead of building
};

/// One compacted BLAS's memory before and after compaction.
struct CompactedBlas {
    std::string mesh;
    int64_t uncompacted_bytes = 0;
    int64_t bytes = 0;
};

/// Every compacted BLAS of a store, and their sums.
struct CompactionSummary {
    std::vector<CompactedBlas> meshes;  ///< in mesh slot order
    CompactionTotals totals;
};

class BlasStore {
public:
    /// `watertight` adds Embree's robust flag to every BLAS (see AccelConfig::watertight);
    /// `context_filter` lets an intersect context's filter see their hits (the incremental TLAS
    /// skips stale instance copies that way, and launches apply HitTests).
    BlasStore(EmbreeDevice& device, bool watertight, bool context_filter = false,
              const ClusterPolicy& clusters = {})
        : m_device(device),
          m_watertight(watertight),
          m_context_filter(context_filter),
          m_cluster_policy(clusters) {}
    ~BlasStore();
    BlasStore(const BlasStore&) = delete;
    BlasStore& operator=(const BlasStore&) = delete;

    /// The BLAS built for exactly this mesh handle, or nullptr.
    const BlasRecord* find(MeshHandle h) const;
    /// The Embree scene of the BLAS in `slot`, or nullptr.
    RTCSceneTy* scene(uint32_t slot) const;

    /// Builds (or rebuilds from scratch) the BLAS of `mesh` from its current data, as clusters
    /// when `clustered` (which may_cluster must allow). A BLAS left in the slot by an older mesh
    /// is released first.
    Status build(MeshHandle h, const MeshRecord& mesh, const MeshMetrics& metrics,
                 bool clustered = false);
    /// Refits the BLAS of `mesh` after uploading its dirty vertex ranges; a clustered BLAS
    /// refits (and rebuilds) the clusters `work` names.
    Status refit(MeshHandle h, const MeshRecord& mesh, ClusterWork* work = nullptr);

    /// Whether `mesh` may have a clustered BLAS (big enough, refit allowed, not compacted).
    bool may_cluster(const MeshRecord& mesh) const {
        return mesh.kind == MeshKind::Triangles && mesh.build.allow_refit &&
               !mesh.build.compact && mesh.motion_positions.empty() &&
               m_cluster_policy.clusters(mesh.triangles.size());
    }
    /// The Embree memory `r` counts in this store's device: a shared BLAS's is its owner's.
    int64_t bytes_of(const BlasRecord& r) const;
    /// Whether `r`'s BLAS may not change in place: shared with another engine that holds it,
    /// or held it once (blas_pool.h). A change to its mesh builds a copy.
    bool frozen(const BlasRecord& r) const;
    /// True when some live BLAS is clustered: hits need mesh_triangle().
    bool any_clustered() const { return m_clustered != 0; }
    /// The mesh's own triangle index of a hit on BLAS `slot` (geomID `geom`, primID `prim`).
    uint32_t mesh_triangle(uint32_t slot, uint32_t geom, uint32_t prim) const {
        const ClusteredBlas* c = slot < m_records.size() ? m_records[slot].clusters.get() : nullptr;
        return c ? c->mesh_triangle(geom, prim) : prim;
    }
    /// Frees the BLAS in the slot of `h` if it belongs to `h`; returns whether it did.
    bool release(MeshHandle h);
    /// Frees the BLASes build() replaced in a slot (a new mesh in a removed mesh's slot, new
    /// build options). They are kept until now because TLAS instances may still reference them:
    /// Embree would free them when the TLAS lets go, in the TLAS's memory phase, and the memory
    /// report would go negative there. Call after the TLAS work, as the commit does.
    void release_retired();

    /// Moves whenever a compacted BLAS is built, refit or freed: compaction() changed.
    uint64_t compaction_version() const { return m_compaction_version; }
    /// The compacted BLASes now (walks every slot: call when compaction_version() moved).
    CompactionSummary compaction() const;

private:
    void release_slot(uint32_t slot, bool account = true);
    void release_record(BlasRecord& r, bool account);
    void retire_slot(uint32_t slot);
    /// Swaps the record's geometry for clusters of `mesh`, or back (the scene object stays, so
    /// instances keep referencing it).
    void set_layout(BlasRecord& r, const MeshRecord& mesh, bool clustered);
    /// Uploads a points or curve mesh whole into its (new) geometry.
    void upload_points_or_curves(BlasRecord& r, const MeshRecord& mesh);
    /// Uploads the whole mesh into the record's single geometry and commits it.
    void upload_whole(BlasRecord& r, const MeshRecord& mesh, uint32_t vertex_count,
                      uint32_t triangle_count);
    /// The Embree scene flags of a BLAS with `options`, with or without the compact layout.
    int scene_flags(const BuildOptions& options, bool compact) const;
    /// Holds `blas` (another engine's, of `mesh`'s content) in `r`, for mesh handle `h`.
    void adopt(BlasRecord& r, const std::shared_ptr<SharedBlas>& blas, MeshHandle h,
               const MeshRecord& mesh);
    /// Publishes `r`'s freshly built whole BLAS in the pool under `key`.
    void publish(BlasRecord& r, uint64_t key, int flags);
    /// Rebuilds the record's freshly built whole-mesh BVH in the compact layout; the full build's
    /// size (`bytes_before` the build started) becomes its uncompacted size. `indexed`: the
    /// geometry has an index buffer (points have none).
    void compact(BlasRecord& r, int64_t bytes_before, bool indexed);

    EmbreeDevice& m_device;
    bool m_watertight;
    bool m_context_filter;
    ClusterPolicy m_cluster_policy;
    uint32_t m_clustered = 0;  ///< records in m_records with clusters
    uint64_t m_compaction_version = 0;
    std::vector<BlasRecord> m_records;  ///< indexed by mesh slot
    std::vector<BlasRecord> m_retired;  ///< replaced by build(), freed by release_retired()
};

/// Bounds and triangle-box areas of a mesh's current positions (parallel over large meshes).
MeshMetrics measure_mesh(const MeshRecord& mesh);

}  // namespace strata
