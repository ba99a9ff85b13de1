#include "engine/accel/instance_array.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <glm/glm.hpp>

#include <embree3/rtcore.h>
#include <immintrin.h>

#include "engine/accel/embree_trace.h"
#include "engine/accel/tlas_merge.h"

namespace strata {

namespace {

using embree_trace::FilterContext;
using embree_trace::put_hit;
using embree_trace::single_ray;

const InstanceEntry& entry_of(void* user, unsigned prim) {
    return (*static_cast<const InstanceTable*>(user))[prim];
}

/// Whether Embree's kernels on this CPU fuse multiply-adds (its AVX2 and AVX-512 kernels do; a
/// device configured down to an older ISA would not, and its hits would differ in the last bit).
/// Everything else here is plain float arithmetic: the build targets no FMA CPU, and ISO C++
/// does not contract a * b + c on its own.
bool embree_fuses() {
    static const bool fused = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return fused;
}

/// Whether this CPU runs the sixteen-lane paths below (to_object16, put_hits16).
bool has_avx512() {
    static const bool avx512 = __builtin_cpu_supports("avx512f");
    return avx512;
}

/// An entry's inverse transform: columns, then the translation.
struct Inverse {
    float l[3][3];
    float p[3];
};
static_assert(sizeof(Inverse) == sizeof(InstanceEntry::to_object));

Inverse inverse_of(const InstanceEntry& e) {
    Inverse t;
    std::memcpy(&t, e.to_object.data(), sizeof t);
    return t;
}

/// The inverse of world transform `w`, computed exactly as Embree computes it for its own
/// instances (rcp(AffineSpace3fa), in its SSE2 common code), so that rays taken through it
/// (to_object) meet the same triangles at the same distances, edges and ties included.
Inverse embree_inverse(const std::array<float, 12>& w) {
    struct V {
        float x, y, z;
    };
    const auto cross = [](const V& a, const V& b) {
        return V{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
    };
    // Embree's columns: vx, vy, vz, then the translation.
    const V vx{w[0], w[4], w[8]}, vy{w[1], w[5], w[9]}, vz{w[2], w[6], w[10]};
    const V rows[3] = {cross(vy, vz), cross(vz, vx), cross(vx, vy)};  // the adjoint's
    const float det = (vx.x * rows[0].x + vx.y * rows[0].y) + vx.z * rows[0].z;
    Inverse t;
    for (int k = 0; k < 3; ++k) {
        t.l[0][k] = rows[k].x / det;
        t.l[1][k] = rows[k].y / det;
        t.l[2][k] = rows[k].z / det;
    }
    for (int k = 0; k < 3; ++k)
        t.p[k] = -(w[3] * t.l[0][k] + (w[7] * t.l[1][k] + w[11] * t.l[2][k]));
    return t;
}

/// Rays in SoA form: origin x, y, z then direction x, y, z, `lanes` wide.
using Soa = float* [6];

/// Takes the `live` lanes of `in` into object space in `out` as Embree's kernels do (xfmPoint,
/// xfmVector), with fused multiply-adds where its kernels have them.
template <bool FUSED>
[[gnu::always_inline]] inline void to_object(const Inverse& t, const Soa& in, const Soa& out,
                                             const int* live, unsigned lanes) {
    const auto mad = [](float x, float y, float z) {
        if constexpr (FUSED) {
            return __builtin_fmaf(x, y, z);
        } else {
            return x * y + z;
        }
    };
    for (unsigned i = 0; i < lanes; ++i) {
        if (!live[i]) continue;
        const float o[3] = {in[0][i], in[1][i], in[2][i]}, d[3] = {in[3][i], in[4][i], in[5][i]};
        for (int k = 0; k < 3; ++k) {
            out[k][i] = mad(o[0], t.l[0][k], mad(o[1], t.l[1][k], mad(o[2], t.l[2][k], t.p[k])));
            out[3 + k][i] = mad(d[0], t.l[0][k], mad(d[1], t.l[1][k], d[2] * t.l[2][k]));
        }
    }
}

__attribute__((target("fma"))) void to_object_fused(const Inverse& t, const Soa& in,
                                                     const Soa& out, const int* live,
                                                     unsigned lanes) {
    to_object<true>(t, in, out, live, lanes);
}

/// All sixteen lanes at once, where the CPU has AVX-512 (Embree's kernels there fuse too).
__attribute__((target("avx512f"))) void to_object16(const Inverse& t, const Soa& in,
                                                    const Soa& out) {
    const __m512 o[3] = {_mm512_loadu_ps(in[0]), _mm512_loadu_ps(in[1]), _mm512_loadu_ps(in[2])};
    const __m512 d[3] = {_mm512_loadu_ps(in[3]), _mm512_loadu_ps(in[4]), _mm512_loadu_ps(in[5])};
    for (int k = 0; k < 3; ++k) {
        const __m512 l0 = _mm512_set1_ps(t.l[0][k]), l1 = _mm512_set1_ps(t.l[1][k]);
        const __m512 l2 = _mm512_set1_ps(t.l[2][k]);
        const __m512 org = _mm512_fmadd_ps(
            o[0], l0, _mm512_fmadd_ps(o[1], l1, _mm512_fmadd_ps(o[2], l2, _mm512_set1_ps(t.p[k]))));
        const __m512 dir =
            _mm512_fmadd_ps(d[0], l0, _mm512_fmadd_ps(d[1], l1, _mm512_mul_ps(d[2], l2)));
        _mm512_storeu_ps(out[k], org);
        _mm512_storeu_ps(out[3 + k], dir);
    }
}

void to_object(const InstanceEntry& e, const Soa& in, const Soa& out, const int* live,
               unsigned lanes) {
    const Inverse t = inverse_of(e);
    if (lanes == 16 && has_avx512() && embree_fuses()) {
        to_object16(t, in, out);  // dead lanes too: their results are never read
    } else if (embree_fuses()) {
        to_object_fused(t, in, out, live, lanes);
    } else {
        to_object<false>(t, in, out, live, lanes);
    }
}

/// The origin and direction arrays of N-wide `ray`.
void soa_of(RTCRayN* ray, unsigned n, Soa& out) {
    out[0] = &RTCRayN_org_x(ray, n, 0), out[1] = &RTCRayN_org_y(ray, n, 0);
    out[2] = &RTCRayN_org_z(ray, n, 0), out[3] = &RTCRayN_dir_x(ray, n, 0);
    out[4] = &RTCRayN_dir_y(ray, n, 0), out[5] = &RTCRayN_dir_z(ray, n, 0);
}

/// The context the instance's BLAS is traced with: the caller's, carrying the slot as the
/// instance id Embree would have pushed. False when the slot's copy is stale (skipped).
bool enter(const RTCIntersectContext* context, unsigned slot, FilterContext& out) {
    const auto* c = reinterpret_cast<const FilterContext*>(context);
    if (c->stale && c->stale[slot]) return false;
    out = *c;
    out.ctx.instID[0] = slot;
    return true;
}

/// A single ray, lane 0 of N-wide `in` (N = 1), in `e`'s object space.
RTCRay single_in(const InstanceEntry& e, RTCRayN* in) {
    RTCRay r = single_ray(in, 1, 0);
    Soa from, to = {&r.org_x, &r.org_y, &r.org_z, &r.dir_x, &r.dir_y, &r.dir_z};
    soa_of(in, 1, from);
    const int live = 1;
    to_object(e, from, to, &live, 1);
    return r;
}

/// Takes the lanes of N-wide `in` that are valid and see `e` into object space in `out`,
/// marks them in `lanes` and deactivates the others (embree_trace::deactivate_unused_lanes).
/// Returns whether any lane is live.
bool gather(const InstanceEntry& e, const int* valid, RTCRayN* in, unsigned n, RTCRay16& out,
            ValidMask16& lanes) {
    bool any = false;
    for (unsigned i = 0; i < 16; ++i) {
        lanes[i] = i < n && valid[i] && (RTCRayN_mask(in, n, i) & e.mask) != 0 ? -1 : 0;
        if (!lanes[i]) {
            out.tnear[i] = 1.0f;
            out.tfar[i] = 0.0f;
            continue;
        }
        out.tnear[i] = RTCRayN_tnear(in, n, i), out.tfar[i] = RTCRayN_tfar(in, n, i);
        out.time[i] = RTCRayN_time(in, n, i), out.mask[i] = RTCRayN_mask(in, n, i);
        out.id[i] = RTCRayN_id(in, n, i), out.flags[i] = RTCRayN_flags(in, n, i);
        any = true;
    }
    if (!any) return false;
    Soa from, to = {out.org_x, out.org_y, out.org_z, out.dir_x, out.dir_y, out.dir_z};
    soa_of(in, n, from);
    to_object(e, from, to, lanes.lanes, std::min(n, 16u));
    return true;
}

/// The world box of `e`'s BLAS: its box taken back through the inverse of `e`'s inverse (centre
/// and half extent) and padded well past the rounding, so that it holds everything rays can meet
/// there.
void array_bounds(const RTCBoundsFunctionArguments* args) {
    const InstanceEntry& e = entry_of(args->geometryUserPtr, args->primID);
    RTCBounds* out = args->bounds_o;
    constexpr float INF = std::numeric_limits<float>::infinity();
    *out = {INF, INF, INF, 0.0f, -INF, -INF, -INF, 0.0f};  // empty: Embree leaves it out
    if (!e.blas) return;
    RTCBounds b;
    rtcGetSceneBounds(e.blas, &b);
    if (!(b.lower_x <= b.upper_x && b.lower_y <= b.upper_y && b.lower_z <= b.upper_z)) return;
    const Inverse t = inverse_of(e);
    const glm::mat3 from = glm::inverse(glm::mat3(t.l[0][0], t.l[0][1], t.l[0][2], t.l[1][0],
                                                  t.l[1][1], t.l[1][2], t.l[2][0], t.l[2][1],
                                                  t.l[2][2]));
    const glm::vec3 lo(b.lower_x, b.lower_y, b.lower_z), hi(b.upper_x, b.upper_y, b.upper_z);
    const glm::vec3 centre = from * (0.5f * (lo + hi) - glm::vec3(t.p[0], t.p[1], t.p[2]));
    const glm::mat3 size(glm::abs(from[0]), glm::abs(from[1]), glm::abs(from[2]));
    const glm::vec3 half = size * (0.5f * (hi - lo));
    const glm::vec3 reach = half + 1e-5f * (half + glm::abs(centre)) + 1e-30f;
    *out = {centre.x - reach.x, centre.y - reach.y, centre.z - reach.z, 0.0f,
            centre.x + reach.x, centre.y + reach.y, centre.z + reach.z, 0.0f};
}

/// Writes the lanes of `local` that hit something into 16-wide `rayhit` (the lanes that were
/// not traced keep their invalid geometry id, so they are left alone too).
__attribute__((target("avx512f"))) void put_hits16(RTCRayHitN* rayhit, const RTCRayHit16& local) {
    constexpr unsigned N = 16;
    const __m512i geom = _mm512_loadu_si512(local.hit.geomID);
    const __mmask16 hit = _mm512_cmpneq_epi32_mask(geom, _mm512_set1_epi32(-1));
    if (!hit) return;
    RTCRayN* ray = RTCRayHitN_RayN(rayhit, N);
    RTCHitN* h = RTCRayHitN_HitN(rayhit, N);
    float* const to[6] = {&RTCRayN_tfar(ray, N, 0), &RTCHitN_Ng_x(h, N, 0),
                          &RTCHitN_Ng_y(h, N, 0),   &RTCHitN_Ng_z(h, N, 0),
                          &RTCHitN_u(h, N, 0),      &RTCHitN_v(h, N, 0)};
    const float* const from[6] = {local.ray.tfar, local.hit.Ng_x, local.hit.Ng_y,
                                  local.hit.Ng_z, local.hit.u,    local.hit.v};
    for (int k = 0; k < 6; ++k) _mm512_mask_storeu_ps(to[k], hit, _mm512_loadu_ps(from[k]));
    unsigned* const ids[3] = {&RTCHitN_primID(h, N, 0), &RTCHitN_geomID(h, N, 0),
                              &RTCHitN_instID(h, N, 0, 0)};
    const unsigned* const id_from[3] = {local.hit.primID, local.hit.geomID, local.hit.instID[0]};
    for (int k = 0; k < 3; ++k)
        _mm512_mask_storeu_epi32(ids[k], hit, _mm512_loadu_si512(id_from[k]));
}

void array_intersect(const RTCIntersectFunctionNArguments* args) {
    const InstanceEntry& e = entry_of(args->geometryUserPtr, args->primID);
    FilterContext context;
    if (!enter(args->context, args->primID, context)) return;
    const unsigned n = args->N;
    RTCRayN* ray = RTCRayHitN_RayN(args->rayhit, n);
    if (n == 1) {
        if (!args->valid[0] || (RTCRayN_mask(ray, 1, 0) & e.mask) == 0) return;
        RTCRayHit rh;
        rh.ray = single_in(e, ray);
        rh.hit.geomID = rh.hit.primID = rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(e.blas, &context.ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID)
            put_hit(args->rayhit, 1, 0, rh.ray.tfar, rh.hit);
        return;
    }
    alignas(64) RTCRayHit16 local;
    ValidMask16 lanes;
    if (!gather(e, args->valid, ray, n, local.ray, lanes)) return;
    for (unsigned i = 0; i < 16; ++i)
        local.hit.geomID[i] = local.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect16(lanes.lanes, e.blas, &context.ctx, &local);
    if (n == 16 && has_avx512()) {
        put_hits16(args->rayhit, local);
        return;
    }
    for (unsigned i = 0; i < n; ++i) {
        if (lanes[i] && local.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
            put_hit(args->rayhit, n, i, local, i);
    }
}

void array_occluded(const RTCOccludedFunctionNArguments* args) {
    const InstanceEntry& e = entry_of(args->geometryUserPtr, args->primID);
    FilterContext context;
    if (!enter(args->context, args->primID, context)) return;
    const unsigned n = args->N;
    constexpr float OCCLUDED = -std::numeric_limits<float>::infinity();
    if (n == 1) {
        if (!args->valid[0] || (RTCRayN_mask(args->ray, 1, 0) & e.mask) == 0) return;
        RTCRay r = single_in(e, args->ray);
        rtcOccluded1(e.blas, &context.ctx, &r);
        if (r.tfar == OCCLUDED) RTCRayN_tfar(args->ray, 1, 0) = OCCLUDED;
        return;
    }
    alignas(64) RTCRay16 local;
    ValidMask16 lanes;
    if (!gather(e, args->valid, args->ray, n, local, lanes)) return;
    rtcOccluded16(lanes.lanes, e.blas, &context.ctx, &local);
    for (unsigned i = 0; i < n; ++i) {
        if (lanes[i] && local.tfar[i] == OCCLUDED) RTCRayN_tfar(args->ray, n, i) = OCCLUDED;
    }
}

}  // namespace

InstanceEntry instance_entry(RTCScene blas, const std::array<float, 12>& world, uint32_t mask) {
    InstanceEntry e;
    e.blas = blas;
    const Inverse t = embree_inverse(world);
    std::memcpy(e.to_object.data(), &t, sizeof t);
    e.mask = mask;
    return e;
}

RTCScene new_instance_array_scene(RTCDevice device, const TlasSceneSetup& setup,
                                  const InstanceTable& table) {
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTCBuildQuality(setup.quality));
    rtcSetSceneFlags(scene, RTCSceneFlags(setup.flags));
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserData(g, const_cast<InstanceTable*>(&table));
    rtcSetGeometryBoundsFunction(g, array_bounds, nullptr);
    rtcSetGeometryIntersectFunction(g, array_intersect);
    rtcSetGeometryOccludedFunction(g, array_occluded);
    rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(table.size()));
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, 0);
    rtcReleaseGeometry(g);
    return scene;
}

void update_instance_array_scene(RTCScene scene, const InstanceTable& table) {
    RTCGeometry g = rtcGetGeometry(scene, 0);
    rtcSetGeometryUserPrimitiveCount(g, static_cast<unsigned>(table.size()));
    rtcCommitGeometry(g);
}

}  // namespace strata
