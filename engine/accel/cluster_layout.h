#pragma once
// How a big mesh is cut into clusters for a clustered BLAS (blas_store.h): its triangles sorted
// by the Morton code of their centroids, the sorted run split at Morton cell boundaries until
// each piece holds at most `cluster_size` triangles, then neighbouring small pieces merged up to
// that size. Each cluster is a compact patch of the surface, and clusters overlap little. A vertex edit then costs the clusters it touches, found through
// a vertex-to-cluster map (a vertex on a seam belongs to every cluster that uses it).
//
// Pure data: no Embree. The BLAS store turns each cluster into one Embree geometry.

#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/types.h"
#include "engine/scene/vertex_ranges.h"

namespace strata {

/// When a mesh's BLAS is clustered, and how big its clusters are. A mesh is built whole; the
/// first local edit of a big one (a vertex edit that moves at most `local_fraction` of its
/// vertices) rebuilds it as clusters, and it stays clustered. So meshes that are never edited
/// locally keep a whole BVH, which traces faster (tests/bench/NOTES.md, "Clustered BLAS").
/// Embree rebuilds the BVH over the clusters at every commit, so a cluster edit costs that top
/// level plus the clusters' refits: about sqrt(triangles) clusters balance the two.
struct ClusterPolicy {
    /// Meshes with fewer triangles stay one geometry; 0 turns clustering off.
    uint32_t min_triangles = 65536;
    /// A vertex edit moving at most this fraction of a mesh's vertices is local.
    double local_fraction = 0.5;
    /// Cluster size is `size_factor * sqrt(triangles)`, clamped to [min_size, max_size].
    double size_factor = 2.0;
    uint32_t min_size = 256;
    uint32_t max_size = 65536;

    /// Whether a mesh of `triangles` triangles may get a clustered BLAS.
    bool clusters(std::size_t triangles) const {
        return min_triangles != 0 && triangles >= min_triangles;
    }
    /// Whether moving `moved` of a mesh's `vertices` vertices is a local edit.
    bool local(uint64_t moved, std::size_t vertices) const {
        return double(moved) <= local_fraction * double(vertices);
    }
    /// Triangles per cluster for a mesh of `triangles` triangles.
    uint32_t cluster_size(std::size_t triangles) const;

    friend bool operator==(const ClusterPolicy&, const ClusterPolicy&) = default;
};

/// Drift measurements of one cluster (the refit policy's, per cluster).
struct ClusterMetrics {
    Bounds3 bounds;
    float triangle_area = 0.0f;  ///< sum of the surface areas of its triangles' boxes
};

class ClusterLayout {
public:
    /// Sorts `triangles` (indices into `positions`) into clusters of at most `cluster_size`.
    ClusterLayout(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                  uint32_t cluster_size);

    uint32_t cluster_count() const { return static_cast<uint32_t>(m_first.size() - 1); }
    uint32_t triangle_count() const { return static_cast<uint32_t>(m_order.size()); }
    /// Position in sorted order of cluster `c`'s first triangle, and its triangle count.
    uint32_t first(uint32_t c) const { return m_first[c]; }
    uint32_t size(uint32_t c) const { return m_first[c + 1] - m_first[c]; }
    /// The mesh's own index of triangle `prim` of cluster `cluster` (a hit's ids).
    uint32_t mesh_triangle(uint32_t cluster, uint32_t prim) const {
        return m_order[first(cluster) + prim];
    }
    /// The clusters that use vertex `v` (none for an unreferenced vertex).
    std::span<const uint32_t> clusters_of(uint32_t v) const {
        return {m_vertex_clusters.data() + m_vertex_offsets[v],
                m_vertex_clusters.data() + m_vertex_offsets[v + 1]};
    }
    /// The clusters that use a vertex in `ranges`, ascending, each once.
    std::vector<uint32_t> touched(const VertexRanges& ranges) const;

    /// Copies the triangles in sorted order (the clusters one after another) to `out`.
    void write_sorted(std::span<const Triangle> triangles, Triangle* out) const;
    /// Measures cluster `c` at `positions`; `sorted` holds the triangles in sorted order (what
    /// write_sorted wrote), so the cluster's triangles are read in one run.
    ClusterMetrics measure(uint32_t c, std::span<const Vec3> positions,
                           const Triangle* sorted) const;

private:
    /// Fills m_first from the sorted (code << 32 | triangle) keys.
    void cut(const std::vector<uint64_t>& keys, uint32_t max_size);

    std::vector<uint32_t> m_first;            ///< cluster -> first sorted position; one past the end
    std::vector<uint32_t> m_order;            ///< sorted position -> mesh triangle
    std::vector<uint32_t> m_vertex_offsets;   ///< vertex -> its run in m_vertex_clusters
    std::vector<uint32_t> m_vertex_clusters;  ///< clusters by vertex, ascending per vertex
};

}  // namespace strata
