#include "engine/accel/clustered_blas.h"

#include <cstring>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace strata {

namespace {

MeshMetrics as_mesh_metrics(const ClusterMetrics& m) {
    return {double(m.bounds.surface_area()), double(m.triangle_area)};
}

void add(MeshMetrics& sum, const ClusterMetrics& m) {
    sum.bounds_area += double(m.bounds.surface_area());
    sum.triangle_area += double(m.triangle_area);
}

/// Sums of the clusters' box areas and triangle areas: what the whole-layout decision compares.
struct LayoutMetrics {
    MeshMetrics now;
    MeshMetrics built;
};

std::vector<ClusterMetrics> measure_clusters(const ClusterLayout& layout,
                                             const std::vector<uint32_t>& clusters,
                                             const MeshRecord& mesh, RTCBuffer sorted) {
    std::vector<ClusterMetrics> out(clusters.size());
    const auto* triangles = static_cast<const Triangle*>(rtcGetBufferData(sorted));
    auto measure = [&](std::size_t i) {
        out[i] = layout.measure(clusters[i], mesh.positions, triangles);
    };
    if (clusters.size() < 4) {
        for (std::size_t i = 0; i < clusters.size(); ++i) measure(i);
        return out;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, clusters.size(), 2),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) measure(i);
                      });
    return out;
}

void copy_ranges(RTCBuffer buffer, const MeshRecord& mesh) {
    auto* dst = static_cast<Vec3*>(rtcGetBufferData(buffer));
    const auto n = static_cast<uint32_t>(mesh.positions.size());
    for (const VertexRanges::Range& r : mesh.dirty.points.ranges()) {
        const uint32_t end = std::min(r.end, n);
        if (r.begin < end)
            std::memcpy(dst + r.begin, mesh.positions.data() + r.begin,
                        std::size_t(end - r.begin) * sizeof(Vec3));
    }
}

}  // namespace

ClusteredBlas::ClusteredBlas(RTCDeviceTy* device, RTCSceneTy* scene, const MeshRecord& mesh,
                             uint32_t cluster_size, int geometry_quality)
    : m_scene(scene), m_layout(mesh.positions, mesh.triangles, cluster_size) {
    static_assert(sizeof(Vec3) == 3 * sizeof(float));
    static_assert(sizeof(Triangle) == 3 * sizeof(uint32_t));
    const std::size_t vertices = mesh.positions.size();
    const std::size_t triangles = mesh.triangles.size();
    // Step: the shared buffers. Embree reads vertices with 16-byte loads, so the last one needs
    // four bytes of padding.
    m_vertices = rtcNewBuffer(device, vertices * sizeof(Vec3) + sizeof(float));
    m_indices = rtcNewBuffer(device, triangles * sizeof(Triangle));
    if (!m_vertices || !m_indices) return;  // the device reports the error
    std::memcpy(rtcGetBufferData(m_vertices), mesh.positions.data(), vertices * sizeof(Vec3));
    m_layout.write_sorted(mesh.triangles, static_cast<Triangle*>(rtcGetBufferData(m_indices)));

    // Step: one geometry per cluster over its slice of the index buffer.
    const uint32_t count = m_layout.cluster_count();
    m_geometries.resize(count, nullptr);
    for (uint32_t c = 0; c < count; ++c) {
        RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        if (!g) return;
        m_geometries[c] = g;
        rtcSetGeometryBuildQuality(g, RTCBuildQuality(geometry_quality));
        rtcSetGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, m_vertices, 0,
                             sizeof(Vec3), vertices);
        rtcSetGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m_indices,
                             std::size_t(m_layout.first(c)) * sizeof(Triangle), sizeof(Triangle),
                             m_layout.size(c));
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(scene, g, c);
    }

    // Step: every cluster's drift baseline.
    std::vector<uint32_t> all(count);
    for (uint32_t c = 0; c < count; ++c) all[c] = c;
    m_metrics = measure_clusters(m_layout, all, mesh, m_indices);
    m_baselines.resize(count);
    for (uint32_t c = 0; c < count; ++c) m_baselines[c] = {as_mesh_metrics(m_metrics[c]), 0};
}

ClusteredBlas::~ClusteredBlas() {
    for (uint32_t c = 0; c < m_geometries.size(); ++c) {
        if (!m_geometries[c]) continue;
        rtcDetachGeometry(m_scene, c);
        rtcReleaseGeometry(m_geometries[c]);
    }
    if (m_vertices) rtcReleaseBuffer(m_vertices);
    if (m_indices) rtcReleaseBuffer(m_indices);
}

ClusterWork ClusteredBlas::plan(const MeshRecord& mesh, const RefitPolicy& policy,
                                BuildReason asked) const {
    ClusterWork work;
    // Step: the clusters the edit touches, measured at their new positions.
    std::vector<uint32_t> touched;
    if (asked == BuildReason::RefitRequested) {
        touched.resize(cluster_count());
        for (uint32_t c = 0; c < cluster_count(); ++c) touched[c] = c;
    } else {
        touched = m_layout.touched(mesh.dirty.points);
    }
    const std::vector<ClusterMetrics> measured =
        measure_clusters(m_layout, touched, mesh, m_indices);

    // Step: the layout as a whole. Clusters that drift apart overlap, which a refit of each
    // cannot mend: past the mesh's limits on the summed box areas, the mesh is re-clustered.
    LayoutMetrics sums;
    std::vector<uint8_t> is_touched(cluster_count(), 0);
    for (std::size_t i = 0; i < touched.size(); ++i) {
        is_touched[touched[i]] = 1;
        add(sums.now, measured[i]);
    }
    for (uint32_t c = 0; c < cluster_count(); ++c) {
        sums.built.bounds_area += m_baselines[c].metrics.bounds_area;
        sums.built.triangle_area += m_baselines[c].metrics.triangle_area;
        if (is_touched[c]) continue;
        add(sums.now, m_metrics[c]);
    }
    work.whole = decide_refit(policy, mesh.build, BuildBaseline{sums.built, 0}, sums.now, asked);
    work.whole.detail = "clusters' " + work.whole.detail;
    if (work.whole.rebuild) return work;

    // Step: each touched cluster against its own baseline, as a mesh would be.
    for (std::size_t i = 0; i < touched.size(); ++i) {
        const uint32_t c = touched[i];
        const RefitDecision d =
            decide_refit(policy, mesh.build, m_baselines[c], as_mesh_metrics(measured[i]), asked);
        if (d.rebuild) {
            work.rebuild.push_back(c);
            work.rebuild_metrics.push_back(measured[i]);
            work.rebuild_triangles += m_layout.size(c);
        } else {
            work.refit.push_back(c);
            work.refit_metrics.push_back(measured[i]);
            work.refit_triangles += m_layout.size(c);
        }
    }
    return work;
}

void ClusteredBlas::refit(const MeshRecord& mesh, const ClusterWork& work) {
    copy_ranges(m_vertices, mesh);
    for (std::size_t i = 0; i < work.refit.size(); ++i) {
        const uint32_t c = work.refit[i];
        rtcUpdateGeometryBuffer(m_geometries[c], RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(m_geometries[c]);
        m_metrics[c] = work.refit_metrics[i];
        ++m_baselines[c].refits_since_build;
    }
    for (std::size_t i = 0; i < work.rebuild.size(); ++i) {
        // A modified index buffer moves the geometry's topology version: Embree rebuilds the
        // cluster's BVH instead of refitting it.
        const uint32_t c = work.rebuild[i];
        rtcUpdateGeometryBuffer(m_geometries[c], RTC_BUFFER_TYPE_VERTEX, 0);
        rtcUpdateGeometryBuffer(m_geometries[c], RTC_BUFFER_TYPE_INDEX, 0);
        rtcCommitGeometry(m_geometries[c]);
        m_metrics[c] = work.rebuild_metrics[i];
        m_baselines[c] = {as_mesh_metrics(m_metrics[c]), 0};
    }
}

}  // namespace strata
