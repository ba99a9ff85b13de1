#pragma once
// The acceleration graph: BLAS per mesh, one TLAS over instances, and the commit that brings them
// in line with the scene doing the least work. A commit is planned first (pure: which BLASes to
// rebuild, refit or release and what the TLAS needs, with reasons), then executed. GET /v1/plan
// shows the plan without executing it.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "engine/accel/blas_store.h"
#include "engine/accel/embree_device.h"
#include "engine/accel/refit_policy.h"
#include "engine/accel/report.h"
#include "engine/accel/tlas.h"
#include "engine/scene/scene.h"

namespace strata {

struct AccelConfig {
    RefitPolicy refit_policy;
    TlasKind tlas = TlasKind::Incremental;
    TlasPolicy tlas_policy;  ///< for TlasKind::Incremental
    BuildPreference tlas_prefer = BuildPreference::FastTrace;
    /// Watertight ray/triangle tests (Embree's robust mode): a ray through a vertex or edge
    /// shared by several triangles never slips between them. It costs some trace speed (see
    /// tests/bench/NOTES.md); turn off only where a rare hole is acceptable.
    bool watertight = true;
    std::string embree_config;  ///< Embree device configuration string
    ClusterPolicy clusters;     ///< which meshes get a clustered BLAS
    /// An Embree device shared with other engines, whose identical BLASes this engine may hold
    /// (blas_pool.h); null: a device of its own (embree_config). Engines on one device take
    /// turns in their commits' Embree phases (embree_device.h).
    std::shared_ptr<SharedEmbree> shared_device;
};

/// A planned commit. The handle vectors run parallel to the report's entry lists.
struct CommitPlan {
    RebuildReport report;
    std::vector<MeshHandle> rebuild;
    std::vector<std::optional<MeshMetrics>> rebuild_metrics;  ///< measured while planning, if so
    std::vector<bool> rebuild_clustered;  ///< parallel to `rebuild`: build as clusters
    std::vector<MeshHandle> refit;
    std::vector<ClusterWork> refit_clusters;  ///< parallel to `refit`; empty for whole meshes
    std::vector<MeshHandle> release;
    TlasDelta tlas;
};

class AccelGraph {
public:
    static Result<std::unique_ptr<AccelGraph>> create(const AccelConfig& config);
    ~AccelGraph();

    /// What a commit of `scene`'s current changes would do. Makes no Embree call.
    CommitPlan plan(const Scene& scene) const;
    /// Carries out `plan`, made against the same scene state. Fills in times and memory.
    Result<RebuildReport> execute(const Scene& scene, CommitPlan&& plan);
    /// A commit with no scene changes: lets the TLAS swap in finished background work. Fills
    /// `report.tlas` (and the TLAS time when it did something).
    void maintain(RebuildReport& report);
    /// Waits for the TLAS's background work (tests and benchmarks).
    void wait_for_background() { m_tlas->wait_for_background(); }

    const TlasStrategy& tlas() const { return *m_tlas; }
    const BlasStore& blas() const { return m_blas; }
    const RefitPolicy& refit_policy() const { return m_config.refit_policy; }
    void set_refit_policy(const RefitPolicy& p) { m_config.refit_policy = p; }

    int64_t memory_bytes(MemoryCategory c) const { return m_device->bytes(c); }
    /// Any Embree error raised since the last check (for example while tracing), as a Status.
    Status device_status(const char* what) { return m_device->status(what); }

private:
    AccelGraph(const AccelConfig& config, std::unique_ptr<EmbreeDevice> device);

    AccelConfig m_config;
    std::unique_ptr<EmbreeDevice> m_device;
    BlasStore m_blas;
    std::unique_ptr<TlasStrategy> m_tlas;
};

}  // namespace strata
