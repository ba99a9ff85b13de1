#pragma once
// Ray and hit records the renderer fills and the acceleration layer traces. Their layout is
// identical to Embree's RTCRayHit and RTCRayHit16 (checked by static_asserts in the one file that
// includes Embree), so tracing passes them through without copying.

#include <cstddef>
#include <cstdint>

namespace strata {

/// Id Embree and Strata use for "no hit".
constexpr uint32_t INVALID_ID = 0xFFFFFFFFu;

/// One ray and its hit. After a hit: `inst_id` is the instance slot, `prim_id` the triangle,
/// `ng_*` the unnormalised geometric normal in the instance's object space.
struct alignas(16) RayHit1 {
    float org_x, org_y, org_z, tnear;
    float dir_x, dir_y, dir_z, time;
    float tfar;
    uint32_t mask, id, flags;
    float ng_x, ng_y, ng_z;
    float u, v;
    uint32_t prim_id, geom_id, inst_id;
};

/// Sixteen rays in SoA layout, traced as one packet.
struct alignas(64) RayHit16 {
    float org_x[16], org_y[16], org_z[16], tnear[16];
    float dir_x[16], dir_y[16], dir_z[16], time[16];
    float tfar[16];
    uint32_t mask[16], id[16], flags[16];
    float ng_x[16], ng_y[16], ng_z[16];
    float u[16], v[16];
    uint32_t prim_id[16], geom_id[16], inst_id[16];
};

/// Active lanes of a 16-ray packet: -1 active, 0 inactive. Embree loads it with aligned vector
/// loads, so it carries the packet's 64-byte alignment.
struct alignas(64) ValidMask16 {
    int lanes[16];

    int& operator[](std::size_t i) { return lanes[i]; }
    int operator[](std::size_t i) const { return lanes[i]; }
};

/// Decides whether a candidate hit is really there: the renderer's alpha cut-outs and blending
/// (FrameState::coverage). Traced through Embree's intersect-context filter, so Embree goes on
/// looking past a refused hit, for closest and any hits alike. Launches pass one only while some
/// material needs it; without one no filter is installed and tracing costs what it did.
struct HitTest {
    /// True keeps the hit on the instance in `slot`, on triangle `prim` of its mesh (its own
    /// numbering) at barycentrics (u, v). `seed` hashes the ray and the triangle: a stochastic
    /// decision made from it is the same each time that ray meets that triangle.
    bool (*keep)(const void* user, uint32_t slot, uint32_t prim, float u, float v, uint32_t seed);
    const void* user;
};

/// Sixteen shadow rays: a miss leaves tfar unchanged, a hit sets it to -inf.
struct alignas(64) Ray16 {
    float org_x[16], org_y[16], org_z[16], tnear[16];
    float dir_x[16], dir_y[16], dir_z[16], time[16];
    float tfar[16];
    uint32_t mask[16], id[16], flags[16];
};

}  // namespace strata
