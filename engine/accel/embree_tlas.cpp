// TLAS strategy on Embree's own top level: one RTC_GEOMETRY_TYPE_INSTANCE per instance slot,
// attached with rtcAttachGeometryByID so a hit's instID is the instance slot. An update touches
// only the listed instances' geometries, but Embree then rebuilds its whole top-level BVH
// (O(instances)); that cost is what a partitioned strategy would remove.

#include <vector>

#include "engine/accel/blas_store.h"
#include "engine/accel/embree_device.h"
#include "engine/accel/instance_transform.h"
#include "engine/accel/embree_trace.h"
#include "engine/accel/tlas.h"
#include "engine/scene/scene.h"

namespace strata {

namespace {

using embree_trace::deactivate_unused_lanes;
using embree_trace::filter_context;
using embree_trace::FilterContext;

struct TlasInstance {
    RTCGeometry geometry = nullptr;
    RTCScene blas = nullptr;
    uint32_t generation = 0;
};

class EmbreeTlas final : public TlasStrategy {
public:
    EmbreeTlas(EmbreeDevice& device, BuildPreference prefer, bool watertight)
        : m_device(device), m_prefer(prefer), m_watertight(watertight) {
        create_scene();
        // An empty committed scene is traceable; launches may come before any instance exists.
        rtcCommitScene(m_scene);
    }
    ~EmbreeTlas() override {
        release_all();
        rtcReleaseScene(m_scene);
    }

    const char* name() const override { return "embree"; }

    bool holds(InstanceHandle h) const override {
        return h.index < m_instances.size() && m_instances[h.index].geometry &&
               m_instances[h.index].generation == h.generation;
    }

    uint64_t instance_count() const override { return m_count; }

    TlasTiers tiers_report() override {
        TlasTiers t;
        t.strategy = "embree";
        t.static_instances = m_count;
        return t;
    }

    Status update(const Scene& scene, const BlasStore& blas, const TlasDelta& delta) override {
        MemoryScope memory(m_device, MemoryCategory::Tlas);
        sweep_lod(blas);
        for (InstanceHandle h : delta.changed) sync_instance(scene, blas, h);
        for (InstanceHandle h : delta.blas_changed) {
            // Committing the instance makes Embree re-read its BLAS's bounds; a BLAS object of
            // its own in place of a shared one (blas_pool.h) is set first.
            if (holds(h)) sync_instance(scene, blas, h);
        }
        rtcCommitScene(m_scene);
        return m_device.status("updating the TLAS");
    }

    Status rebuild(const Scene& scene, const BlasStore& blas) override {
        MemoryScope memory(m_device, MemoryCategory::Tlas);
        sweep_lod(blas);
        release_all();
        rtcReleaseScene(m_scene);
        create_scene();
        scene.instances().for_each(
            [&](InstanceHandle h, const InstanceRecord&) { sync_instance(scene, blas, h); });
        rtcCommitScene(m_scene);
        return m_device.status("rebuilding the TLAS");
    }

    void trace1(RayHit1& ray, bool coherent, const TraceOptions& options) const override {
        FilterContext c = filter_context(coherent, *this, options);
        rtcIntersect1(m_scene, &c.ctx, reinterpret_cast<RTCRayHit*>(&ray));
    }

    void trace16(const ValidMask16& valid, RayHit16& rays, bool coherent,
                 const TraceOptions& options) const override {
        FilterContext c = filter_context(coherent, *this, options);
        deactivate_unused_lanes(valid, rays);
        rtcIntersect16(valid.lanes, m_scene, &c.ctx, reinterpret_cast<RTCRayHit16*>(&rays));
    }

    void trace_occluded16(const ValidMask16& valid, Ray16& rays,
                          const TraceOptions& options) const override {
        FilterContext c = filter_context(false, *this, options);
        deactivate_unused_lanes(valid, rays);
        rtcOccluded16(valid.lanes, m_scene, &c.ctx, reinterpret_cast<RTCRay16*>(&rays));
    }

private:
    void create_scene() {
        m_scene = rtcNewScene(m_device.get());
        rtcSetSceneBuildQuality(m_scene, m_prefer == BuildPreference::FastTrace ? RTC_BUILD_QUALITY_MEDIUM
                                                                                : RTC_BUILD_QUALITY_LOW);
        rtcSetSceneFlags(m_scene, RTCSceneFlags(RTC_SCENE_FLAG_DYNAMIC |
                                                 (m_watertight ? RTC_SCENE_FLAG_ROBUST : 0)));
    }

    void release_slot(uint32_t slot) {
        TlasInstance& t = m_instances[slot];
        if (!t.geometry) return;
        rtcDetachGeometry(m_scene, slot);
        rtcReleaseGeometry(t.geometry);
        t = TlasInstance{};
        --m_count;
    }

    void release_all() {
        for (uint32_t slot = 0; slot < m_instances.size(); ++slot) release_slot(slot);
    }

    /// Makes the TLAS entry of `h`'s slot match the scene: created, updated or removed.
    void sync_instance(const Scene& scene, const BlasStore& blas, InstanceHandle h) {
        if (h.index >= m_instances.size()) m_instances.resize(h.index + 1);
        TlasInstance& t = m_instances[h.index];
        const auto inst = scene.instance(h);
        if (!inst) {
            if (t.geometry && t.generation == h.generation) release_slot(h.index);
            return;
        }
        const InstanceRecord& r = *inst.value();
        if (t.geometry && t.generation != h.generation) release_slot(h.index);
        STRATA_CHECK(blas.scene(r.mesh.index) != nullptr);
        RTCScene blas_scene = instanced_scene(m_device, blas, h.index, r);
        if (!t.geometry) {
            t.geometry = rtcNewGeometry(m_device.get(), RTC_GEOMETRY_TYPE_INSTANCE);
            t.generation = h.generation;
            rtcAttachGeometryByID(m_scene, t.geometry, h.index);
            ++m_count;
        }
        if (t.blas != blas_scene) {
            rtcSetGeometryInstancedScene(t.geometry, blas_scene);
            t.blas = blas_scene;
        }
        set_instance_transform(t.geometry, r.world.m.data(), r.rare->world_motion,
                               r.rare->world_interpolation);
        rtcSetGeometryMask(t.geometry, r.mask);
        if (r.world_visible) {
            rtcEnableGeometry(t.geometry);
        } else {
            rtcDisableGeometry(t.geometry);
        }
        rtcCommitGeometry(t.geometry);
    }


    EmbreeDevice& m_device;
    BuildPreference m_prefer;
    bool m_watertight;
    RTCScene m_scene = nullptr;
    std::vector<TlasInstance> m_instances;  ///< indexed by instance slot
    uint64_t m_count = 0;
};

}  // namespace

std::unique_ptr<TlasStrategy> make_embree_tlas(EmbreeDevice& device, BuildPreference prefer,
                                               bool watertight) {
    return std::make_unique<EmbreeTlas>(device, prefer, watertight);
}

}  // namespace strata
