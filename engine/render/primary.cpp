#include "engine/render/primary.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/render/camera_rays.h"
#include "engine/render/tiles.h"

namespace strata {

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
    const Lighting& light = frame.lighting;
    const Vec3 background = light.sky_color * light.sky_intensity;
    const Vec3 sun = glm::normalize(light.sun_direction);
    const Vec3 eye = rays.eye();

    parallel_for_tiles(settings.width, settings.height, [&](const TileRect& tile) {
        alignas(64) RayHit16 packet;
        int valid[PACKET_LANES];
        for (uint32_t y0 = tile.y0; y0 < tile.y1; y0 += PACKET_SIZE) {
            for (uint32_t x0 = tile.x0; x0 < tile.x1; x0 += PACKET_SIZE) {
                // Step: fill the packet with pixel-centre rays; lanes outside the image are off.
                packet_lanes(tile, x0, y0, valid);
                for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                    const float x = float(x0 + i % PACKET_SIZE) + 0.5f;
                    const float y = float(y0 + i / PACKET_SIZE) + 0.5f;
                    set_lane(packet, i, eye, rays.direction(x, y), 0.0f, settings.ray_mask);
                }
                tlas.intersect16(valid, packet, true);

                // Step: write hit buffers and a simple preview shade.
                for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                    if (!valid[i]) continue;
                    const std::size_t p =
                        std::size_t(y0 + i / PACKET_SIZE) * settings.width + x0 + i % PACKET_SIZE;
                    const uint32_t inst = packet.inst_id[i];
                    if (inst == INVALID_ID) {
                        out.color[p] = background;
                        continue;
                    }
                    const InstanceShade& shade = frame.instances[inst];
                    Vec3 n = glm::normalize(shade.normal_matrix *
                                            Vec3(packet.ng_x[i], packet.ng_y[i], packet.ng_z[i]));
                    const Vec3 dir(packet.dir_x[i], packet.dir_y[i], packet.dir_z[i]);
                    if (glm::dot(n, dir) > 0.0f) n = -n;
                    const Material& m = frame.materials[shade.material];
                    out.distance[p] = packet.tfar[i];
                    out.instance[p] = inst;
                    out.primitive[p] = packet.prim_id[i];
                    out.normal[p] = n;
                    out.color[p] = m.base_color * (light.sun_color * std::max(0.0f, glm::dot(n, sun)) +
                                                   background) +
                                   m.emission;
                }
            }
        }
    });
}

}  // namespace strata
