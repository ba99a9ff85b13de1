#include "engine/accel/lod_scenes.h"

#include <limits>

#include "engine/accel/blas_store.h"
#include "engine/accel/embree_device.h"
#include "engine/accel/embree_trace.h"
#include "engine/scene/scene.h"

namespace strata {

struct LodScenes::Wrapper {
    const LodScenes* owner = nullptr;
    RTCScene scene = nullptr;  ///< the wrapper: one user geometry
    RTCScene blas = nullptr;   ///< retained; null once the mesh is gone
    RTCBounds bounds{};
};

namespace {

using embree_trace::FilterContext;
using embree_trace::put_hit;
using embree_trace::single_ray;
using embree_trace::store_lane;

/// The slot of the instance whose wrapper the ray is in, or INVALID_ID when it is a stale copy
/// (the incremental TLAS's static tier skips those).
uint32_t entered_slot(const RTCIntersectContext* context) {
    const auto* c = reinterpret_cast<const FilterContext*>(context);
    const uint32_t slot = c->slot(context->instID[0]);
    return c->stale && c->stale[slot] ? INVALID_ID : slot;
}

bool lane_selected(const LodScenes& lod, const RTCIntersectContext* context, uint32_t slot,
                   RTCRayN* ray, unsigned n, unsigned i) {
    const Vec3 org(RTCRayN_org_x(ray, n, i), RTCRayN_org_y(ray, n, i), RTCRayN_org_z(ray, n, i));
    const Vec3* eye = reinterpret_cast<const FilterContext*>(context)->lod_eye;
    return lod.selects(slot, eye, org, RTCRayN_time(ray, n, i));
}

void wrapper_bounds(const RTCBoundsFunctionArguments* args) {
    const auto* w = static_cast<const LodScenes::Wrapper*>(args->geometryUserPtr);
    *args->bounds_o = w->bounds;
}

/// Copies the lanes of N-wide `ray` (N <= 16) that are active and see the instance into the
/// same lanes of `out`, marks them in `lanes` and deactivates every other lane of `out` the way
/// the stream path reads a packet (embree_trace::deactivate_unused_lanes). Returns whether any
/// lane was copied. With an eye in the context the choice is one for the whole packet.
bool gather(const LodScenes& lod, const RTCIntersectContext* context, uint32_t slot,
            const int* valid, RTCRayN* ray, unsigned n, RTCRay16& out, ValidMask16& lanes) {
    const Vec3* eye = reinterpret_cast<const FilterContext*>(context)->lod_eye;
    if (eye && !lod.selects(slot, eye, Vec3(0.0f), 0.0f)) return false;
    bool any = false;
    for (unsigned i = 0; i < 16; ++i) {
        lanes[i] = i < n && valid[i] && (eye || lane_selected(lod, context, slot, ray, n, i))
                       ? -1
                       : 0;
        if (!lanes[i]) {
            out.tnear[i] = 1.0f;
            out.tfar[i] = 0.0f;
            continue;
        }
        store_lane(out, i, single_ray(ray, n, i));
        any = true;
    }
    return any;
}

// Single rays trace the BLAS as single rays, packets as packets (coherent camera rays keep
// their packet speed inside the level).
void wrapper_intersect(const RTCIntersectFunctionNArguments* args) {
    const auto* w = static_cast<const LodScenes::Wrapper*>(args->geometryUserPtr);
    if (!w->blas) return;
    const uint32_t slot = entered_slot(args->context);
    if (slot == INVALID_ID) return;
    const unsigned n = args->N;
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
    if (n == 1) {
        if (!args->valid[0] || !lane_selected(*w->owner, args->context, slot, ray, 1, 0)) return;
        RTCRayHit rh;
        rh.ray = single_ray(ray, 1, 0);
        rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(w->blas, args->context, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
            put_hit(args->rayhit, 1, 0, rh.ray.tfar, rh.hit);
        return;
    }
    alignas(64) RTCRayHit16 local;
    ValidMask16 lanes;
    if (!gather(*w->owner, args->context, slot, args->valid, ray, n, local.ray, lanes)) return;
    for (unsigned i = 0; i < 16; ++i)
        local.hit.geomID[i] = local.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect16(lanes.lanes, w->blas, args->context, &local);
    for (unsigned i = 0; i < n; ++i) {
        if (lanes[i] && local.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
            put_hit(args->rayhit, n, i, local, i);
    }
}

void wrapper_occluded(const RTCOccludedFunctionNArguments* args) {
    const auto* w = static_cast<const LodScenes::Wrapper*>(args->geometryUserPtr);
    if (!w->blas) return;
    const uint32_t slot = entered_slot(args->context);
    if (slot == INVALID_ID) return;
    const unsigned n = args->N;
    constexpr float OCCLUDED = -std::numeric_limits<float>::infinity();
    if (n == 1) {
        if (!args->valid[0] || !lane_selected(*w->owner, args->context, slot, args->ray, 1, 0))
            return;
        RTCRay r = single_ray(args->ray, 1, 0);
        rtcOccluded1(w->blas, args->context, &r);
        if (r.tfar == OCCLUDED) RTCRayN_tfar(args->ray, 1, 0) = OCCLUDED;
        return;
    }
    alignas(64) RTCRay16 local;
    ValidMask16 lanes;
    if (!gather(*w->owner, args->context, slot, args->valid, args->ray, n, local, lanes)) return;
    rtcOccluded16(lanes.lanes, w->blas, args->context, &local);
    for (unsigned i = 0; i < n; ++i) {
        if (lanes[i] && local.tfar[i] == OCCLUDED) RTCRayN_tfar(args->ray, n, i) = OCCLUDED;
    }
}

bool same_bounds(const RTCBounds& a, const RTCBounds& b) {
    return a.lower_x == b.lower_x && a.lower_y == b.lower_y && a.lower_z == b.lower_z &&
           a.upper_x == b.upper_x && a.upper_y == b.upper_y && a.upper_z == b.upper_z;
}

}  // namespace

LodScenes::LodScenes(EmbreeDevice& device) : m_device(device) {}

LodScenes::~LodScenes() {
    for (auto& [mesh, w] : m_wrappers) {
        if (w->blas) rtcReleaseScene(w->blas);
        rtcReleaseScene(w->scene);
    }
}

LodScenes::Wrapper& LodScenes::wrapper(uint32_t mesh_slot) {
    std::unique_ptr<Wrapper>& w = m_wrappers[mesh_slot];
    if (w) return *w;
    w = std::make_unique<Wrapper>();
    w->owner = this;
    w->scene = rtcNewScene(m_device.get());
    RTCGeometry g = rtcNewGeometry(m_device.get(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(g, 1);
    rtcSetGeometryUserData(g, w.get());
    rtcSetGeometryBoundsFunction(g, wrapper_bounds, nullptr);
    rtcSetGeometryIntersectFunction(g, wrapper_intersect);
    rtcSetGeometryOccludedFunction(g, wrapper_occluded);
    rtcCommitGeometry(g);
    rtcAttachGeometry(w->scene, g);
    rtcReleaseGeometry(g);
    return *w;
}

RTCScene LodScenes::instanced_scene(const BlasStore& blas, uint32_t slot,
                                    const InstanceRecord& r) {
    RTCScene mesh_blas = blas.scene(r.mesh.index);
    if (r.rare->world_lod.empty()) {
        m_instances.erase(slot);
        return mesh_blas;
    }
    Wrapper& w = wrapper(r.mesh.index);
    RTCBounds bounds;
    rtcGetSceneBounds(mesh_blas, &bounds);
    if (w.blas != mesh_blas || !same_bounds(bounds, w.bounds)) {
        if (w.blas != mesh_blas) {
            rtcRetainScene(mesh_blas);
            if (w.blas) rtcReleaseScene(w.blas);
            w.blas = mesh_blas;
        }
        w.bounds = bounds;
        rtcCommitGeometry(rtcGetGeometry(w.scene, 0));
        rtcCommitScene(w.scene);
    }
    const InstanceRare& rare = *r.rare;
    m_instances[slot] =
        Instance{r.world, rare.world_motion, rare.world_interpolation, rare.world_lod};
    return w.scene;
}

void LodScenes::sweep(const BlasStore& blas) {
    for (auto& [mesh, w] : m_wrappers) {
        if (!w->blas || blas.scene(mesh) == w->blas) continue;
        // The mesh was removed or rebuilt into a new scene: no current instance reaches this
        // BLAS through the wrapper (each was handed the wrapper again, or left the TLAS).
        rtcReleaseScene(w->blas);
        w->blas = nullptr;
    }
}

bool LodScenes::selects(uint32_t slot, const Vec3* eye, const Vec3& org, float time) const {
    const auto it = m_instances.find(slot);
    if (it == m_instances.end()) return false;
    const Instance& inst = it->second;
    if (eye) return lod_selects(inst.bands, *eye);
    const Affine world =
        inst.keys.size() >= 2 ? motion_at(inst.keys, time, inst.interpolation) : inst.world;
    return lod_selects(inst.bands, world.transform_point(org));
}

}  // namespace strata
