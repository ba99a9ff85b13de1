#pragma once
// Tracing helpers shared by the TLAS strategies (embree_tlas.cpp, incremental_tlas.cpp): the ray
// layout checks against Embree's, the intersect context, and the packet lane fix-up. Only those
// files include it, since it includes Embree.

#include <cstddef>
#include <cstdint>
#include <cstring>

#include <embree3/rtcore.h>

#include "engine/accel/ray.h"
#include "engine/accel/tlas.h"

namespace strata::embree_trace {

// Ray layouts are passed to Embree without copying.
static_assert(sizeof(RayHit1) == sizeof(RTCRayHit));
static_assert(offsetof(RayHit1, tfar) == offsetof(RTCRayHit, ray.tfar));
static_assert(offsetof(RayHit1, ng_x) == offsetof(RTCRayHit, hit.Ng_x));
static_assert(offsetof(RayHit1, inst_id) == offsetof(RTCRayHit, hit.instID));
static_assert(sizeof(RayHit16) == sizeof(RTCRayHit16));
static_assert(offsetof(RayHit16, tfar) == offsetof(RTCRayHit16, ray.tfar));
static_assert(offsetof(RayHit16, ng_x) == offsetof(RTCRayHit16, hit.Ng_x));
static_assert(offsetof(RayHit16, inst_id) == offsetof(RTCRayHit16, hit.instID));
static_assert(sizeof(Ray16) == sizeof(RTCRay16));
static_assert(offsetof(Ray16, flags) == offsetof(RTCRay16, flags));

inline RTCIntersectContext make_context(bool coherent) {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    ctx.flags =
        coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
    return ctx;
}

/// An intersect context with what its filter (filter_hits) reads. Embree hands the context back
/// to the filter, which casts it to this (`ctx` comes first).
struct FilterContext {
    RTCIntersectContext ctx;
    const TlasStrategy* tlas = nullptr;  ///< renumbers clustered triangles for the test
    const HitTest* test = nullptr;       ///< null: no hit test
    const uint8_t* stale = nullptr;      ///< by slot: 1 skips the hit (incremental static tier)
    /// The slot of the traced scene's instance id i is the uint32_t at slots + i * slot_stride;
    /// null: ids are slots.
    const char* slots = nullptr;
    std::size_t slot_stride = 0;
    const Vec3* lod_eye = nullptr;  ///< what LOD groups measure from (null: the ray's origin)

    uint32_t slot(uint32_t inst) const {
        if (!slots) return inst;
        uint32_t s;
        std::memcpy(&s, slots + std::size_t(inst) * slot_stride, sizeof s);
        return s;
    }
};

/// Refuses the candidate hits of stale instance copies and those the hit test refuses.
void filter_hits(const RTCFilterFunctionNArguments* args);

/// A context that filters with `options.test` and, when `stale` is set, skips stale copies; its
/// filter is installed only when there is something to filter.
inline FilterContext filter_context(bool coherent, const TlasStrategy& tlas,
                                    const TraceOptions& options, const uint8_t* stale = nullptr) {
    FilterContext c{make_context(coherent), &tlas, options.test, stale};
    c.lod_eye = options.lod_eye;
    if (options.test || stale) c.ctx.filter = filter_hits;
    return c;
}

/// Marks the lanes `valid` leaves out as inactive the way Embree's ray-stream path reads a packet:
/// tnear > tfar. Without a native 16-wide kernel (no AVX-512) rtcIntersect16 and rtcOccluded16
/// run through that path, which treats every lane with tnear <= tfar as live whatever the mask
/// says, so a stale unused lane would be traced (and Debian's Embree asserts on its values).
template <class Packet>
void deactivate_unused_lanes(const ValidMask16& valid, Packet& rays) {
    for (uint32_t i = 0; i < 16; ++i) {
        if (valid.lanes[i]) continue;
        rays.tnear[i] = 1.0f;
        rays.tfar[i] = 0.0f;
    }
}

/// Lane i of an N-wide ray as a single ray.
inline RTCRay single_ray(RTCRayN* ray, unsigned n, unsigned i) {
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

/// Stores single ray `r` in lane i of a 16-wide packet.
inline void store_lane(RTCRay16& out, unsigned i, const RTCRay& r) {
    out.org_x[i] = r.org_x, out.org_y[i] = r.org_y, out.org_z[i] = r.org_z;
    out.dir_x[i] = r.dir_x, out.dir_y[i] = r.dir_y, out.dir_z[i] = r.dir_z;
    out.tnear[i] = r.tnear, out.tfar[i] = r.tfar, out.time[i] = r.time;
    out.mask[i] = r.mask, out.id[i] = r.id, out.flags[i] = r.flags;
}

/// Writes a hit (distance and hit record) into lane i of N-wide `rayhit`.
inline void put_hit(RTCRayHitN* rayhit, unsigned n, unsigned i, float t, const RTCHit& h) {
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

/// Writes lane k of 16-wide `from` (a trace of a copy of the rays) into lane i of `rayhit`.
inline void put_hit(RTCRayHitN* rayhit, unsigned n, unsigned i, const RTCRayHit16& from,
                    unsigned k) {
    RTCHit h;
    h.Ng_x = from.hit.Ng_x[k], h.Ng_y = from.hit.Ng_y[k], h.Ng_z = from.hit.Ng_z[k];
    h.u = from.hit.u[k], h.v = from.hit.v[k];
    h.primID = from.hit.primID[k], h.geomID = from.hit.geomID[k];
    h.instID[0] = from.hit.instID[0][k];
    put_hit(rayhit, n, i, from.ray.tfar[k], h);
}

}  // namespace strata::embree_trace
