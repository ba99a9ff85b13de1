#pragma once
// The Embree side of a clustered BLAS: one triangle geometry per cluster of a ClusterLayout, all
// in the mesh's BLAS scene, sharing one vertex buffer and slices of one index buffer. The scene
// has build quality LOW, so Embree's two-level builder rebuilds (or refits) only the clusters
// whose geometry was committed since the last scene commit, then the BVH over the clusters:
// deforming k clusters costs their refits plus that top level, not the whole mesh.
//
// A hit reports the cluster as its geomID and the triangle within the cluster as its primID;
// mesh_triangle() turns the pair back into the mesh's own triangle index.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "engine/accel/cluster_layout.h"
#include "engine/accel/refit_policy.h"
#include "engine/scene/scene.h"

struct RTCDeviceTy;
struct RTCSceneTy;
struct RTCGeometryTy;
struct RTCBufferTy;

namespace strata {

/// What local topology edits (TriangleSplices) do to the clusters: those that held a replaced
/// triangle or take a new one are re-made with the members listed (mesh triangles, numbered as
/// after the edits), and their BVHs rebuilt.
struct ClusterSplice {
    TriangleSplices runs;
    std::vector<uint32_t> clusters;  ///< ascending
    std::vector<std::vector<uint32_t>> members;  ///< parallel to `clusters`
    std::vector<ClusterMetrics> metrics;         ///< parallel to `clusters`
    uint64_t triangles = 0;  ///< triangles in the re-made clusters

    bool empty() const { return runs.empty(); }
};

/// Sums of the clusters' box areas and triangle areas, now and at their builds: what the
/// whole-layout decision compares.
struct LayoutMetrics {
    MeshMetrics now;
    MeshMetrics built;
};

/// What a commit does to a clustered BLAS whose positions or triangles changed: planned without
/// touching Embree, carried out by ClusteredBlas::refit.
struct ClusterWork {
    /// The decision over all clusters: `whole.rebuild` when their drift taken together calls for
    /// a new layout (the whole BLAS is rebuilt), with its reason and detail.
    RefitDecision whole;
    std::vector<uint32_t> refit;       ///< clusters refit in place
    std::vector<uint32_t> rebuild;     ///< clusters whose own BVH is rebuilt (their drift)
    std::vector<ClusterMetrics> refit_metrics;    ///< parallel to `refit`, measured at planning
    std::vector<ClusterMetrics> rebuild_metrics;  ///< parallel to `rebuild`
    uint64_t refit_triangles = 0;
    uint64_t rebuild_triangles = 0;
    ClusterSplice splice;  ///< a local topology edit's clusters (empty: none)
};

class ClusteredBlas {
public:
    /// Creates the cluster geometries of `mesh` in `scene` (uncommitted: the caller commits the
    /// scene). `geometry_quality` is an RTCBuildQuality.
    ClusteredBlas(RTCDeviceTy* device, RTCSceneTy* scene, const MeshRecord& mesh,
                  uint32_t cluster_size, int geometry_quality);
    /// Detaches and releases the cluster geometries and buffers.
    ~ClusteredBlas();
    ClusteredBlas(const ClusteredBlas&) = delete;
    ClusteredBlas& operator=(const ClusteredBlas&) = delete;

    uint32_t cluster_count() const { return m_layout.cluster_count(); }
    /// The mesh's own triangle index of a hit on triangle `prim` of cluster `geom`.
    uint32_t mesh_triangle(uint32_t geom, uint32_t prim) const {
        return m_layout.mesh_triangle(geom, prim);
    }

    /// Which clusters a commit of `mesh`'s current positions and triangles refits or rebuilds.
    /// `asked` is PositionsChanged (the clusters its dirty vertices touch), TrianglesReplaced
    /// (the clusters of its dirty triangles, and of its dirty vertices) or RefitRequested (all).
    ClusterWork plan(const MeshRecord& mesh, const RefitPolicy& policy,
                     const ClusterPolicy& clusters, BuildReason asked) const;
    /// Re-makes the clusters of `work`'s splice, uploads the dirty vertices and commits the
    /// clusters of `work` (the caller commits the scene).
    void refit(const MeshRecord& mesh, ClusterWork& work);

private:
    /// Cluster `c`'s triangles as Embree reads them.
    const Triangle* triangles_of(uint32_t c) const;
    /// Which clusters a local topology edit re-makes, and with what (work.whole.rebuild when the
    /// edit is too big for that).
    void plan_splice(const MeshRecord& mesh, const ClusterPolicy& clusters,
                     ClusterWork& work) const;
    /// The layout's sums, with `touched` measured now (`measured`) and the clusters `splice`
    /// re-makes (`remade`) counting as built now.
    LayoutMetrics layout_sums(std::span<const uint32_t> touched,
                              std::span<const ClusterMetrics> measured,
                              const ClusterSplice& splice,
                              const std::vector<uint8_t>& remade) const;
    /// The cluster new triangle `t` joins: the nearest (by its centroid's distance to their
    /// boxes) among those using its vertices, else among `losing`, else among all.
    uint32_t nearest_cluster(const MeshRecord& mesh, const Triangle& t,
                             std::span<const uint32_t> losing) const;
    /// Orders work.splice's clusters, measures them, or asks for a new layout (work.whole) when
    /// one would hold more than twice the cut size.
    void finish_splice(const MeshRecord& mesh, ClusterWork& work) const;
    /// Carries out `splice`: new index buffers for its clusters, the layout's numbering.
    void apply_splice(const MeshRecord& mesh, ClusterSplice& splice);

    RTCDeviceTy* m_device;
    RTCSceneTy* m_scene;
    ClusterLayout m_layout;
    RTCBufferTy* m_vertices = nullptr;
    RTCBufferTy* m_indices = nullptr;
    std::vector<RTCGeometryTy*> m_geometries;  ///< by cluster, attached by cluster index
    /// A re-made cluster's own index buffer (null: its slice of m_indices; or none, when empty).
    std::vector<RTCBufferTy*> m_own_indices;
    std::vector<ClusterMetrics> m_metrics;     ///< now
    std::vector<BuildBaseline> m_baselines;    ///< at each cluster's last build
};

}  // namespace strata
