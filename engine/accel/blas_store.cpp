#include "engine/accel/blas_store.h"

#include <cstring>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace strata {

namespace {

struct SceneSetup {
    RTCBuildQuality scene_quality;
    RTCBuildQuality geometry_quality;
    RTCSceneFlags flags;
};

// Embree 3.13 refits REFIT-quality geometry only in a LOW-quality scene that is also flagged
// DYNAMIC; without the flag it silently rebuilds (measured: 1M triangles refit in ~10x less time
// with it). DYNAMIC also lets LOW-quality rebuilds reuse their memory.
SceneSetup setup_for(const BuildOptions& o) {
    if (o.allow_refit) return {RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_REFIT, RTC_SCENE_FLAG_DYNAMIC};
    if (o.prefer == BuildPreference::FastTrace)
        return {RTC_BUILD_QUALITY_HIGH, RTC_BUILD_QUALITY_HIGH, RTC_SCENE_FLAG_NONE};
    return {RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_LOW, RTC_SCENE_FLAG_DYNAMIC};
}

/// Vertices [begin, end) of key `key` into that time step's buffer: float3 for triangles, x y z
/// and the radius for points and curves.
void copy_vertices(RTCGeometry g, const MeshRecord& mesh, unsigned key, uint32_t begin,
                   uint32_t end) {
    static_assert(sizeof(Vec3) == 3 * sizeof(float));
    auto* dst = static_cast<float*>(rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_VERTEX, key));
    if (mesh.kind == MeshKind::Triangles && key == 0) {
        std::memcpy(dst + std::size_t(begin) * 3, mesh.positions.data() + begin,
                    std::size_t(end - begin) * sizeof(Vec3));
        return;
    }
    const std::size_t stride = mesh.kind == MeshKind::Triangles ? 3 : 4;
    // Key 0 is the positions; key k >= 1 of vertex i is motion_positions[i * per + k - 1].
    const std::size_t per = mesh.motion_keys() - 1;
    const Vec3* src = key == 0 ? mesh.positions.data() : mesh.motion_positions.data() + key - 1;
    const std::size_t step = key == 0 ? 1 : per;
    for (uint32_t i = begin; i < end; ++i) {
        const Vec3& p = src[std::size_t(i) * step];
        float* v = dst + std::size_t(i) * stride;
        v[0] = p.x;
        v[1] = p.y;
        v[2] = p.z;
        if (stride == 4) v[3] = mesh.radii[i];
    }
}

RTCGeometryType geometry_type(const MeshRecord& mesh) {
    if (mesh.kind == MeshKind::Points) return RTC_GEOMETRY_TYPE_SPHERE_POINT;
    if (mesh.kind == MeshKind::Triangles) return RTC_GEOMETRY_TYPE_TRIANGLE;
    const bool flat = mesh.style == CurveStyle::Flat;
    switch (mesh.basis) {
        case CurveBasis::Bezier:
            return flat ? RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE
                        : RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE;
        case CurveBasis::BSpline:
            return flat ? RTC_GEOMETRY_TYPE_FLAT_BSPLINE_CURVE
                        : RTC_GEOMETRY_TYPE_ROUND_BSPLINE_CURVE;
        case CurveBasis::CatmullRom:
            return flat ? RTC_GEOMETRY_TYPE_FLAT_CATMULL_ROM_CURVE
                        : RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE;
        default:
            return flat ? RTC_GEOMETRY_TYPE_FLAT_LINEAR_CURVE
                        : RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE;
    }
}

void copy_triangles(RTCGeometry g, const std::vector<Triangle>& tris) {
    static_assert(sizeof(Triangle) == 3 * sizeof(uint32_t));
    auto* dst = rtcGetGeometryBufferData(g, RTC_BUFFER_TYPE_INDEX, 0);
    std::memcpy(dst, tris.data(), tris.size() * sizeof(Triangle));
}

struct MetricsAccumulator {
    Bounds3 bounds;
    double triangle_area = 0.0;
};

}  // namespace

namespace {

/// Points and curves: the bounds of each primitive's control vertices grown by their radii.
MeshMetrics measure_primitives(const MeshRecord& mesh) {
    const std::vector<Vec3>& p = mesh.positions;
    const std::vector<float>& radius = mesh.radii;
    auto vertex_bounds = [&](uint32_t i) {
        Bounds3 b;
        b.extend(p[i] - Vec3(radius[i]));
        b.extend(p[i] + Vec3(radius[i]));
        return b;
    };
    Bounds3 total;
    double area = 0.0;
    if (mesh.kind == MeshKind::Points) {
        for (uint32_t i = 0; i < p.size(); ++i) {
            const Bounds3 b = vertex_bounds(i);
            area += double(b.surface_area());
            total.extend(b);
        }
        return {total.surface_area(), area};
    }
    const uint32_t span = mesh.basis == CurveBasis::Linear ? 2 : 4;
    for (uint32_t first : curve_segment_starts(mesh.basis, mesh.strands)) {
        Bounds3 b;
        for (uint32_t k = 0; k < span; ++k) b.extend(vertex_bounds(first + k));
        area += double(b.surface_area());
        total.extend(b);
    }
    return {total.surface_area(), area};
}

}  // namespace

MeshMetrics measure_mesh(const MeshRecord& mesh) {
    if (mesh.kind != MeshKind::Triangles) return measure_primitives(mesh);
    const std::vector<Vec3>& p = mesh.positions;
    const std::vector<Triangle>& t = mesh.triangles;
    // Every vertex of a valid mesh may be unreferenced, so bounds come from the vertex array the
    // BVH would see through the triangles: measure triangles only.
    const MetricsAccumulator total = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, t.size(), 16384), MetricsAccumulator{},
        [&](const tbb::blocked_range<std::size_t>& r, MetricsAccumulator acc) {
            float area = 0.0f;
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                Bounds3 b;
                b.extend(p[t[i].x]);
                b.extend(p[t[i].y]);
                b.extend(p[t[i].z]);
                area += b.surface_area();
                acc.bounds.extend(b);
            }
            acc.triangle_area += double(area);
            return acc;
        },
        [](MetricsAccumulator a, const MetricsAccumulator& b) {
            a.bounds.extend(b.bounds);
            a.triangle_area += b.triangle_area;
            return a;
        });
    return {total.bounds.surface_area(), total.triangle_area};
}

BlasStore::~BlasStore() {
    for (BlasRecord& r : m_retired) release_record(r, false);
    m_retired.clear();
    for (uint32_t slot = 0; slot < m_records.size(); ++slot) release_slot(slot, false);
}

const BlasRecord* BlasStore::find(MeshHandle h) const {
    if (h.index >= m_records.size()) return nullptr;
    const BlasRecord& r = m_records[h.index];
    return r.scene && r.generation == h.generation ? &r : nullptr;
}

RTCSceneTy* BlasStore::scene(uint32_t slot) const {
    return slot < m_records.size() ? m_records[slot].scene : nullptr;
}

int64_t BlasStore::bytes_of(const BlasRecord& r) const {
    return r.shared ? m_device.pool()->bytes_for(*r.shared, m_device) : r.bytes;
}

bool BlasStore::frozen(const BlasRecord& r) const {
    return r.shared && m_device.pool()->frozen(*r.shared, m_device);
}

void BlasStore::release_record(BlasRecord& r, bool account) {
    const int64_t before = m_device.bytes(MemoryCategory::Blas);
    // A shared BLAS's bytes stay with the engines that still hold it.
    if (r.shared) r.bytes = m_device.pool()->release(r.shared, m_device);
    r.clusters.reset();
    if (r.geometry) rtcReleaseGeometry(r.geometry);
    rtcReleaseScene(r.scene);
    // A TLAS copy that still references the BLAS (a stale static-tier copy of a removed instance)
    // keeps Embree from freeing it now; it is freed with that copy, in the TLAS's memory phase,
    // so its bytes are the TLAS's from here on.
    const int64_t freed = before - m_device.bytes(MemoryCategory::Blas);
    if (account && r.bytes > freed)
        m_device.transfer(MemoryCategory::Blas, MemoryCategory::Tlas, r.bytes - freed);
    r = BlasRecord{};
}

void BlasStore::release_slot(uint32_t slot, bool account) {
    BlasRecord& r = m_records[slot];
    if (!r.scene) return;
    if (r.clusters) --m_clustered;
    if (r.options.compact) ++m_compaction_version;
    release_record(r, account);
}

void BlasStore::retire_slot(uint32_t slot) {
    BlasRecord& r = m_records[slot];
    if (!r.scene) return;
    if (r.clusters) --m_clustered;
    if (r.options.compact) ++m_compaction_version;
    m_retired.push_back(std::move(r));
    r = BlasRecord{};
}

void BlasStore::release_retired() {
    for (BlasRecord& r : m_retired) release_record(r, true);
    m_retired.clear();
}

bool BlasStore::release(MeshHandle h) {
    if (!find(h)) return false;
    release_slot(h.index);
    return true;
}

Status BlasStore::build(MeshHandle h, const MeshRecord& mesh, const MeshMetrics& metrics,
                        bool clustered) {
    if (h.index >= m_records.size()) m_records.resize(h.index + 1);
    BlasRecord& r = m_records[h.index];
    // A shared BLAS never changes: the record lets go of it (a TLAS may still reference it).
    if (r.scene && (r.generation != h.generation || !(r.options == mesh.build) || r.shared))
        retire_slot(h.index);

    // Step: a whole BLAS another engine built for exactly this content is held, not built.
    BlasPool* pool = m_device.pool();
    const bool poolable = pool && !(clustered && may_cluster(mesh)) && !mesh.build.compact &&
                          mesh.kind == MeshKind::Triangles && mesh.motion_keys() == 1;
    const int flags = scene_flags(mesh.build, false);
    const uint64_t key = poolable ? shared_blas_key(mesh, flags) : 0;
    if (poolable) {
        if (auto found = pool->hold(mesh, flags, key, m_device)) {
            if (r.scene) retire_slot(h.index);
            adopt(m_records[h.index], found, h, mesh);
            return {};
        }
    }
    r.adopted = false;

    const auto vertex_count = static_cast<uint32_t>(mesh.positions.size());
    const auto triangle_count = static_cast<uint32_t>(mesh.primitive_count());
    RTCDevice device = m_device.get();
    const int64_t bytes_before = m_device.bytes(MemoryCategory::Blas);

    // Step: create the scene the first time this mesh is built.
    if (!r.scene) {
        r.scene = rtcNewScene(device);
        rtcSetSceneBuildQuality(r.scene, setup_for(mesh.build).scene_quality);
        r.mesh_id = mesh.id;
        r.generation = h.generation;
        r.options = mesh.build;
        r.vertex_count = r.triangle_count = 0;
    }

    // Step: the geometry (whole or clustered), uploaded, then the scene's BVH (at full size
    // first when it is compacted: that build is what compaction is measured against).
    rtcSetSceneFlags(r.scene, RTCSceneFlags(scene_flags(r.options, false)));
    set_layout(r, mesh, clustered && may_cluster(mesh));
    if (Status s = m_device.status("allocating BLAS buffers"); !s) {
        release_slot(h.index);
        return s;
    }
    if (mesh.kind != MeshKind::Triangles)
        upload_points_or_curves(r, mesh);
    else if (!r.clusters)
        upload_whole(r, mesh, vertex_count, triangle_count);
    rtcCommitScene(r.scene);
    if (r.options.compact) compact(r, bytes_before, mesh.kind != MeshKind::Points);

    r.vertex_count = vertex_count;
    r.triangle_count = triangle_count;
    r.baseline = BuildBaseline{metrics, 0};
    r.bytes += m_device.bytes(MemoryCategory::Blas) - bytes_before;
    if (r.options.compact) ++m_compaction_version;
    if (Status s = m_device.status("building BLAS"); !s) {
        release_slot(h.index);
        return s;
    }
    if (poolable && r.geometry) publish(r, key, flags);
    return {};
}

void BlasStore::adopt(BlasRecord& r, const std::shared_ptr<SharedBlas>& blas, MeshHandle h,
                      const MeshRecord& mesh) {
    rtcRetainScene(blas->scene);
    rtcRetainGeometry(blas->geometry);
    r.mesh_id = mesh.id;
    r.scene = blas->scene;
    r.geometry = blas->geometry;
    r.generation = h.generation;
    r.vertex_count = blas->vertex_count;
    r.triangle_count = blas->triangle_count;
    r.options = blas->options;
    r.baseline = blas->baseline;
    r.bytes = r.uncompacted_bytes = 0;
    r.shared = blas;
    r.adopted = true;
}

void BlasStore::publish(BlasRecord& r, uint64_t key, int flags) {
    auto blas = std::make_shared<SharedBlas>();
    blas->scene = r.scene;
    blas->geometry = r.geometry;
    blas->key = key;
    blas->vertex_count = r.vertex_count;
    blas->triangle_count = r.triangle_count;
    blas->options = r.options;
    blas->scene_flags = flags;
    blas->baseline = r.baseline;
    blas->bytes = r.bytes;
    blas->owner = &m_device;
    blas->holders = {&m_device};
    m_device.pool()->publish(blas);
    r.shared = std::move(blas);
    r.bytes = 0;
}

int BlasStore::scene_flags(const BuildOptions& options, bool compact) const {
    const int robust = m_watertight ? RTC_SCENE_FLAG_ROBUST : 0;
    const int filter = m_context_filter ? RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION : 0;
    return setup_for(options).flags | robust | filter | (compact ? RTC_SCENE_FLAG_COMPACT : 0);
}

void BlasStore::compact(BlasRecord& r, int64_t bytes_before, bool indexed) {
    STRATA_CHECK(r.geometry != nullptr);  // a compacted mesh is never clustered
    r.uncompacted_bytes = r.bytes + (m_device.bytes(MemoryCategory::Blas) - bytes_before);
    // Embree picks a scene's layout when it builds it: with the flag set, a topology change
    // (the index buffer marked modified; points have none, so the geometry is attached anew)
    // makes the next commit build the compact BVH and free the full one.
    rtcSetSceneFlags(r.scene, RTCSceneFlags(scene_flags(r.options, true)));
    if (indexed) {
        rtcUpdateGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_INDEX, 0);
    } else {
        rtcDetachGeometry(r.scene, 0);
        rtcAttachGeometryByID(r.scene, r.geometry, 0);
    }
    rtcCommitGeometry(r.geometry);
    rtcCommitScene(r.scene);
}

CompactionSummary BlasStore::compaction() const {
    CompactionSummary out;
    for (const BlasRecord& r : m_records) {
        if (!r.scene || !r.options.compact) continue;
        out.meshes.push_back({r.mesh_id, r.uncompacted_bytes, r.bytes});
        ++out.totals.meshes;
        out.totals.uncompacted_bytes += r.uncompacted_bytes;
        out.totals.bytes += r.bytes;
    }
    return out;
}

void BlasStore::set_layout(BlasRecord& r, const MeshRecord& mesh, bool clustered) {
    // A rebuild starts from new clusters: the layout follows the positions and triangles now.
    if (r.clusters) {
        r.clusters.reset();
        --m_clustered;
    }
    // Points and curves start from a new geometry at every build (a new count is a new BVH), and
    // so does a mesh whose vertex keys changed (Embree fixes a geometry's time steps).
    if ((mesh.kind != MeshKind::Triangles || r.keys != mesh.motion_keys()) && r.geometry) {
        rtcDetachGeometry(r.scene, 0);
        rtcReleaseGeometry(r.geometry);
        r.geometry = nullptr;
    }
    if (!clustered) {
        if (!r.geometry) {
            r.geometry = rtcNewGeometry(m_device.get(), geometry_type(mesh));
            r.keys = static_cast<uint32_t>(mesh.motion_keys());
            rtcSetGeometryTimeStepCount(r.geometry, r.keys);
            rtcSetGeometryBuildQuality(r.geometry, setup_for(r.options).geometry_quality);
            rtcAttachGeometryByID(r.scene, r.geometry, 0);
            r.vertex_count = r.triangle_count = 0;
        }
        return;
    }
    if (r.geometry) {
        rtcDetachGeometry(r.scene, 0);
        rtcReleaseGeometry(r.geometry);
        r.geometry = nullptr;
    }
    r.clusters = std::make_unique<ClusteredBlas>(
        m_device.get(), r.scene, mesh, m_cluster_policy.cluster_size(mesh.triangles.size()),
        setup_for(r.options).geometry_quality);
    ++m_clustered;
}

void BlasStore::upload_whole(BlasRecord& r, const MeshRecord& mesh, uint32_t vertex_count,
                             uint32_t triangle_count) {
    // (Re)allocate buffers when sizes change, then upload everything.
    if (r.vertex_count != vertex_count) {
        for (unsigned k = 0; k < r.keys; ++k)
            rtcSetNewGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_VERTEX, k, RTC_FORMAT_FLOAT3,
                                    sizeof(Vec3), vertex_count);
    }
    if (r.triangle_count != triangle_count) {
        rtcSetNewGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                sizeof(Triangle), triangle_count);
    }
    for (unsigned k = 0; k < r.keys; ++k)
        if (!rtcGetGeometryBufferData(r.geometry, RTC_BUFFER_TYPE_VERTEX, k))
            return;  // allocation failed: the device reports it
    if (!rtcGetGeometryBufferData(r.geometry, RTC_BUFFER_TYPE_INDEX, 0)) return;
    for (unsigned k = 0; k < r.keys; ++k) {
        copy_vertices(r.geometry, mesh, k, 0, vertex_count);
        rtcUpdateGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_VERTEX, k);
    }
    copy_triangles(r.geometry, mesh.triangles);
    // Marking the index buffer modified moves the geometry's topology version, which is what
    // makes a REFIT-quality geometry rebuild instead of refit.
    rtcUpdateGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_INDEX, 0);
    rtcCommitGeometry(r.geometry);
}

void BlasStore::upload_points_or_curves(BlasRecord& r, const MeshRecord& mesh) {
    const auto vertex_count = static_cast<uint32_t>(mesh.positions.size());
    for (unsigned k = 0; k < r.keys; ++k) {
        if (!rtcSetNewGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_VERTEX, k, RTC_FORMAT_FLOAT4,
                                     4 * sizeof(float), vertex_count))
            return;  // allocation failed: the device reports it
        copy_vertices(r.geometry, mesh, k, 0, vertex_count);
    }
    if (mesh.kind == MeshKind::Curves) {
        const std::vector<uint32_t> starts = curve_segment_starts(mesh.basis, mesh.strands);
        auto* dst = rtcSetNewGeometryBuffer(r.geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT,
                                            sizeof(uint32_t), starts.size());
        if (!dst) return;
        std::memcpy(dst, starts.data(), starts.size() * sizeof(uint32_t));
    }
    rtcCommitGeometry(r.geometry);
}

Status BlasStore::refit(MeshHandle h, const MeshRecord& mesh, ClusterWork* work) {
    BlasRecord* r = h.index < m_records.size() ? &m_records[h.index] : nullptr;
    STRATA_CHECK(r && r->scene && r->generation == h.generation);
    STRATA_CHECK(r->vertex_count == mesh.positions.size());
    // Points, curves and meshes with vertex keys rebuild (accel_graph.cpp).
    STRATA_CHECK(mesh.kind == MeshKind::Triangles && mesh.motion_keys() == 1 && r->keys == 1);
    if (r->shared) {
        // Shared since the commit was planned: this engine builds its own copy.
        if (!m_device.pool()->withdraw(r->shared, m_device))
            return build(h, mesh, measure_mesh(mesh), false);
        // Only ever held by this engine: out of the pool, it is an ordinary BLAS again.
        r->bytes = r->shared->bytes;
        r->shared.reset();
    }
    const int64_t bytes_before = m_device.bytes(MemoryCategory::Blas);
    if (r->clusters) {
        STRATA_CHECK(work != nullptr);
        r->clusters->refit(mesh, *work);
    } else {
        for (const VertexRanges::Range& range : mesh.dirty.points.ranges()) {
            const uint32_t begin = std::min(range.begin, r->vertex_count);
            const uint32_t end = std::min(range.end, r->vertex_count);
            if (begin < end) copy_vertices(r->geometry, mesh, 0, begin, end);
        }
        rtcUpdateGeometryBuffer(r->geometry, RTC_BUFFER_TYPE_VERTEX, 0);
        rtcCommitGeometry(r->geometry);
    }
    rtcCommitScene(r->scene);
    r->triangle_count = static_cast<uint32_t>(mesh.triangles.size());
    ++r->baseline.refits_since_build;
    r->bytes += m_device.bytes(MemoryCategory::Blas) - bytes_before;
    if (r->options.compact) ++m_compaction_version;
    return m_device.status("refitting BLAS");
}

}  // namespace strata
