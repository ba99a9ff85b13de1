#pragma once
// The fixed tile grid launches run over, and helpers to fill ray packets.
//
// Tiles are TILE_SIZE squares at fixed positions and packets are the PACKET_SIZE squares inside
// them, so which rays travel together never depends on TBB's splitting or on the thread count:
// with every pixel computed from its own sample sequence, a frame is the same bytes however it
// was scheduled.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "engine/accel/ray.h"
#include "engine/core/math.h"
#include "engine/render/camera_rays.h"

namespace strata {

/// Pixels per tile side; one tile is one unit of TBB work.
constexpr uint32_t TILE_SIZE = 16;
/// Pixels per packet side: a packet is 4x4 = 16 rays.
constexpr uint32_t PACKET_SIZE = 4;
constexpr uint32_t PACKET_LANES = PACKET_SIZE * PACKET_SIZE;
static_assert(TILE_SIZE % PACKET_SIZE == 0);

/// A tile's pixel rectangle [x0, x1) x [y0, y1).
struct TileRect {
    uint32_t x0, y0, x1, y1;
};

/// Calls `f(const TileRect&)` for every tile of a width x height image that overlaps rows
/// [row_begin, row_end), clipped to them, in parallel. With `row_begin` a multiple of
/// PACKET_SIZE and `row_end` a multiple of it or `height`, every packet of those rows has the
/// pixels and lanes it has in the whole image (packet_lanes).
template <class F>
void parallel_for_tile_rows(uint32_t width, uint32_t height, uint32_t row_begin, uint32_t row_end,
                            F&& f) {
    row_end = std::min(row_end, height);
    if (row_begin >= row_end || width == 0) return;
    const uint32_t cols = (width + TILE_SIZE - 1) / TILE_SIZE;
    const uint32_t first = row_begin / TILE_SIZE;
    const uint32_t rows = (row_end + TILE_SIZE - 1) / TILE_SIZE - first;
    auto run = [&](const tbb::blocked_range<uint32_t>& range) {
        for (uint32_t t = range.begin(); t != range.end(); ++t) {
            const uint32_t x0 = (t % cols) * TILE_SIZE;
            const uint32_t y0 = (first + t / cols) * TILE_SIZE;
            f(TileRect{x0, std::max(y0, row_begin), std::min(x0 + TILE_SIZE, width),
                       std::min(y0 + TILE_SIZE, row_end)});
        }
    };
    tbb::parallel_for(tbb::blocked_range<uint32_t>(0, cols * rows), run);
}

/// Calls `f(const TileRect&)` for every tile of a width x height image, in parallel.
template <class F>
void parallel_for_tiles(uint32_t width, uint32_t height, F&& f) {
    parallel_for_tile_rows(width, height, 0, height, std::forward<F>(f));
}

/// Marks the lanes of the packet at (x0, y0) that fall inside the tile; returns how many do.
/// Lane i is pixel (x0 + i % PACKET_SIZE, y0 + i / PACKET_SIZE).
inline uint32_t packet_lanes(const TileRect& tile, uint32_t x0, uint32_t y0, ValidMask16& valid) {
    uint32_t active = 0;
    for (uint32_t i = 0; i < PACKET_LANES; ++i) {
        const bool inside = x0 + i % PACKET_SIZE < tile.x1 && y0 + i / PACKET_SIZE < tile.y1;
        valid[i] = inside ? -1 : 0;
        active += inside;
    }
    return active;
}

/// A packet of camera rays from one eye. Fields Embree never writes (origin, tnear, time, mask,
/// id, flags) are set once; aiming a packet writes only directions and resets the hit.
class CameraPacket {
public:
    CameraPacket(const CameraRays& rays, uint32_t mask = 0xFFFFFFFFu) : m_rays(rays) {
        const Vec3 eye = rays.eye();
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            m_packet.org_x[i] = eye.x;
            m_packet.org_y[i] = eye.y;
            m_packet.org_z[i] = eye.z;
            m_packet.tnear[i] = 0.0f;
            m_packet.time[i] = rays.time(0.0f);
            m_packet.mask[i] = mask;
            m_packet.id[i] = i;
            m_packet.flags[i] = 0;
            // Embree writes these on hits only; shading that reads every lane must not meet
            // indeterminate values on a miss.
            m_packet.ng_x[i] = m_packet.ng_y[i] = m_packet.ng_z[i] = 0.0f;
            m_packet.u[i] = m_packet.v[i] = 0.0f;
        }
    }

    /// Aims lane i through image position (x[i], y[i]) at ray time `times[i]` (null: the
    /// shutter's opening) and clears the hit of every lane.
    RayHit16& aim(const float* x, const float* y, const float* times = nullptr) {
        m_rays.directions(x, y, PACKET_LANES, m_packet.dir_x, m_packet.dir_y, m_packet.dir_z);
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            m_packet.time[i] = times ? times[i] : m_rays.time(0.0f);
            m_packet.tfar[i] = std::numeric_limits<float>::infinity();
            m_packet.geom_id[i] = INVALID_ID;
            m_packet.inst_id[i] = INVALID_ID;
            m_packet.prim_id[i] = INVALID_ID;
        }
        return m_packet;
    }

    /// Aims the packet through the centres of the 4x4 pixels at (x0, y0).
    RayHit16& aim_centres(uint32_t x0, uint32_t y0) {
        float x[PACKET_LANES], y[PACKET_LANES];
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            x[i] = float(x0 + i % PACKET_SIZE) + 0.5f;
            y[i] = float(y0 + i / PACKET_SIZE) + 0.5f;
        }
        return aim(x, y);
    }

    RayHit16& packet() { return m_packet; }

private:
    const CameraRays& m_rays;
    alignas(64) RayHit16 m_packet;
};

/// Sets the ray fields shared by closest-hit and shadow packets.
template <class Packet>
void set_ray(Packet& p, uint32_t i, const Vec3& org, const Vec3& dir, float tnear, uint32_t mask) {
    p.org_x[i] = org.x;
    p.org_y[i] = org.y;
    p.org_z[i] = org.z;
    p.tnear[i] = tnear;
    p.dir_x[i] = dir.x;
    p.dir_y[i] = dir.y;
    p.dir_z[i] = dir.z;
    p.time[i] = 0.0f;
    p.tfar[i] = std::numeric_limits<float>::infinity();
    p.mask[i] = mask;
    p.id[i] = i;
    p.flags[i] = 0;
}

/// Sets lane i of a closest-hit packet to the ray org + t * dir, t in [tnear, inf).
inline void set_lane(RayHit16& p, uint32_t i, const Vec3& org, const Vec3& dir, float tnear = 0.0f,
                     uint32_t mask = 0xFFFFFFFFu) {
    set_ray(p, i, org, dir, tnear, mask);
    p.geom_id[i] = INVALID_ID;
    p.inst_id[i] = INVALID_ID;
    p.prim_id[i] = INVALID_ID;
}

/// Sets lane i of a shadow packet to the ray org + t * dir, t in [0, inf).
inline void set_lane(Ray16& p, uint32_t i, const Vec3& org, const Vec3& dir,
                     uint32_t mask = 0xFFFFFFFFu) {
    set_ray(p, i, org, dir, 0.0f, mask);
}

/// Prefetches the cache lines of [begin, end) for writing.
template <class T>
inline void prefetch_for_write(const T* begin, const T* end) {
    const char* p = reinterpret_cast<const char*>(begin);
    const char* e = reinterpret_cast<const char*>(end);
    for (p -= reinterpret_cast<uintptr_t>(p) % 64; p < e; p += 64) __builtin_prefetch(p, 1, 3);
}

/// Largest ray coordinate Embree accepts (its FLT_LARGE); it asserts on rays beyond it.
constexpr float MAX_RAY_COORDINATE = 1.8e18f;

/// True when rays may start at `o`: finite and within MAX_RAY_COORDINATE. Scene validation keeps
/// cameras and translations far inside; this catches what arithmetic can still produce (a hit
/// on geometry at the edge of Embree's range, pushed off its surface).
inline bool ray_origin_ok(const Vec3& o) {
    return std::abs(o.x) <= MAX_RAY_COORDINATE && std::abs(o.y) <= MAX_RAY_COORDINATE &&
           std::abs(o.z) <= MAX_RAY_COORDINATE;
}

/// Origin for rays leaving a surface point p (reached at distance t from a ray starting at
/// `from`): p pushed off the surface along the normal n by an epsilon that scales with the
/// magnitudes that bound p's rounding error, so secondary rays do not hit the surface they leave.
inline Vec3 offset_origin(const Vec3& p, const Vec3& n, const Vec3& from, float t) {
    const Vec3 a = glm::abs(from);
    const float scale = std::max(std::max(t, 1e-3f), std::max(a.x, std::max(a.y, a.z)));
    return p + n * (scale * 0x1p-15f);
}

}  // namespace strata
