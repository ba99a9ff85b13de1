#include "engine/accel/embree_trace.h"

#include <cstring>

#include "engine/core/hash.h"

namespace strata::embree_trace {

namespace {

uint32_t bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

}  // namespace

void filter_hits(const RTCFilterFunctionNArguments* args) {
    const auto* c = reinterpret_cast<const FilterContext*>(args->context);
    const unsigned n = args->N;
    for (unsigned i = 0; i < n; ++i) {
        if (args->valid[i] == 0) continue;
        const uint32_t inst = RTCHitN_instID(args->hit, n, i, 0);
        const uint32_t slot = c->slot(inst);
        if (c->stale && c->stale[slot]) {
            args->valid[i] = 0;
            continue;
        }
        if (!c->test) continue;
        const uint32_t prim = c->tlas->mesh_triangle(slot, RTCHitN_geomID(args->hit, n, i),
                                                     RTCHitN_primID(args->hit, n, i));
        uint32_t seed = hash_combine(slot, prim);
        seed = hash_combine(seed, bits(RTCRayN_org_x(args->ray, n, i)));
        seed = hash_combine(seed, bits(RTCRayN_org_y(args->ray, n, i)));
        seed = hash_combine(seed, bits(RTCRayN_org_z(args->ray, n, i)));
        seed = hash_combine(seed, bits(RTCRayN_dir_x(args->ray, n, i)));
        seed = hash_combine(seed, bits(RTCRayN_dir_y(args->ray, n, i)));
        seed = hash_combine(seed, bits(RTCRayN_dir_z(args->ray, n, i)));
        if (!c->test->keep(c->test->user, slot, prim, RTCHitN_u(args->hit, n, i),
                           RTCHitN_v(args->hit, n, i), seed))
            args->valid[i] = 0;
    }
}

}  // namespace strata::embree_trace
