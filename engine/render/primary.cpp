#include "engine/render/primary.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "engine/render/camera_rays.h"
#include "engine/render/tiles.h"

namespace strata {

namespace {

/// What the preview shade reads of a hit's material: its base colour and emission, times their
/// textures as FrameState::surface() applies them, and whether it is unlit. A material without
/// those textures is read in place: surface() copies the whole material for every hit, which
/// cost the primary pass more than its own buffer writes.
struct Preview {
    const Vec3& base;
    const Vec3& emission;
    bool unlit;
};

template <class F>
auto with_preview(const FrameState& frame, uint32_t material, uint32_t mesh_slot, uint32_t prim,
                  float u, float v, F&& f) {
    const Material& m = frame.materials[material];
    const MaterialTextures& tex = frame.material_textures[material];
    if (!tex[slot_index(TextureSlot::BaseColor)] && !tex[slot_index(TextureSlot::Emissive)])
        return f(Preview{m.base_color, m.emission, m.unlit});
    const SurfaceMaterial s = frame.surface(material, frame.mesh_shade(mesh_slot), prim, u, v);
    return f(Preview{s.material.base_color, s.material.emission, s.material.unlit});
}

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

    float* const distance = out.depth.data();
    uint32_t* const instance = out.instance_id.data();
    uint32_t* const primitive = out.primitive_id.data();
    Vec3* const normal = out.normal.data();
    Vec3* const color = out.color.data();
    const InstanceShade* const shades = frame.instances.data();
    const std::optional<HitTest> test = frame.hit_test();

    parallel_for_tiles(settings.width, settings.height, [&](const TileRect& tile) {
        // The output rows of a tile are short pieces of five large arrays, too scattered for the
        // hardware prefetcher: ask for their cache lines now, while the rays are traced, instead
        // of stalling on each first store (a few percent at 720p).
        for (uint32_t y = tile.y0; y < tile.y1; ++y) {
            const std::size_t row = std::size_t(y) * settings.width;
            prefetch_for_write(distance + row + tile.x0, distance + row + tile.x1);
            prefetch_for_write(instance + row + tile.x0, instance + row + tile.x1);
            prefetch_for_write(primitive + row + tile.x0, primitive + row + tile.x1);
            prefetch_for_write(normal + row + tile.x0, normal + row + tile.x1);
            prefetch_for_write(color + row + tile.x0, color + row + tile.x1);
        }
        CameraPacket camera(rays, settings.ray_mask);
        ValidMask16 valid;
        for (uint32_t y0 = tile.y0; y0 < tile.y1; y0 += PACKET_SIZE) {
            for (uint32_t x0 = tile.x0; x0 < tile.x1; x0 += PACKET_SIZE) {
                // Step: pixel-centre rays; lanes outside the image are off.
                packet_lanes(tile, x0, y0, valid);
                RayHit16& packet = camera.aim_centres(x0, y0);
                tlas.intersect16(valid, packet, true, test ? &*test : nullptr);

                // Step: write hit buffers and a simple preview shade.
                for (uint32_t i = 0; i < PACKET_LANES; ++i) {
                    if (!valid[i]) continue;
                    const std::size_t p =
                        std::size_t(y0 + i / PACKET_SIZE) * settings.width + x0 + i % PACKET_SIZE;
                    const uint32_t inst = packet.inst_id[i];
                    if (inst == INVALID_ID) {
                        distance[p] = std::numeric_limits<float>::infinity();
                        instance[p] = INVALID_ID;
                        primitive[p] = INVALID_ID;
                        normal[p] = Vec3(0.0f);
                        color[p] = background;
                        continue;
                    }
                    const InstanceShade& shade = shades[inst];
                    Vec3 n = glm::normalize(shade.normal_matrix *
                                            Vec3(packet.ng_x[i], packet.ng_y[i], packet.ng_z[i]));
                    const Vec3 dir(packet.dir_x[i], packet.dir_y[i], packet.dir_z[i]);
                    if (glm::dot(n, dir) > 0.0f) n = -n;
                    distance[p] = packet.tfar[i];
                    instance[p] = inst;
                    primitive[p] = packet.prim_id[i];
                    normal[p] = n;
                    color[p] = with_preview(
                        frame, shade.material, shade.mesh_slot, packet.prim_id[i], packet.u[i],
                        packet.v[i], [&](const Preview& m) {
                            return m.unlit ? m.base
                                           : m.base * (light.sun_color *
                                                           std::max(0.0f, glm::dot(n, sun)) +
                                                       background) +
                                                 m.emission;
                        });
                }
            }
        }
    });
}

}  // namespace strata
