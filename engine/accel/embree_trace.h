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

}  // namespace strata::embree_trace
