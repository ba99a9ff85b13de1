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

/// Lane i of an N-wide ray as a single ray.
RTCRay single_ray(RTCRayN* ray, unsigned n, unsigned i) {
    RTCRay r;
    r.org_x = RTCRayN_org_x(ray, n, i);
    r.org_y = RTCRayN_org_y(ray, n, i);
    r.org_z = RTCRayN_org_z(ray, n, i);
    r.tnear = RTCRayN_tnear(ray, n, i);
    r.dir_x = RTCRayN_dir_x(ray, n, i);
    r.dir_y = RTCRayN_dir_y(ray, n, i);
    r.dir_z = RTCRayN_dir_z(ray, n, i);
    r.time = RTCRayN_time(ray, n, i);
    r.tfar = RTCRayN_tfar(ray, n, i);
    r.mask = RTCRayN_mask(ray, n, i);
    r.id = RTCRayN_id(ray, n, i);
    r.flags = RTCRayN_flags(ray, n, i);
    return r;
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
        const RTCRay r = single_ray(ray, n, i);
        out.org_x[i] = r.org_x, out.org_y[i] = r.org_y, out.org_z[i] = r.org_z;
        out.dir_x[i] = r.dir_x, out.dir_y[i] = r.dir_y, out.dir_z[i] = r.dir_z;
        out.tnear[i] = r.tnear, out.tfar[i] = r.tfar, out.time[i] = r.time;
        out.mask[i] = r.mask, out.id[i] = r.id, out.flags[i] = r.flags;
        any = true;
    }
    return any;
}

/// Writes a BLAS hit (distance and hit record) into lane i of N-wide `rayhit`.
void put_hit(RTCRayHitN* rayhit, unsigned n, unsigned i, float t, const RTCHit& h) {
    RTCRayN_tfar(RTCRayHitN_RayN(rayhit, n), n, i) = t;
    RTCHitN* hit = RTCRayHitN_HitN(rayhit, n);
    RTCHitN_Ng_x(hit, n, i) = h.Ng_x;
    RTCHitN_Ng_y(hit, n, i) = h.Ng_y;
    RTCHitN_Ng_z(hit, n, i) = h.Ng_z;
    RTCHitN_u(hit, n, i) = h.u;
    RTCHitN_v(hit, n, i) = h.v;
    RTCHitN_primID(hit, n, i) = h.primID;
    RTCHitN_geomID(hit, n, i) = h.geomID;
    RTCHitN_instID(hit, n, i, 0) = h.instID[0];
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
        if (!lanes[i] || local.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) continue;
        RTCHit h;
        h.Ng_x = local.hit.Ng_x[i], h.Ng_y = local.hit.Ng_y[i], h.Ng_z = local.hit.Ng_z[i];
        h.u = local.hit.u[i], h.v = local.hit.v[i];
        h.primID = local.hit.primID[i], h.geomID = local.hit.geomID[i];
        h.instID[0] = local.hit.instID[0][i];
        put_hit(args->rayhit, n, i, local.ray.tfar[i], h);
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
    if (r.world_lod.empty()) {
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
    m_instances[slot] = Instance{r.world, r.world_motion, r.world_interpolation, r.world_lod};
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
