#pragma once
// Tracing helpers shared by the TLAS strategies (embree_tlas.cpp, incremental_tlas.cpp): the ray
// layout checks against Embree's, the intersect context, and the packet lane fix-up. Only those
// files include it, since it includes Embree.

#include <cstddef>
#include <cstdint>

#include <embree3/rtcore.h>

#include "engine/accel/ray.h"

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
