#include "engine/accel/clustered_blas.h"

#include <cstring>
#include <limits>

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

/// Measures `count` items in parallel when there are enough: out[i] = measure(i).
template <class F>
std::vector<ClusterMetrics> measure_each(std::size_t count, F&& measure) {
    std::vector<ClusterMetrics> out(count);
    if (count < 4) {
        for (std::size_t i = 0; i < count; ++i) out[i] = measure(i);
        return out;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 2),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = measure(i);
                      });
    return out;
}

/// Measures mesh triangles `ids` at the mesh's positions now.
ClusterMetrics measure_ids(const MeshRecord& mesh, std::span<const uint32_t> ids) {
    ClusterMetrics m;
    for (uint32_t id : ids) measure_into(m, mesh.positions, mesh.triangles[id]);
    return m;
}

/// Squared distance from `p` to box `b` (0 inside; infinite for an empty box).
float distance2(const Bounds3& b, const Vec3& p) {
    if (b.empty()) return std::numeric_limits<float>::infinity();
    const Vec3 d = glm::max(glm::max(b.lower - p, p - b.upper), Vec3(0.0f));
    return glm::dot(d, d);
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
    : m_device(device), m_scene(scene), m_layout(mesh.positions, mesh.triangles, cluster_size) {
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
    m_own_indices.resize(count, nullptr);
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
    m_metrics = measure_each(count, [&](std::size_t c) {
        return ClusterLayout::measure(mesh.positions, triangles_of(uint32_t(c)),
                                      m_layout.size(uint32_t(c)));
    });
    m_baselines.resize(count);
    for (uint32_t c = 0; c < count; ++c) m_baselines[c] = {as_mesh_metrics(m_metrics[c]), 0};
}

ClusteredBlas::~ClusteredBlas() {
    for (uint32_t c = 0; c < m_geometries.size(); ++c) {
        if (!m_geometries[c]) continue;
        rtcDetachGeometry(m_scene, c);
        rtcReleaseGeometry(m_geometries[c]);
    }
    for (RTCBuffer b : m_own_indices)
        if (b) rtcReleaseBuffer(b);
    if (m_vertices) rtcReleaseBuffer(m_vertices);
    if (m_indices) rtcReleaseBuffer(m_indices);
}

const Triangle* ClusteredBlas::triangles_of(uint32_t c) const {
    if (m_own_indices[c]) return static_cast<const Triangle*>(rtcGetBufferData(m_own_indices[c]));
    if (!m_layout.in_place(c)) return nullptr;  // re-made empty
    return static_cast<const Triangle*>(rtcGetBufferData(m_indices)) + m_layout.first(c);
}

LayoutMetrics ClusteredBlas::layout_sums(std::span<const uint32_t> touched,
                                         std::span<const ClusterMetrics> measured,
                                         const ClusterSplice& splice,
                                         const std::vector<uint8_t>& remade) const {
    LayoutMetrics sums;
    for (const ClusterMetrics& m : measured) add(sums.now, m);
    for (const ClusterMetrics& m : splice.metrics) {  // re-made: built now
        add(sums.now, m);
        add(sums.built, m);
    }
    std::vector<uint8_t> is_touched(cluster_count(), 0);
    for (uint32_t c : touched) is_touched[c] = 1;
    for (uint32_t c = 0; c < cluster_count(); ++c) {
        if (remade[c]) continue;
        sums.built.bounds_area += m_baselines[c].metrics.bounds_area;
        sums.built.triangle_area += m_baselines[c].metrics.triangle_area;
        if (!is_touched[c]) add(sums.now, m_metrics[c]);
    }
    return sums;
}

ClusterWork ClusteredBlas::plan(const MeshRecord& mesh, const RefitPolicy& policy,
                                const ClusterPolicy& clusters, BuildReason asked) const {
    ClusterWork work;
    // Step: a local topology edit re-makes the clusters of the triangles it replaced.
    if (!mesh.dirty.triangles.empty()) {
        plan_splice(mesh, clusters, work);
        if (work.whole.rebuild) return work;
    }
    std::vector<uint8_t> remade(cluster_count(), 0);
    for (uint32_t c : work.splice.clusters) remade[c] = 1;

    // Step: the clusters the edit's vertices touch, measured at their new positions.
    std::vector<uint32_t> touched;
    if (mesh.dirty.bits.has(MeshDirty::RefitRequested)) {
        touched.resize(cluster_count());
        for (uint32_t c = 0; c < cluster_count(); ++c) touched[c] = c;
    } else if (mesh.dirty.bits.has(MeshDirty::Points)) {
        touched = m_layout.touched(mesh.dirty.points);
    }
    std::erase_if(touched, [&](uint32_t c) { return remade[c] || m_layout.size(c) == 0; });
    const std::vector<ClusterMetrics> measured = measure_each(touched.size(), [&](std::size_t i) {
        return ClusterLayout::measure(mesh.positions, triangles_of(touched[i]),
                                      m_layout.size(touched[i]));
    });

    // Step: the layout as a whole. Clusters that drift apart overlap, which a refit of each
    // cannot mend: past the mesh's limits on the summed box areas, the mesh is re-clustered.
    const LayoutMetrics sums = layout_sums(touched, measured, work.splice, remade);
    work.whole = decide_refit(policy, mesh.build, BuildBaseline{sums.built, 0}, sums.now, asked);
    work.whole.detail = "clusters' " + work.whole.detail;
    if (work.whole.rebuild) return work;
    if (!work.splice.empty()) {
        const TriangleSplices& runs = work.splice.runs;
        work.whole.detail = std::to_string(runs.old_count()) + " triangles replaced by " +
                            std::to_string(runs.new_count()) + ": " +
                            std::to_string(work.splice.clusters.size()) +
                            " clusters re-made; " + work.whole.detail;
    }

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

void ClusteredBlas::plan_splice(const MeshRecord& mesh, const ClusterPolicy& clusters,
                                ClusterWork& work) const {
    const TriangleSplices& runs = mesh.dirty.triangles;
    ClusterSplice& splice = work.splice;
    splice.runs = runs;
    if (!clusters.local(runs.old_count(), m_layout.triangle_count()) ||
        !clusters.local(runs.new_count(), mesh.triangles.size())) {
        work.whole = {true, BuildReason::TopologyChanged,
                      std::to_string(runs.old_count()) + " of " +
                          std::to_string(m_layout.triangle_count()) + " triangles replaced by " +
                          std::to_string(runs.new_count()) +
                          ": not a local edit, the mesh is re-clustered"};
        return;
    }

    // Step: the clusters that held a replaced triangle keep their others, renumbered.
    const TriangleRenumbering renumber(runs);
    std::vector<int32_t> slot(cluster_count(), -1);
    auto take = [&](uint32_t c) -> std::vector<uint32_t>& {
        if (slot[c] < 0) {
            slot[c] = static_cast<int32_t>(splice.clusters.size());
            splice.clusters.push_back(c);
            std::vector<uint32_t>& kept = splice.members.emplace_back();
            for (uint32_t id : m_layout.members(c))
                if (const auto now = renumber(id)) kept.push_back(*now);
        }
        return splice.members[std::size_t(slot[c])];
    };
    const std::vector<uint32_t> losing = m_layout.holding(runs);
    for (uint32_t c : losing) take(c);

    // Step: each new triangle joins the nearest cluster (nearest_cluster).
    const std::vector<uint32_t> starts = runs.starts();
    for (std::size_t k = 0; k < starts.size(); ++k) {
        const uint32_t end = starts[k] + runs.runs()[k].count;
        for (uint32_t id = starts[k]; id < end; ++id)
            take(nearest_cluster(mesh, mesh.triangles[id], losing)).push_back(id);
    }

    finish_splice(mesh, work);
}

uint32_t ClusteredBlas::nearest_cluster(const MeshRecord& mesh, const Triangle& t,
                                        std::span<const uint32_t> losing) const {
    const std::vector<Vec3>& p = mesh.positions;
    const Vec3 centre = (p[t.x] + p[t.y] + p[t.z]) * (1.0f / 3.0f);
    uint32_t best = UINT32_MAX;
    float best_d = 0.0f;
    auto consider = [&](uint32_t c) {
        const float d = distance2(m_metrics[c].bounds, centre);
        if (best == UINT32_MAX || d < best_d) {
            best = c;
            best_d = d;
        }
    };
    for (int corner = 0; corner < 3; ++corner) m_layout.for_each_cluster_of(t[corner], consider);
    if (best == UINT32_MAX)
        for (uint32_t c : losing) consider(c);
    if (best == UINT32_MAX)
        for (uint32_t c = 0; c < cluster_count(); ++c) consider(c);
    return best;
}

void ClusteredBlas::finish_splice(const MeshRecord& mesh, ClusterWork& work) const {
    ClusterSplice& splice = work.splice;
    std::vector<uint32_t> order(splice.clusters.size());
    for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(),
              [&](uint32_t a, uint32_t b) { return splice.clusters[a] < splice.clusters[b]; });
    ClusterSplice sorted;
    sorted.runs = splice.runs;
    const uint64_t limit = 2 * uint64_t(m_layout.cut_size());
    for (uint32_t i : order) {
        if (splice.members[i].size() > limit) {
            work.whole = {true, BuildReason::TopologyChanged,
                          "cluster " + std::to_string(splice.clusters[i]) + " would hold " +
                              std::to_string(splice.members[i].size()) + " triangles (limit " +
                              std::to_string(limit) + "): the mesh is re-clustered"};
            return;
        }
        sorted.triangles += splice.members[i].size();
        sorted.clusters.push_back(splice.clusters[i]);
        sorted.members.push_back(std::move(splice.members[i]));
    }
    sorted.metrics = measure_each(sorted.clusters.size(), [&](std::size_t i) {
        return measure_ids(mesh, sorted.members[i]);
    });
    splice = std::move(sorted);
}

void ClusteredBlas::apply_splice(const MeshRecord& mesh, ClusterSplice& splice) {
    for (std::size_t i = 0; i < splice.clusters.size(); ++i) {
        const uint32_t c = splice.clusters[i];
        const std::vector<uint32_t>& members = splice.members[i];
        RTCGeometry g = m_geometries[c];
        const bool was_empty = m_layout.size(c) == 0;
        RTCBuffer old = m_own_indices[c];
        m_own_indices[c] = nullptr;
        if (members.empty()) {
            // Embree builds no geometry of zero triangles: an empty cluster is switched off.
            if (!was_empty) rtcDisableGeometry(g);
        } else {
            RTCBuffer b = rtcNewBuffer(m_device, members.size() * sizeof(Triangle));
            if (!b) return;  // the device reports the error
            auto* dst = static_cast<Triangle*>(rtcGetBufferData(b));
            for (std::size_t k = 0; k < members.size(); ++k) dst[k] = mesh.triangles[members[k]];
            rtcSetGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, b, 0,
                                 sizeof(Triangle), members.size());
            rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0);
            rtcUpdateGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0);
            if (was_empty) rtcEnableGeometry(g);
            rtcCommitGeometry(g);
            m_own_indices[c] = b;
        }
        if (old) rtcReleaseBuffer(old);
        m_metrics[c] = splice.metrics[i];
        m_baselines[c] = {as_mesh_metrics(m_metrics[c]), 0};
    }
    m_layout.splice(TriangleRenumbering(splice.runs), splice.clusters, std::move(splice.members),
                    mesh.triangles, mesh.positions.size());
}

void ClusteredBlas::refit(const MeshRecord& mesh, ClusterWork& work) {
    if (!work.splice.empty()) apply_splice(mesh, work.splice);
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
