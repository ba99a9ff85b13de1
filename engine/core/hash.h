#pragma once
// Small integer hashes: sample sequences (render/sampler.h) and per-ray decisions (the blend
// alpha mode's coin, accel/embree_trace.cpp) draw well-mixed bits from them.

#include <cstdint>

namespace strata {

/// A well-mixed 32-bit hash (Wellons' lowbias32).
constexpr uint32_t hash_u32(uint32_t x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

constexpr uint32_t hash_combine(uint32_t seed, uint32_t v) {
    return hash_u32(seed ^ (v + 0x9e3779b9u + (seed << 6) + (seed >> 2)));
}

}  // namespace strata
