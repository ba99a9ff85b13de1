#include "engine/render/renderer.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <new>

#include "engine/core/timer.h"
#include "engine/render/aov_filter.h"
#include "engine/render/camera_rays.h"
#include "engine/render/sampler.h"
#include "engine/render/shading.h"
#include "engine/render/tiles.h"

namespace strata {

namespace {

// Sample dimensions: group 0 is the pixel jitter and the bounce direction, dimension 4 (group 1)
// picks the BRDF lobe, groups 2 and 3 choose a point on a light at the first and second surface.
constexpr uint32_t DIM_LOBE = 4;
constexpr uint32_t DIM_TIME = 5;  ///< where in the shutter interval a camera sample is taken
constexpr uint32_t DIM_GROUP_LIGHT = 2;

/// Shadow rays toward a light point stop this far short of it (relative): an emitting triangle
/// must not shadow itself.
constexpr float SHADOW_SHORTEN = 0.999f;

/// Multiple importance sampling weight of a strategy of density `a` against one of density `b`
/// (Veach's power heuristic, beta = 2).
float power_heuristic(float a, float b) {
    if (!(b > 0.0f)) return 1.0f;
    if (!(a > 0.0f)) return 0.0f;
    // As ratios, so that huge densities (near-mirror lobes) cannot overflow.
    if (a >= b) {
        const float r = b / a;
        return 1.0f / (1.0f + r * r);
    }
    const float r = a / b;
    return r * r / (1.0f + r * r);
}

/// Samples of one packet between two polls of the cancel token.
constexpr uint32_t CANCEL_POLL_SAMPLES = 16;

Unexpected<Error> cancelled_error(const CancelToken& token) {
    return failure(ErrorCode::Cancelled, std::string("the render stopped early: ") +
                                                cancel_reason_text(token.reason()));
}

static_assert(MAX_ACCUMULATED_SAMPLES <= PixelSampler::MAX_SAMPLES &&
              MAX_RENDER_SPP <= PixelSampler::MAX_SAMPLES);

/// A surface a ray reached, prepared for shading.
struct SurfaceHit {
    Vec3 position;
    Vec3 normal;    ///< shading normal: unit, facing the incoming ray
    Vec3 geometry;  ///< geometric normal: unit, facing the incoming ray
    Vec3 origin;    ///< where rays leaving the surface start
    float time;     ///< the ray time it was hit at: rays leaving it see the scene then
    uint32_t material;      ///< index into FrameState::materials
    SurfaceMaterial shade;  ///< the material with its textures read at the hit

    /// True when direction `l` leaves on the side the ray came from. Shading normals may lean
    /// past the true surface; light from behind it must not leak through.
    bool above(const Vec3& l) const { return glm::dot(geometry, l) > 0.0f; }
};

/// Least cosine between a shading normal and the view direction: a shading normal that leans
/// away from the viewer (silhouettes of coarse smooth meshes) is bent back just enough.
constexpr float MIN_SHADING_COS = 0.01f;

/// The shading normal at a hit: the interpolated vertex normal `ns` (world space, unnormalised),
/// turned to the side of the geometric normal `ng` (unit, facing the viewer) and bent toward the
/// viewer `v` so that the view is above it.
Vec3 shading_normal(Vec3 ns, const Vec3& ng, const Vec3& v) {
    const float len2 = glm::dot(ns, ns);
    if (!(len2 > 0.0f) || !std::isfinite(len2)) return ng;
    ns /= std::sqrt(len2);
    if (glm::dot(ns, ng) < 0.0f) ns = -ns;
    const float c = glm::dot(ns, v);
    if (c < MIN_SHADING_COS) {
        ns = glm::normalize(ns + (MIN_SHADING_COS - c) * v);
        if (!is_finite(ns)) return ng;
    }
    return ns;
}

/// The normal a normal map gives: `tn` (tangent space) in the frame of the interpolated tangent
/// `t4` and normal `n` (object space) of a mesh, taken to world space by `normal_matrix`.
Vec3 mapped_normal(const Vec3& tn, const glm::vec4& t4, const Vec3& n,
                   const glm::mat3& normal_matrix) {
    const Vec3 t(t4);
    const Vec3 b = glm::cross(n, t) * (t4.w < 0.0f ? -1.0f : 1.0f);
    // Tangents transform as directions: by the linear part, the inverse transpose of normals'.
    const glm::mat3 linear = glm::transpose(glm::inverse(normal_matrix));
    const auto unit = [](const Vec3& v) {
        const float l = glm::length(v);
        return l > 0.0f && std::isfinite(l) ? v / l : Vec3(0.0f);
    };
    return tn.x * unit(linear * t) + tn.y * unit(linear * b) + tn.z * unit(normal_matrix * n);
}

/// Everything one launch's tiles share. `out` holds rows [row0, row0 + out.height) of a
/// out.width x `frame_height` frame; tiles may trace rows beyond them (whole packets), which are
/// not written.
class FrameKernel {
public:
    FrameKernel(const TlasStrategy& tlas, const FrameState& frame, const Camera& camera,
                FrameBuffers& out, uint32_t frame_height, uint32_t row0, SampleRange samples,
                uint32_t total_samples, PixelSums* accum, float* variance,
                const CancelToken* cancel)
        : m_tlas(tlas),
          m_frame(frame),
          m_rays(camera, out.width, frame_height),
          m_sky(frame.lighting),
          m_out(out),
          m_row0(row0),
          m_row1(row0 + out.height),
          m_samples(samples),
          m_inv_total(total_samples > 0 ? 1.0f / float(total_samples) : 0.0f),
          m_total(total_samples),
          m_accum(accum),
          m_variance(variance),
          m_cancel(cancel),
          m_hit_test(frame.hit_test()) {}

    void render_tile(const TileRect& tile) const {
        PixelSums local[TILE_SIZE * TILE_SIZE];
        CameraPacket camera(m_rays);
        uint64_t rays = 0;
        for (uint32_t y0 = tile.y0; y0 < tile.y1; y0 += PACKET_SIZE) {
            for (uint32_t x0 = tile.x0; x0 < tile.x1; x0 += PACKET_SIZE) {
                // A cancelled launch leaves the rest of the frame unwritten; render() discards it.
                if (should_stop(m_cancel)) return;
                ValidMask16 valid;
                packet_lanes(tile, x0, y0, valid);
                PixelSums* sums[PACKET_LANES];
                for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                    const uint32_t x = x0 + i % PACKET_SIZE, y = y0 + i / PACKET_SIZE;
                    if (!valid[i]) {
                        sums[i] = nullptr;
                    } else if (m_accum) {
                        sums[i] = &m_accum[std::size_t(y) * m_out.width + x];
                    } else {
                        sums[i] = &local[(y - tile.y0) * TILE_SIZE + (x - tile.x0)];
                        *sums[i] = PixelSums{};
                    }
                }
                PixelSampler samplers[PACKET_LANES];
                for (uint32_t i = 0; i < PACKET_LANES; ++i)
                    samplers[i] = PixelSampler(x0 + i % PACKET_SIZE, y0 + i / PACKET_SIZE);
                for (uint32_t s = 0; s < m_samples.count; ++s) {
                    // At thousands of samples a packet takes long enough to poll inside it too.
                    if (s % CANCEL_POLL_SAMPLES == CANCEL_POLL_SAMPLES - 1 && should_stop(m_cancel))
                        return;
                    rays +=
                        trace_sample(camera, samplers, x0, y0, valid, m_samples.first + s, sums);
                }
                if (m_out.aovs.needs_centre_ray()) rays += trace_centre(camera, x0, y0, valid);
                resolve(x0, y0, valid, sums);
            }
        }
        m_ray_count.fetch_add(rays, std::memory_order_relaxed);
    }

    uint64_t rays() const { return m_ray_count.load(); }

private:
    /// Shading data of the surface lane i of `hits` reached.
    SurfaceHit surface(const RayHit16& hits, uint32_t i) const {
        const InstanceShade& inst = m_frame.instances[hits.inst_id[i]];
        const Vec3 dir(hits.dir_x[i], hits.dir_y[i], hits.dir_z[i]);
        const Vec3 org(hits.org_x[i], hits.org_y[i], hits.org_z[i]);
        const glm::mat3 normals = inst.normals_at(hits.time[i]);
        Vec3 n = normals * Vec3(hits.ng_x[i], hits.ng_y[i], hits.ng_z[i]);
        const float len2 = glm::dot(n, n);
        n = len2 > 0.0f ? n / std::sqrt(len2) : -dir;
        if (glm::dot(n, dir) > 0.0f) n = -n;
        SurfaceHit s;
        s.position = org + hits.tfar[i] * dir;
        s.geometry = n;
        s.normal = n;
        const MeshShade* mesh = m_frame.mesh_shade(inst.mesh_slot);
        const uint32_t prim = hits.prim_id[i];
        s.material = inst.material;
        s.shade = m_frame.surface(inst.material, mesh, prim, hits.u[i], hits.v[i]);
        if (mesh && !mesh->normals.empty() && prim < mesh->triangles.size()) {
            const Vec3 normal = mesh->normal(prim, hits.u[i], hits.v[i]);
            const Vec3 ns = s.shade.normal_mapped
                                ? mapped_normal(s.shade.tangent_normal,
                                                mesh->tangent(prim, hits.u[i], hits.v[i]), normal,
                                                normals)
                                : normals * normal;
            s.normal = shading_normal(ns, n, -dir);
        }
        s.origin = offset_origin(s.position, n, org, hits.tfar[i]);
        s.time = hits.time[i];
        return s;
    }

    /// The hit test the launch traces with (alpha cut-outs), or null.
    const HitTest* test() const { return m_hit_test ? &*m_hit_test : nullptr; }

    /// Shadow rays from up to one surface per lane, each with the radiance it adds to its lane
    /// when nothing blocks it.
    struct ShadowQueue {
        alignas(64) Ray16 rays;
        ValidMask16 valid = {};
        Vec3 add[PACKET_LANES];
        bool any = false;

        void push(uint32_t i, const SurfaceHit& from, const Vec3& dir, float tfar,
                  const Vec3& value) {
            set_lane(rays, i, from.origin, dir);
            rays.time[i] = from.time;
            rays.tfar[i] = tfar;
            add[i] = value;
            valid[i] = -1;
            any = true;
        }
    };

    /// Queues lane i's shadow ray toward the sun when `hit` faces it, seen through `bsdf` from `v`.
    void queue_sun(ShadowQueue& q, uint32_t i, const SurfaceHit& hit, const Bsdf& bsdf,
                   const Vec3& v) const {
        if (!m_sky.has_sun() || glm::dot(hit.normal, m_sky.sun_direction()) <= 0.0f) return;
        if (!hit.above(m_sky.sun_direction())) return;
        if (!ray_origin_ok(hit.origin)) return;
        const Vec3 f = bsdf.eval_cos(hit.normal, v, m_sky.sun_direction());
        if (f.x <= 0.0f && f.y <= 0.0f && f.z <= 0.0f) return;
        q.push(i, hit, m_sky.sun_direction(), std::numeric_limits<float>::infinity(),
               f * m_sky.sun_irradiance());
    }

    /// Queues lane i's shadow ray toward a point chosen on the scene's lights (next-event
    /// estimation) with the 3 numbers in `u`. `mis`: a bounce ray from this surface may also reach
    /// emitting triangles, so their share is weighted by the power heuristic.
    void queue_light(ShadowQueue& q, uint32_t i, const SurfaceHit& hit, const Bsdf& bsdf,
                     const Vec3& v, const std::array<float, 4>& u, bool mis) const {
        if (!ray_origin_ok(hit.origin)) return;
        const LightSample s = m_frame.lights.sample(hit.origin, u[0], u[1], u[2]);
        if (!s.valid || !hit.above(s.dir)) return;
        Vec3 f = bsdf.eval_cos(hit.normal, v, s.dir);
        if (f.x <= 0.0f && f.y <= 0.0f && f.z <= 0.0f) return;
        if (mis && s.pdf > 0.0f) f *= power_heuristic(s.pdf, bsdf.pdf(hit.normal, v, s.dir));
        q.push(i, hit, s.dir, s.distance * SHADOW_SHORTEN, f * s.weight);
    }

    /// Traces the queued shadow rays and adds the radiance of each unblocked one to its lane.
    /// Returns the rays traced.
    uint64_t trace_shadows(ShadowQueue& q, Vec3* radiance) const {
        if (!q.any) return 0;
        m_tlas.occluded16(q.valid, q.rays, test(), &m_rays.eye());
        uint64_t rays = 0;
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            if (!q.valid[i]) continue;
            ++rays;
            if (q.rays.tfar[i] != -std::numeric_limits<float>::infinity()) radiance[i] += q.add[i];
        }
        return rays;
    }

    /// Traces sample `index` of the packet's pixels and adds it to their sums; returns the rays.
    uint64_t trace_sample(CameraPacket& camera, const PixelSampler* samplers, uint32_t x0,
                          uint32_t y0, const ValidMask16& valid, uint32_t index,
                          PixelSums* const* sums) const {
        uint64_t rays = 0;

        // Step: camera rays, jittered by the pixel's own sequence.
        float px[PACKET_LANES], py[PACKET_LANES], time[PACKET_LANES];
        float bounce_u[PACKET_LANES][3];
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            const uint32_t x = x0 + i % PACKET_SIZE, y = y0 + i / PACKET_SIZE;
            px[i] = float(x) + 0.5f;
            py[i] = float(y) + 0.5f;
            time[i] = m_rays.time(0.0f);
            if (!valid[i]) continue;
            const PixelSampler& sampler = samplers[i];
            const auto u = sampler.get4(index, 0);
            px[i] = float(x) + u[0];
            py[i] = float(y) + u[1];
            bounce_u[i][0] = u[2];
            bounce_u[i][1] = u[3];
            bounce_u[i][2] = sampler.get1(index, DIM_LOBE);
            if (m_rays.blurs()) time[i] = m_rays.time(sampler.get1(index, DIM_TIME));
            ++rays;
        }
        const RayHit16& primary = camera.aim(px, py, time);
        m_tlas.intersect16(valid, camera.packet(), true, test(), &m_rays.eye());

        // Step: shade first hits; queue shadow rays (sun, lights) and bounce rays.
        const bool lights = !m_frame.lights.empty();
        Vec3 radiance[PACKET_LANES];
        Vec3 weight[PACKET_LANES];
        float bounce_pdf[PACKET_LANES];
        float first_roughness[PACKET_LANES] = {};
        alignas(64) RayHit16 bounce;
        ValidMask16 bounce_valid = {};
        bool any_bounce = false;
        ShadowQueue sun, light;
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            if (!valid[i]) continue;
            const Vec3 dir(primary.dir_x[i], primary.dir_y[i], primary.dir_z[i]);
            if (primary.inst_id[i] == INVALID_ID) {
                radiance[i] = m_sky.radiance(dir);
                add_color(*sums[i], radiance[i]);
                continue;
            }
            const SurfaceHit hit = surface(primary, i);
            const Material& m = hit.shade.material;
            sums[i]->albedo += m.base_color;
            sums[i]->normal += hit.normal;
            if (m.unlit) {
                radiance[i] = m.base_color;
                continue;
            }
            const Bsdf bsdf(m);
            radiance[i] = m.emission;
            first_roughness[i] = m.roughness;
            queue_sun(sun, i, hit, bsdf, -dir);
            if (lights)
                queue_light(light, i, hit, bsdf, -dir, samplers[i].get4(index, DIM_GROUP_LIGHT),
                            true);
            const BsdfSample b =
                bsdf.sample(hit.normal, -dir, bounce_u[i][0], bounce_u[i][1], bounce_u[i][2]);
            if (b.valid && hit.above(b.dir) && ray_origin_ok(hit.origin)) {
                set_lane(bounce, i, hit.origin, b.dir);
                bounce.time[i] = hit.time;
                weight[i] = b.weight * hit.shade.occlusion;
                bounce_pdf[i] = b.pdf;
                bounce_valid[i] = -1;
                any_bounce = true;
            }
        }

        // Step: direct light at first hits.
        rays += trace_shadows(sun, radiance);
        rays += trace_shadows(light, radiance);

        // Step: one bounce, ended by the sky or by direct light at the second surface.
        if (any_bounce) {
            m_tlas.intersect16(bounce_valid, bounce, false, test(), &m_rays.eye());
            Vec3 incoming[PACKET_LANES];
            ShadowQueue sun2, light2;
            for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                if (!bounce_valid[i]) continue;
                ++rays;
                const Vec3 dir(bounce.dir_x[i], bounce.dir_y[i], bounce.dir_z[i]);
                if (bounce.inst_id[i] == INVALID_ID) {
                    incoming[i] = m_sky.radiance(dir);
                    continue;
                }
                const SurfaceHit hit = surface(bounce, i);
                const Material& m = hit.shade.material;
                if (m.unlit) {
                    incoming[i] = m.base_color;
                    continue;
                }
                // An emitter in the light table was also sampled at the first hit: weigh its
                // emission against that strategy.
                float emission_weight = 1.0f;
                if (lights && m_frame.is_emitter(bounce.inst_id[i])) {
                    const float pdf_light =
                        m_frame.lights.emitter_pdf(m_frame.emitter_emission[hit.material],
                                                   bounce.tfar[i], glm::dot(hit.geometry, -dir));
                    emission_weight = power_heuristic(bounce_pdf[i], pdf_light);
                }
                incoming[i] = m.emission * emission_weight +
                              m.base_color * m_sky.radiance(hit.normal) * hit.shade.occlusion;
                const Bsdf bsdf(m, std::max(MIN_SECONDARY_ROUGHNESS, first_roughness[i]));
                queue_sun(sun2, i, hit, bsdf, -dir);
                // The path ends here: light sampling is the only strategy, so no MIS.
                if (lights)
                    queue_light(light2, i, hit, bsdf, -dir,
                                samplers[i].get4(index, DIM_GROUP_LIGHT + 1), false);
            }
            rays += trace_shadows(sun2, incoming);
            rays += trace_shadows(light2, incoming);
            for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                if (bounce_valid[i])
                    radiance[i] += clamp_max_component(weight[i] * incoming[i], INDIRECT_CLAMP);
            }
        }

        // Step: add the sample's radiance of every hit lane (misses were added above).
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            if (valid[i] && primary.inst_id[i] != INVALID_ID) add_color(*sums[i], radiance[i]);
        }
        return rays;
    }

    /// Where pixel (x, y) of the frame lies in the output buffers, or SIZE_MAX for a row the
    /// buffers do not hold.
    std::size_t out_index(uint32_t x, uint32_t y) const {
        if (y < m_row0 || y >= m_row1) return SIZE_MAX;
        return std::size_t(y - m_row0) * m_out.width + x;
    }

    static void add_color(PixelSums& sums, const Vec3& radiance) {
        sums.color += radiance;
        const float l = luminance(radiance);
        sums.luminance2 += l * l;
    }

    /// Traces the unjittered pixel-centre rays and writes depth, position and ids.
    uint64_t trace_centre(CameraPacket& camera, uint32_t x0, uint32_t y0,
                          const ValidMask16& valid) const {
        const Vec3 eye = m_rays.eye();
        uint64_t rays = 0;
        for (uint32_t i = 0; i < PACKET_LANES; ++i) rays += valid[i] != 0;
        RayHit16& packet = camera.aim_centres(x0, y0);
        m_tlas.intersect16(valid, packet, true, test(), &m_rays.eye());
        const AovSet aovs = m_out.aovs;
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            if (!valid[i]) continue;
            const std::size_t p = out_index(x0 + i % PACKET_SIZE, y0 + i / PACKET_SIZE);
            if (p == SIZE_MAX) continue;
            const uint32_t inst = packet.inst_id[i];
            const bool hit = inst != INVALID_ID;
            const float t = hit ? packet.tfar[i] : std::numeric_limits<float>::infinity();
            if (aovs.has(Aov::Depth)) m_out.depth[p] = t;
            if (aovs.has(Aov::Position)) {
                m_out.position[p] =
                    hit ? eye + t * Vec3(packet.dir_x[i], packet.dir_y[i], packet.dir_z[i])
                        : Vec3(0.0f);
            }
            if (aovs.has(Aov::InstanceId)) m_out.instance_id[p] = hit ? inst : MISS_ID;
            if (aovs.has(Aov::PrimitiveId))
                m_out.primitive_id[p] = hit ? packet.prim_id[i] : MISS_ID;
            if (aovs.has(Aov::MeshId))
                m_out.mesh_id[p] = hit ? m_frame.instances[inst].mesh_slot : MISS_ID;
            if (aovs.has(Aov::UserId))
                m_out.user_id[p] = hit ? m_frame.instances[inst].user_id : MISS_ID;
        }
        return rays;
    }

    /// Writes the averages of the packet's sums to the output buffers.
    void resolve(uint32_t x0, uint32_t y0, const ValidMask16& valid, PixelSums* const* sums) const {
        const AovSet aovs = m_out.aovs;
        for (uint32_t i = 0; i < PACKET_LANES; ++i) {
            if (!valid[i]) continue;
            const std::size_t p = out_index(x0 + i % PACKET_SIZE, y0 + i / PACKET_SIZE);
            if (p == SIZE_MAX) continue;
            m_out.color[p] = sums[i]->color * m_inv_total;
            if (m_variance) {
                // The variance of the mean of independent samples, s^2 / n (aov_filter.h).
                const float mean = luminance(sums[i]->color) * m_inv_total;
                const float spread = sums[i]->luminance2 * m_inv_total - mean * mean;
                m_variance[p] = std::max(0.0f, spread) / float(m_total - 1);
            }
            if (aovs.has(Aov::Albedo)) m_out.albedo[p] = sums[i]->albedo * m_inv_total;
            if (aovs.has(Aov::Normal)) m_out.normal[p] = sums[i]->normal * m_inv_total;
        }
    }

    const TlasStrategy& m_tlas;
    const FrameState& m_frame;
    const CameraRays m_rays;
    const SkyModel m_sky;
    FrameBuffers& m_out;
    const uint32_t m_row0, m_row1;
    const SampleRange m_samples;
    const float m_inv_total;
    const uint32_t m_total;
    PixelSums* const m_accum;
    float* const m_variance;
    const CancelToken* const m_cancel;
    const std::optional<HitTest> m_hit_test;
    mutable std::atomic<uint64_t> m_ray_count{0};
};

}  // namespace

Result<Frame> Renderer::render(const TlasStrategy& tlas, const FrameState& frame,
                               const RenderRequest& request) {
    Stopwatch clock;
    Frame out;
    out.info.version = frame.version;
    const auto resolved = resolve_camera(request.camera, frame.camera);
    if (!resolved) return Unexpected(resolved.error());
    const Camera camera = resolved.value();
    out.camera = camera;
    if (should_stop(request.cancel)) return cancelled_error(*request.cancel);
    try {
        // The filter's guides are traced like requested AOVs and dropped after it ran.
        AovSet aovs(request.aovs);
        const AovSet requested = aovs;
        if (request.filter) {
            aovs.add(Aov::Albedo);
            aovs.add(Aov::Normal);
            aovs.add(Aov::Depth);
        }
        // A band traces whole packets (rows rounded out to PACKET_SIZE), so that every packet
        // holds the lanes it holds in the whole frame, and keeps only its own rows.
        const RowBand band = request.band.value_or(RowBand{0, request.height});
        const uint32_t trace_begin = band.y0 / PACKET_SIZE * PACKET_SIZE;
        const uint32_t trace_end =
            std::min(request.height, (band.y0 + band.rows + PACKET_SIZE - 1) / PACKET_SIZE *
                                         PACKET_SIZE);
        out.band = request.band;
        out.frame_height = request.height;
        out.buffers.allocate(request.width, band.rows, aovs);
        SampleRange samples{0, request.spp};
        PixelSums* accum = nullptr;
        if (request.accumulate) {
            if (uint64_t(request.width) * request.height > MAX_ACCUMULATE_PIXELS)
                return failure(ErrorCode::TooLarge,
                               "accumulation is limited to " +
                                   std::to_string(MAX_ACCUMULATE_PIXELS) + " pixels",
                               "accumulate");
            samples = m_accumulator.begin(
                {frame.version, camera, request.width, request.height, frame.clock}, request.spp);
            accum = m_accumulator.sums();
        }
        const uint32_t total = samples.first + samples.count;
        // The filter's noise level: each pixel's variance of the mean, from two samples on.
        std::vector<float> variance;
        if (request.filter && total >= 2) variance.resize(out.buffers.pixel_count());
        FrameKernel kernel(tlas, frame, camera, out.buffers, request.height, band.y0, samples,
                           total, accum, variance.empty() ? nullptr : variance.data(),
                           request.cancel);
        parallel_for_tile_rows(request.width, request.height, trace_begin, trace_end,
                               [&](const TileRect& tile) { kernel.render_tile(tile); });
        if (should_stop(request.cancel)) {
            // Some pixels hold fewer samples than the others: the sums cannot be continued.
            if (request.accumulate) m_accumulator.reset();
            return cancelled_error(*request.cancel);
        }
        if (request.accumulate) m_accumulator.finish(samples);
        if (request.filter) {
            filter_frame(out.buffers, variance, total, {}, &m_filter_scratch);
            if (out.buffers.pixel_count() > KEEP_FILTER_SCRATCH_PIXELS) m_filter_scratch.release();
            out.buffers.keep_only(requested);
        }
        out.info.samples = total;
        out.info.samples_added = samples.count;
        out.info.rays = kernel.rays();
        out.names = frame.id_names(out.buffers);
    } catch (const std::bad_alloc&) {
        m_accumulator.reset();
        return failure(ErrorCode::TooLarge, "not enough memory for a frame of this size", "width");
    }
    out.info.render_ms = clock.ms();
    return out;
}

}  // namespace strata
