#pragma once
// How a big mesh is cut into clusters for a clustered BLAS (blas_store.h): its triangles sorted
// by the Morton code of their centroids, the sorted run split at Morton cell boundaries until
// each piece holds at most `cluster_size` triangles, then neighbouring small pieces merged up to
// that size. Each cluster is a compact patch of the surface, and clusters overlap little. A vertex edit then costs the clusters it touches, found through
// a vertex-to-cluster map (a vertex on a seam belongs to every cluster that uses it).
//
// Pure data: no Embree. The BLAS store turns each cluster into one Embree geometry.

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/math.h"
#include "engine/scene/dirty.h"
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

/// Adds triangle `t` at `positions` to `m`.
inline void measure_into(ClusterMetrics& m, std::span<const Vec3> positions, const Triangle& t) {
    Bounds3 b;
    b.extend(positions[t.x]);
    b.extend(positions[t.y]);
    b.extend(positions[t.z]);
    m.triangle_area += b.surface_area();
    m.bounds.extend(b);
}

class ClusterLayout {
public:
    /// Sorts `triangles` (indices into `positions`) into clusters of at most `cluster_size`.
    ClusterLayout(std::span<const Vec3> positions, std::span<const Triangle> triangles,
                  uint32_t cluster_size);

    uint32_t cluster_count() const { return static_cast<uint32_t>(m_size.size()); }
    uint32_t triangle_count() const { return m_triangle_count; }
    /// The size the clusters were cut to.
    uint32_t cut_size() const { return m_cut_size; }
    /// Cluster `c`'s triangle count.
    uint32_t size(uint32_t c) const { return m_size[c]; }
    /// Whether cluster `c` is still the run of the sorted order it was cut as (no splice has
    /// re-made it), and that run's first position.
    bool in_place(uint32_t c) const { return !m_remade[c]; }
    uint32_t first(uint32_t c) const { return m_first[c]; }
    /// The mesh's own index of triangle `prim` of cluster `cluster` (a hit's ids).
    uint32_t mesh_triangle(uint32_t cluster, uint32_t prim) const { return m_ids[cluster][prim]; }
    /// Cluster `c`'s triangles, as the mesh numbers them, in the cluster's own order.
    std::span<const uint32_t> members(uint32_t c) const { return {m_ids[c], m_size[c]}; }
    /// Calls `f(cluster)` for each cluster that uses vertex `v` (a cluster may come twice).
    template <class F>
    void for_each_cluster_of(uint32_t v, F&& f) const {
        for (uint32_t k = m_vertex_offsets[v]; k < m_vertex_offsets[v + 1]; ++k)
            f(m_vertex_clusters[k]);
        auto it = std::lower_bound(m_extra.begin(), m_extra.end(), uint64_t(v) << 32);
        for (; it != m_extra.end() && uint32_t(*it >> 32) == v; ++it) f(uint32_t(*it));
    }
    /// The clusters that use a vertex in `ranges`, ascending, each once.
    std::vector<uint32_t> touched(const VertexRanges& ranges) const;
    /// The clusters holding a triangle that one of `splices`' runs replaced, ascending.
    std::vector<uint32_t> holding(const TriangleSplices& splices) const;

    /// Copies the triangles in sorted order (the clusters one after another) to `out`.
    void write_sorted(std::span<const Triangle> triangles, Triangle* out) const;
    /// Measures the `count` triangles at `tris` (one cluster's) at `positions`.
    static ClusterMetrics measure(std::span<const Vec3> positions, const Triangle* tris,
                                  uint32_t count);

    /// A local topology edit: clusters[i] now holds members[i] (mesh triangles, numbered as
    /// now); every other cluster's triangles are renumbered by `renumber`. `triangles` are the
    /// mesh's triangles now.
    void splice(const TriangleRenumbering& renumber, std::span<const uint32_t> clusters,
                std::vector<std::vector<uint32_t>>&& members, std::span<const Triangle> triangles,
                std::size_t vertex_count);

private:
    /// Fills m_first from the sorted (code << 32 | triangle) keys.
    void cut(const std::vector<uint64_t>& keys, uint32_t max_size);
    /// Rebuilds the vertex-to-cluster map from the clusters' members (m_extra emptied).
    void map_vertices(std::span<const Triangle> triangles, std::size_t vertex_count);

    uint32_t m_cut_size = 0;
    uint32_t m_triangle_count = 0;
    std::vector<uint32_t> m_first;   ///< cluster -> first sorted position; one past the end
    std::vector<uint32_t> m_order;   ///< sorted position -> mesh triangle (clusters in place)
    std::vector<uint32_t> m_size;    ///< cluster -> triangle count
    std::vector<uint8_t> m_remade;   ///< cluster -> re-made by a splice (its ids in m_own)
    std::vector<std::vector<uint32_t>> m_own;  ///< re-made clusters' triangles
    std::vector<uint32_t*> m_ids;    ///< cluster -> its triangles (into m_order or m_own)
    std::vector<uint32_t> m_vertex_offsets;   ///< vertex -> its run in m_vertex_clusters
    std::vector<uint32_t> m_vertex_clusters;  ///< clusters by vertex, ascending per vertex
    /// (vertex << 32 | cluster) pairs splices added since the map was built, sorted: a vertex
    /// a new triangle uses. Entries a splice made stale only cost a cluster measured in vain.
    std::vector<uint64_t> m_extra;
};

}  // namespace strata
