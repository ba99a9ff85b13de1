#include "engine/accel/accel_graph.h"

#include <algorithm>

#include "engine/core/timer.h"

namespace strata {

Result<std::unique_ptr<AccelGraph>> AccelGraph::create(const AccelConfig& config) {
    if (config.shared_device)
        return std::unique_ptr<AccelGraph>(
            new AccelGraph(config, EmbreeDevice::view(config.shared_device)));
    auto device = EmbreeDevice::create(config.embree_config);
    if (!device) return Unexpected(device.error());
    return std::unique_ptr<AccelGraph>(new AccelGraph(config, std::move(device.value())));
}

AccelGraph::AccelGraph(const AccelConfig& config, std::unique_ptr<EmbreeDevice> device)
    : m_config(config),
      m_device(std::move(device)),
      // Every BLAS lets intersect-context filters see its hits: launches apply HitTests (alpha
      // cut-outs) with them under both strategies. A context without a filter costs nothing.
      m_blas(*m_device, config.watertight, true, config.clusters),
      m_tlas(config.tlas == TlasKind::Incremental
                 ? make_incremental_tlas(*m_device, config.tlas_prefer, config.watertight,
                                         config.tlas_policy)
                 : make_embree_tlas(*m_device, config.tlas_prefer, config.watertight)) {}

AccelGraph::~AccelGraph() {
    // Instances hold references to BLASes: drop the TLAS first.
    m_tlas.reset();
}

namespace {

/// What a commit does with one dirty mesh's BLAS, and why.
struct MeshAction {
    bool rebuild = true;
    bool clustered = false;  ///< a rebuild builds clusters
    MeshBuildEntry entry;
    std::optional<MeshMetrics> metrics;  ///< measured while deciding (whole meshes)
    ClusterWork clusters;                ///< a clustered refit's clusters
};

/// Decides the BLAS work for `mesh` (dirty with geometry bits), built as `built` (or not yet).
MeshAction decide(const MeshRecord& mesh, const BlasRecord* built, const BlasStore& blas,
                  const AccelConfig& config) {
    const DirtyBits<MeshDirty> dirty = mesh.dirty.bits;
    MeshAction a;
    a.entry.mesh = mesh.id;
    a.entry.primitives = mesh.primitive_count();
    // A rebuilt BLAS keeps its kind; a big whole one turns clustered at its first local edit.
    a.clustered = built && built->clusters && blas.may_cluster(mesh);
    if (!built) {
        a.entry.reason = BuildReason::Added;
    } else if (dirty.has(MeshDirty::Topology)) {
        a.entry.reason = BuildReason::TopologyChanged;
    } else if (dirty.has(MeshDirty::Keys)) {
        // Embree fixes a geometry's time steps when it is built: a new count is a new BVH.
        a.entry.reason = BuildReason::KeysChanged;
        a.entry.detail = "vertex keys " + std::string(mesh.motion_positions.empty()
                                                          ? "removed: the mesh is still"
                                                          : "added: the BVH bounds every key");
    } else if (dirty.has(MeshDirty::RebuildRequested)) {
        a.entry.reason = BuildReason::RebuildRequested;
    } else if (blas.frozen(*built)) {
        a.entry.reason = BuildReason::Unshared;
        a.entry.detail =
            "its BLAS is (or was) shared with another scene, which may still trace it: this "
            "one builds its own";
    } else if (mesh.kind != MeshKind::Triangles || mesh.motion_keys() > 1) {
        // Embree 3 builds sphere, curve and motion-blur BVHs with builders that have no refit
        // (only still triangle, quad, user and instance geometry refit): a move is a rebuild.
        a.entry.reason = dirty.has(MeshDirty::Points) ? BuildReason::PositionsChanged
                                                      : BuildReason::RefitRequested;
        a.entry.detail = mesh.kind != MeshKind::Triangles
                             ? std::string(mesh_kind_name(mesh.kind)) +
                                   ": Embree has no refit for them, so their BVH is rebuilt"
                             : "vertex keys: Embree has no refit for a motion-blur BVH, so it "
                               "is rebuilt";
    } else if (!built->clusters && dirty.has(MeshDirty::Triangles)) {
        // A whole BLAS has no smaller part to rebuild: a big one turns clustered at this first
        // local edit, others are rebuilt.
        const TriangleSplices& t = mesh.dirty.triangles;
        a.entry.detail = std::to_string(t.old_count()) + " triangles replaced by " +
                         std::to_string(t.new_count());
        a.clustered = blas.may_cluster(mesh) &&
                      config.clusters.local(t.old_count(), built->triangle_count) &&
                      config.clusters.local(t.new_count(), mesh.triangles.size());
        a.entry.reason = a.clustered ? BuildReason::Clustered : BuildReason::TopologyChanged;
        if (a.clustered)
            a.entry.detail += ": rebuilt as clusters, so local edits rebuild only the clusters "
                              "they touch";
    } else if (!built->clusters && blas.may_cluster(mesh) && dirty.has(MeshDirty::Points) &&
               config.clusters.local(mesh.dirty.points.count(), mesh.positions.size())) {
        a.entry.reason = BuildReason::Clustered;
        a.entry.detail = std::to_string(mesh.dirty.points.count()) + " of " +
                         std::to_string(mesh.positions.size()) +
                         " vertices in edited ranges: rebuilt as clusters, so local edits refit "
                         "only the clusters they touch";
        a.clustered = true;
    } else {
        const BuildReason asked = dirty.has(MeshDirty::Triangles) ? BuildReason::TrianglesReplaced
                                  : dirty.has(MeshDirty::Points)  ? BuildReason::PositionsChanged
                                                                  : BuildReason::RefitRequested;
        RefitDecision d;
        if (built->clusters) {
            // A clustered BLAS measures only the clusters the edit touches.
            a.clusters = built->clusters->plan(mesh, config.refit_policy, config.clusters, asked);
            d = a.clusters.whole;
        } else {
            a.metrics = measure_mesh(mesh);
            d = decide_refit(config.refit_policy, mesh.build, built->baseline, *a.metrics, asked);
        }
        a.rebuild = d.rebuild;
        a.entry.reason = d.reason;
        a.entry.detail = std::move(d.detail);
    }
    return a;
}

/// Adds `a` for mesh `h` to the plan and its report.
void record(MeshHandle h, const MeshRecord& mesh, const BlasRecord* built, MeshAction&& a,
            CommitPlan& plan) {
    RebuildReport& report = plan.report;
    if (a.rebuild) {
        // A clustered build's cluster count is known once its layout is: see execute().
        plan.rebuild.push_back(h);
        plan.rebuild_metrics.push_back(a.metrics);
        plan.rebuild_clustered.push_back(a.clustered);
        report.rebuilt.push_back(std::move(a.entry));
        report.primitives_built += mesh.primitive_count();
        return;
    }
    MeshBuildEntry& entry = a.entry;
    if (built->clusters) {
        const ClusterWork& work = a.clusters;
        entry.clusters = built->clusters->cluster_count();
        entry.clusters_refit = uint32_t(work.refit.size());
        entry.clusters_rebuilt = uint32_t(work.rebuild.size());
        entry.clusters_rebuilt += uint32_t(work.splice.clusters.size());
        entry.primitives = work.refit_triangles + work.rebuild_triangles + work.splice.triangles;
        if (!work.rebuild.empty())
            entry.detail += "; " + std::to_string(work.rebuild.size()) +
                            " clusters rebuilt past the refit policy's limits";
        report.clusters_refit += entry.clusters_refit;
        report.clusters_rebuilt += entry.clusters_rebuilt;
        report.primitives_refit += work.refit_triangles;
        report.primitives_built += work.rebuild_triangles + work.splice.triangles;
    } else {
        report.primitives_refit += mesh.primitive_count();
    }
    plan.refit.push_back(h);
    plan.refit_clusters.push_back(std::move(a.clusters));
    report.refit.push_back(std::move(entry));
}

/// Carries out the plan's BLAS builds and refits, one mesh at a time (each Embree build is
/// parallel inside), timing each into `report`.
Status build_and_refit(const Scene& scene, BlasStore& blas, CommitPlan& plan,
                       RebuildReport& report) {
    for (std::size_t i = 0; i < plan.rebuild.size(); ++i) {
        Stopwatch clock;
        const MeshRecord& mesh = *scene.mesh(plan.rebuild[i]).value();
        const MeshMetrics metrics =
            plan.rebuild_metrics[i] ? *plan.rebuild_metrics[i] : measure_mesh(mesh);
        if (Status s = blas.build(plan.rebuild[i], mesh, metrics, plan.rebuild_clustered[i]); !s)
            return s;
        MeshBuildEntry& entry = report.rebuilt[i];
        entry.ms = clock.ms();
        const BlasRecord& built = *blas.find(plan.rebuild[i]);
        entry.bytes = blas.bytes_of(built);
        if (built.adopted) {
            entry.reason = BuildReason::Shared;
            entry.detail = "identical to a BLAS another scene holds: held, not built";
            report.primitives_built -= mesh.primitive_count();
            --report.blas_rebuilds;
        }
        entry.uncompacted_bytes = built.uncompacted_bytes;
        if (const ClusteredBlas* c = built.clusters.get()) {
            entry.clusters = entry.clusters_rebuilt = c->cluster_count();
            report.clusters_rebuilt += entry.clusters;
        }
    }
    for (std::size_t i = 0; i < plan.refit.size(); ++i) {
        Stopwatch clock;
        const MeshRecord& mesh = *scene.mesh(plan.refit[i]).value();
        if (Status s = blas.refit(plan.refit[i], mesh, &plan.refit_clusters[i]); !s) return s;
        report.refit[i].ms = clock.ms();
    }
    return {};
}

}  // namespace

CommitPlan AccelGraph::plan(const Scene& scene) const {
    Stopwatch clock;
    CommitPlan plan;
    RebuildReport& report = plan.report;
    report.version = scene.version();
    report.planned = true;
    const ChangeTracker& changes = scene.changes();

    // Step: meshes. Each dirty mesh gets at most one BLAS action.
    constexpr DirtyBits<MeshDirty> GEOMETRY_BITS = MeshDirty::Added | MeshDirty::Points |
                                                   MeshDirty::Topology | MeshDirty::Triangles |
                                                   MeshDirty::RefitRequested |
                                                   MeshDirty::RebuildRequested |
                                                   MeshDirty::Keys;
    for (MeshHandle h : changes.meshes()) {
        const BlasRecord* built = m_blas.find(h);
        const auto rec = scene.mesh(h);
        if (!rec) {
            if (built) {
                plan.release.push_back(h);
                report.released.push_back(built->mesh_id);
            }
            continue;
        }
        const MeshRecord& mesh = *rec.value();
        if (!mesh.dirty.bits.has(GEOMETRY_BITS)) continue;
        record(h, mesh, built, decide(mesh, built, m_blas, m_config), plan);
        // Instances of a changed BLAS must have their bounds re-read by the TLAS.
        for (InstanceHandle user : mesh.users) {
            if (m_tlas->holds(user)) plan.tlas.blas_changed.push_back(user);
        }
    }
    report.blas_rebuilds = static_cast<uint32_t>(report.rebuilt.size());
    report.blas_refits = static_cast<uint32_t>(report.refit.size());

    // Step: instances. Shading-only changes (material, user id) need no TLAS work, and an
    // instance added and removed within the same commit window leaves nothing to do.
    for (InstanceHandle h : changes.instances()) {
        const auto rec = scene.instance(h);
        if (!rec) {
            if (m_tlas->holds(h)) plan.tlas.changed.push_back(h);
        } else if (rec.value()->dirty.has(INSTANCE_TLAS_BITS)) {
            plan.tlas.changed.push_back(h);
        }
    }

    // Step: TLAS action. An explicit rebuild request wins; otherwise any change is one update.
    if (changes.has(SceneDirty::TlasRebuildRequested)) {
        report.tlas_action = TlasAction::Rebuild;
    } else if (!plan.tlas.empty() || changes.has(SceneDirty::TlasUpdateRequested)) {
        report.tlas_action = TlasAction::Update;
    }
    report.tlas_instances = scene.instances().size();
    report.world_transforms = changes.world_transforms();
    report.instances_changed = plan.tlas.changed.size() + plan.tlas.blas_changed.size();
    report.tlas.strategy = m_tlas->name();
    report.phases.plan_ms = clock.ms();
    return plan;
}

Result<RebuildReport> AccelGraph::execute(const Scene& scene, CommitPlan&& plan) {
    Stopwatch total;
    RebuildReport report = std::move(plan.report);
    report.planned = false;

    // Step: BLAS builds and refits, one mesh at a time (each Embree build is parallel inside).
    // Background TLAS work that reads BLASes stops first if any existing BLAS is about to change.
    Stopwatch blas_clock;
    const bool existing_blas_changes =
        !plan.refit.empty() || !plan.release.empty() ||
        std::any_of(report.rebuilt.begin(), report.rebuilt.end(),
                    [](const MeshBuildEntry& e) { return e.reason != BuildReason::Added; });
    if (existing_blas_changes) {
        MemoryScope memory(*m_device, MemoryCategory::Tlas);
        m_tlas->before_blas_changes();
    }
    {
        MemoryScope memory(*m_device, MemoryCategory::Blas);
        if (Status s = build_and_refit(scene, m_blas, plan, report); !s)
            return Unexpected(s.error());
    }
    report.phases.blas_ms = blas_clock.ms();

    // Step: TLAS work.
    Stopwatch tlas_clock;
    if (report.tlas_action == TlasAction::Rebuild) {
        if (Status s = m_tlas->rebuild(scene, m_blas); !s) return Unexpected(s.error());
    } else if (report.tlas_action == TlasAction::Update) {
        if (Status s = m_tlas->update(scene, m_blas, plan.tlas); !s) return Unexpected(s.error());
    }
    report.phases.tlas_ms = tlas_clock.ms();
    report.tlas_instances = m_tlas->instance_count();
    report.tlas = m_tlas->tiers_report();

    // Step: BLAS releases, after the TLAS has dropped the instances that still referenced them
    // (Embree frees a BLAS only with its last reference).
    blas_clock.restart();
    {
        MemoryScope memory(*m_device, MemoryCategory::Blas);
        for (MeshHandle h : plan.release) m_blas.release(h);
        m_blas.release_retired();
    }
    report.phases.blas_ms += blas_clock.ms();

    report.memory_blas_bytes = m_device->bytes(MemoryCategory::Blas);
    report.memory_tlas_bytes = m_device->bytes(MemoryCategory::Tlas);
    report.phases.total_ms = report.phases.plan_ms + total.ms();
    return report;
}

}  // namespace strata

namespace strata {

void AccelGraph::maintain(RebuildReport& report) {
    Stopwatch clock;
    {
        MemoryScope memory(*m_device, MemoryCategory::Tlas);
        if (m_tlas->maintain()) report.phases.tlas_ms = clock.ms();
    }
    report.tlas = m_tlas->tiers_report();
}

}  // namespace strata
