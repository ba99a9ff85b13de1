#include "engine/render/primary.h"

#include <algorithm>
#include <cmath>
#include <limits>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "engine/render/camera_rays.h"
#include "engine/render/tiles.h"

namespace strata {

namespace {

/// What the preview shade reads of a hit: its instance's normal matrix and its material's base
/// colour, emission and unlit flag, the colours times their textures as FrameState::surface()
/// applies them. A material without those textures is read in place: surface() copies the whole
/// material, which for every hit cost more than the primary pass's own buffer writes.
struct LaneInputs {
    const glm::mat3* normal_matrix;
    Vec3 base;
    Vec3 emission;
    bool unlit;
};

/// Whether material `material`'s preview colours vary over its surface.
bool preview_textured(const FrameState& frame, uint32_t material) {
    const MaterialTextures& tex = frame.material_textures[material];
    return tex[slot_index(TextureSlot::BaseColor)] || tex[slot_index(TextureSlot::Emissive)];
}

/// The inputs of a hit on `shade` when its material is not preview_textured().
LaneInputs untextured_inputs(const FrameState& frame, const InstanceShade& shade) {
    const Material& m = frame.materials[shade.material];
    return {&shade.normal_matrix, m.base_color, m.emission, m.unlit};
}

LaneInputs lane_inputs(const FrameState& frame, const InstanceShade& shade, uint32_t prim, float u,
                       float v) {
    if (!preview_textured(frame, shade.material)) return untextured_inputs(frame, shade);
    const SurfaceMaterial s =
        frame.surface(shade.material, frame.mesh_shade(shade.mesh_slot), prim, u, v);
    return {&shade.normal_matrix, s.material.base_color, s.material.emission, s.material.unlit};
}

const glm::mat3 IDENTITY{1.0f};
/// The inputs of a miss lane: computed like a hit's, then not used.
const LaneInputs MISS{&IDENTITY, Vec3(0.0f), Vec3(0.0f), true};

/// A packet's shade inputs, one array entry per lane, so that the shade loop vectorises.
struct LaneArrays {
    static constexpr uint32_t N = PACKET_LANES;
    alignas(64) float m[9][N];  ///< normal matrix, glm's column-major order
    alignas(64) float base[3][N];
    alignas(64) float emission[3][N];
    alignas(64) float lit[N];  ///< 1: lit by sun and sky; 0: unlit

    /// The same inputs in every lane: one instance and an untextured material (nearly every
    /// packet), read from the tables once and stored as whole vectors.
    void fill(const LaneInputs& in) {
        const float* mat = &(*in.normal_matrix)[0][0];
        const float b[3] = {in.base.x, in.base.y, in.base.z};
        const float e[3] = {in.emission.x, in.emission.y, in.emission.z};
        for (uint32_t k = 0; k < 9; ++k) std::fill_n(m[k], N, mat[k]);
        for (int c = 0; c < 3; ++c)
            std::fill_n(base[c], N, b[c]), std::fill_n(emission[c], N, e[c]);
        std::fill_n(lit, N, in.unlit ? 0.0f : 1.0f);
    }

    /// Each lane's own inputs: packets across instances or on a textured material.
    void gather(const FrameState& frame, const RayHit16& packet, const float* hit) {
        uint32_t last = INVALID_ID;
        LaneInputs in{};
        for (uint32_t i = 0; i < N; ++i) {
            if (hit[i] == 0.0f) {
                set(i, MISS);
                continue;
            }
            const uint32_t inst = packet.inst_id[i];
            const InstanceShade& shade = frame.instances[inst];
            if (inst != last) {
                in = lane_inputs(frame, shade, packet.prim_id[i], packet.u[i], packet.v[i]);
                // A textured material differs from lane to lane: read it again for the next.
                last = preview_textured(frame, shade.material) ? INVALID_ID : inst;
            }
            set(i, in);
        }
    }

private:
    void set(uint32_t i, const LaneInputs& in) {
        const float* mat = &(*in.normal_matrix)[0][0];
        for (uint32_t k = 0; k < 9; ++k) m[k][i] = mat[k];
        base[0][i] = in.base.x, base[1][i] = in.base.y, base[2][i] = in.base.z;
        emission[0][i] = in.emission.x, emission[1][i] = in.emission.y;
        emission[2][i] = in.emission.z;
        lit[i] = in.unlit ? 0.0f : 1.0f;
    }
};

#if defined(__SSE2__)
/// Lanes of `a` where `mask` is set, of `b` elsewhere.
inline __m128 select(__m128 mask, __m128 a, __m128 b) {
    return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}
inline __m128i select(__m128i mask, __m128i a, __m128i b) {
    return _mm_or_si128(_mm_and_si128(mask, a), _mm_andnot_si128(mask, b));
}
inline __m128i load_ints(const uint32_t* p) {
    return _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
}

/// Stores four points given as coordinate arrays x, y, z (four each) as four packed Vec3.
inline void store_vec3x4(const float* x, const float* y, const float* z, Vec3* out) {
    static_assert(sizeof(Vec3) == 3 * sizeof(float));
    const __m128 X = _mm_loadu_ps(x), Y = _mm_loadu_ps(y), Z = _mm_loadu_ps(z);
    const __m128 xy01 = _mm_unpacklo_ps(X, Y);                             // x0 y0 x1 y1
    const __m128 xy23 = _mm_unpackhi_ps(X, Y);                             // x2 y2 x3 y3
    const __m128 z0x1 = _mm_shuffle_ps(Z, xy01, _MM_SHUFFLE(2, 2, 0, 0));  // z0 z0 x1 x1
    const __m128 y1z1 = _mm_shuffle_ps(xy01, Z, _MM_SHUFFLE(1, 1, 3, 3));  // y1 y1 z1 z1
    const __m128 z2x3 = _mm_shuffle_ps(Z, xy23, _MM_SHUFFLE(2, 2, 2, 2));  // z2 z2 x3 x3
    const __m128 y3z3 = _mm_shuffle_ps(xy23, Z, _MM_SHUFFLE(3, 3, 3, 3));  // y3 y3 z3 z3
    float* f = &out->x;
    _mm_storeu_ps(f, _mm_shuffle_ps(xy01, z0x1, _MM_SHUFFLE(2, 0, 1, 0)));      // x0 y0 z0 x1
    _mm_storeu_ps(f + 4, _mm_shuffle_ps(y1z1, xy23, _MM_SHUFFLE(1, 0, 2, 0)));  // y1 z1 x2 y2
    _mm_storeu_ps(f + 8, _mm_shuffle_ps(z2x3, y3z3, _MM_SHUFFLE(2, 0, 2, 0)));  // z2 x3 y3 z3
}

#endif

/// Where the primary AOVs of one pixel (and the pixels after it in its row) go.
struct PrimaryOut {
    float* distance;
    uint32_t* instance;
    uint32_t* primitive;
    Vec3* normal;
    Vec3* color;

    PrimaryOut at(std::size_t p) const {
        return {distance + p, instance + p, primitive + p, normal + p, color + p};
    }
    /// Prefetches pixels [p, end) for writing.
    void prefetch(std::size_t p, std::size_t end) const {
        prefetch_for_write(distance + p, distance + end);
        prefetch_for_write(instance + p, instance + end);
        prefetch_for_write(primitive + p, primitive + end);
        prefetch_for_write(normal + p, normal + end);
        prefetch_for_write(color + p, color + end);
    }
};

/// One packet's hit buffers and preview, computed over all 16 lanes in loops the compiler
/// vectorises.
struct PacketShade {
    static constexpr uint32_t N = PACKET_LANES;
    alignas(64) float hit[N];  ///< 1: a hit; 0: a miss or a lane outside the image
    alignas(64) float n[3][N];
    alignas(64) float color[3][N];
    LaneArrays in;
    uint32_t filled = INVALID_ID;  ///< the instance `in` holds in every lane (INVALID_ID: none)

    /// Step: which lanes hit; the shade inputs, read once when every hit shares them.
    void shade(const FrameState& frame, const ValidMask16& valid, const RayHit16& packet,
               const Vec3& sun, const Vec3& sun_color, const Vec3& sky) {
        uint32_t first = INVALID_ID;
        for (uint32_t i = 0; i < N; ++i) {
            hit[i] = valid[i] && packet.inst_id[i] != INVALID_ID ? 1.0f : 0.0f;
            if (first == INVALID_ID && hit[i] != 0.0f) first = packet.inst_id[i];
        }
        if (first == INVALID_ID) return fill_misses(sky);
        bool uniform = !preview_textured(frame, frame.instances[first].material);
        for (uint32_t i = 0; i < N; ++i) uniform &= hit[i] == 0.0f || packet.inst_id[i] == first;
        if (!uniform) {
            in.gather(frame, packet, hit);
            filled = INVALID_ID;
        } else if (filled != first) {  // the packet before was filled for another instance
            in.fill(untextured_inputs(frame, frame.instances[first]));
            filled = first;
        }
        shade_lanes(packet, sun, sun_color, sky);
    }

    /// Step: writes lanes [i0, i0 + 4), a whole packet row inside the image, to the pixels
    /// at the given addresses: nine vector stores instead of 36 scalar ones, so the stores of a
    /// packet do not fill the store buffer while the next packet is traced.
    void store_row(uint32_t i0, const RayHit16& packet, const PrimaryOut& out) const {
#if !defined(__SSE2__)
        store_lanes(i0, PACKET_SIZE, packet, out);
#else
        const __m128 hit_mask = _mm_cmpneq_ps(_mm_load_ps(hit + i0), _mm_setzero_ps());
        const __m128i hit_bits = _mm_castps_si128(hit_mask);
        const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
        const __m128i miss = _mm_set1_epi32(int(INVALID_ID));
        _mm_storeu_ps(out.distance, select(hit_mask, _mm_load_ps(packet.tfar + i0), inf));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out.instance),
                         select(hit_bits, load_ints(packet.inst_id + i0), miss));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out.primitive),
                         select(hit_bits, load_ints(packet.prim_id + i0), miss));
        store_vec3x4(n[0] + i0, n[1] + i0, n[2] + i0, out.normal);
        store_vec3x4(color[0] + i0, color[1] + i0, color[2] + i0, out.color);
#endif
    }

    /// store_row() for the first `lanes` lanes of a row, lane by lane (a row the image's edge
    /// cuts).
    void store_lanes(uint32_t i0, uint32_t lanes, const RayHit16& packet,
                     const PrimaryOut& out) const {
        for (uint32_t j = 0; j < lanes; ++j) {
            const uint32_t i = i0 + j;
            const bool h = hit[i] != 0.0f;
            out.distance[j] = h ? packet.tfar[i] : std::numeric_limits<float>::infinity();
            out.instance[j] = h ? packet.inst_id[i] : INVALID_ID;
            out.primitive[j] = h ? packet.prim_id[i] : INVALID_ID;
            out.normal[j] = Vec3(n[0][i], n[1][i], n[2][i]);
            out.color[j] = Vec3(color[0][i], color[1][i], color[2][i]);
        }
    }

private:
    void fill_misses(const Vec3& sky) {
        for (int c = 0; c < 3; ++c) std::fill_n(n[c], N, 0.0f);
        std::fill_n(color[0], N, sky.x);
        std::fill_n(color[1], N, sky.y);
        std::fill_n(color[2], N, sky.z);
    }

    /// Step: n = normalize(M ng) facing the ray; colour = base (sun N.L + sky) + emission, or
    /// base when unlit; misses get no normal and the sky. The same operations in the same order
    /// as glm's mat3 * vec3, normalize and dot, so the same bits as a scalar shade.
    void shade_lanes(const RayHit16& p, const Vec3& sun, const Vec3& sun_color, const Vec3& sky) {
        for (uint32_t i = 0; i < N; ++i) {
            const float gx = p.ng_x[i], gy = p.ng_y[i], gz = p.ng_z[i];
            float x = (in.m[0][i] * gx + in.m[3][i] * gy) + in.m[6][i] * gz;
            float y = (in.m[1][i] * gx + in.m[4][i] * gy) + in.m[7][i] * gz;
            float z = (in.m[2][i] * gx + in.m[5][i] * gy) + in.m[8][i] * gz;
            const float inv = 1.0f / std::sqrt((x * x + y * y) + z * z);
            x *= inv, y *= inv, z *= inv;
            const float to_ray = (x * p.dir_x[i] + y * p.dir_y[i]) + z * p.dir_z[i];
            const float facing = to_ray > 0.0f ? -1.0f : 1.0f;
            x *= facing, y *= facing, z *= facing;
            const float d = (x * sun.x + y * sun.y) + z * sun.z;
            const float l = 0.0f < d ? d : 0.0f;
            const bool h = hit[i] != 0.0f, lit = in.lit[i] != 0.0f;
            n[0][i] = h ? x : 0.0f;
            n[1][i] = h ? y : 0.0f;
            n[2][i] = h ? z : 0.0f;
            const float r = in.base[0][i] * (sun_color.x * l + sky.x) + in.emission[0][i];
            const float g = in.base[1][i] * (sun_color.y * l + sky.y) + in.emission[1][i];
            const float b = in.base[2][i] * (sun_color.z * l + sky.z) + in.emission[2][i];
            color[0][i] = h ? (lit ? r : in.base[0][i]) : sky.x;
            color[1][i] = h ? (lit ? g : in.base[1][i]) : sky.y;
            color[2][i] = h ? (lit ? b : in.base[2][i]) : sky.z;
        }
    }
};

}  // namespace

AovSet primary_aovs() {
    AovSet set;
    for (Aov a : {Aov::Depth, Aov::InstanceId, Aov::PrimitiveId, Aov::Normal}) set.add(a);
    return set;
}

void render_primary(const TlasStrategy& tlas, const FrameState& frame,
                    const PrimarySettings& settings, FrameBuffers& out) {
    // Every pixel is written below, so buffers of the right size are reused as they are.
    out.reserve_frame(settings.width, settings.height, primary_aovs());
    if (settings.width == 0 || settings.height == 0) return;
    const CameraRays rays(settings.camera.value_or(frame.camera), settings.width, settings.height);
    const Lighting& light = frame.lighting;
    const Vec3 background = light.sky_color * light.sky_intensity;
    const Vec3 sun = glm::normalize(light.sun_direction);

    const PrimaryOut pixels{out.depth.data(), out.instance_id.data(), out.primitive_id.data(),
                            out.normal.data(), out.color.data()};
    const std::optional<HitTest> test = frame.hit_test();

    parallel_for_tiles(settings.width, settings.height, [&](const TileRect& tile) {
        CameraPacket camera(rays, settings.ray_mask);
        ValidMask16 valid;
        PacketShade s;
        for (uint32_t y0 = tile.y0; y0 < tile.y1; y0 += PACKET_SIZE) {
            // The output rows are short pieces of five large arrays, too scattered for the
            // hardware prefetcher: ask for a packet row's cache lines while its rays are traced
            // instead of stalling on each first store.
            for (uint32_t y = y0; y < std::min(y0 + PACKET_SIZE, tile.y1); ++y) {
                const std::size_t row = std::size_t(y) * settings.width;
                pixels.prefetch(row + tile.x0, row + tile.x1);
            }
            for (uint32_t x0 = tile.x0; x0 < tile.x1; x0 += PACKET_SIZE) {
                // Step: pixel-centre rays; lanes outside the image are off.
                packet_lanes(tile, x0, y0, valid);
                RayHit16& packet = camera.aim_centres(x0, y0);
                tlas.intersect16(valid, packet, true, test ? &*test : nullptr);
                s.shade(frame, valid, packet, sun, light.sun_color, background);

                // Step: write the hit buffers, a packet row at a time (the image's edges cut
                // rows short and leave rows out).
                const uint32_t lanes = std::min(PACKET_SIZE, tile.x1 - x0);
                for (uint32_t r = 0; r < PACKET_SIZE && y0 + r < tile.y1; ++r) {
                    const uint32_t i0 = r * PACKET_SIZE;
                    const PrimaryOut row = pixels.at(std::size_t(y0 + r) * settings.width + x0);
                    if (lanes == PACKET_SIZE)
                        s.store_row(i0, packet, row);
                    else
                        s.store_lanes(i0, lanes, packet, row);
                }
            }
        }
    });
}

}  // namespace strata
