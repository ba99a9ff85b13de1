#include "engine/render/primary.h"

#include <algorithm>
#include <limits>

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include "engine/render/camera_rays.h"

namespace strata {

namespace {

constexpr uint32_t TILE = 16;   // pixels per tile side, one TBB task
constexpr uint32_t PACKET = 4;  // 4x4 pixels per 16-ray packet

Vec3 shade(const FrameState& frame, const InstanceShade& inst, const Vec3& n) {
    const Material& m = frame.materials[inst.material];
    const Lighting& l = frame.lighting;
    const float n_dot_l = std::max(0.0f, glm::dot(n, glm::normalize(l.sun_direction)));
    return m.base_color * (l.sun_color * n_dot_l + l.sky_color * l.sky_intensity) + m.emission;
}

}  // namespace

void HitBuffers::resize(uint32_t w, uint32_t h) {
    width = w;
    height = h;
    const std::size_t n = std::size_t(w) * h;
    distance.assign(n, std::numeric_limits<float>::infinity());
    instance.assign(n, INVALID_ID);
    primitive.assign(n, INVALID_ID);
    normal.assign(n, Vec3(0.0f));
    color.assign(n, Vec3(0.0f));
}

void render_primary(const TlasStrategy& tlas, const FrameState& frame,
                    const PrimarySettings& settings, HitBuffers& out) {
    out.resize(settings.width, settings.height);
    if (settings.width == 0 || settings.height == 0) return;
    const CameraRays rays(settings.camera.value_or(frame.camera), settings.width, settings.height);
    const Vec3 background = frame.lighting.sky_color * frame.lighting.sky_intensity;
    const Vec3 eye = rays.eye();

    tbb::parallel_for(
        tbb::blocked_range2d<uint32_t>(0, settings.height, TILE, 0, settings.width, TILE),
        [&](const tbb::blocked_range2d<uint32_t>& tile) {
            RayHit16 packet;
            ValidMask16 valid;
            for (uint32_t y0 = tile.rows().begin(); y0 < tile.rows().end(); y0 += PACKET) {
                for (uint32_t x0 = tile.cols().begin(); x0 < tile.cols().end(); x0 += PACKET) {
                    // Step: fill the packet; lanes outside the image are inactive.
                    for (uint32_t i = 0; i < 16; ++i) {
                        const uint32_t x = x0 + i % PACKET, y = y0 + i / PACKET;
                        const bool inside = x < tile.cols().end() && y < tile.rows().end();
                        valid.lanes[i] = inside ? -1 : 0;
                        const Vec3 d = rays.direction(float(x) + 0.5f, float(y) + 0.5f);
                        packet.org_x[i] = eye.x;
                        packet.org_y[i] = eye.y;
                        packet.org_z[i] = eye.z;
                        packet.tnear[i] = 0.0f;
                        packet.dir_x[i] = d.x;
                        packet.dir_y[i] = d.y;
                        packet.dir_z[i] = d.z;
                        packet.time[i] = 0.0f;
                        packet.tfar[i] = std::numeric_limits<float>::infinity();
                        packet.mask[i] = settings.ray_mask;
                        packet.id[i] = i;
                        packet.flags[i] = 0;
                        packet.geom_id[i] = INVALID_ID;
                        packet.inst_id[i] = INVALID_ID;
                        packet.prim_id[i] = INVALID_ID;
                    }
                    tlas.intersect16(valid, packet, true);

                    // Step: write hit buffers and shade.
                    for (uint32_t i = 0; i < 16; ++i) {
                        if (!valid.lanes[i]) continue;
                        const std::size_t p =
                            std::size_t(y0 + i / PACKET) * settings.width + x0 + i % PACKET;
                        const uint32_t inst = packet.inst_id[i];
                        if (inst == INVALID_ID) {
                            out.color[p] = background;
                            continue;
                        }
                        const InstanceShade& shade_info = frame.instances[inst];
                        Vec3 n = shade_info.normal_matrix *
                                 Vec3(packet.ng_x[i], packet.ng_y[i], packet.ng_z[i]);
                        n = glm::normalize(n);
                        const Vec3 dir(packet.dir_x[i], packet.dir_y[i], packet.dir_z[i]);
                        if (glm::dot(n, dir) > 0.0f) n = -n;
                        out.distance[p] = packet.tfar[i];
                        out.instance[p] = inst;
                        out.primitive[p] = packet.prim_id[i];
                        out.normal[p] = n;
                        out.color[p] = shade(frame, shade_info, n);
                    }
                }
            }
        });
}

}  // namespace strata
