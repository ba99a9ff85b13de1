#pragma once
// A rendered frame before encoding: the linear beauty image and the requested AOVs, row-major
// from the top-left pixel.
//
// What each AOV holds (and its value where the pixel's ray hits nothing):
//
//   AOV           source                 value                                          miss
//   color         every sample           linear RGB radiance, averaged                  sky
//   albedo        every sample           base_color of the first surface, averaged      0
//   normal        every sample           world-space unit geometric normal facing the   0
//                                        camera, averaged (so shorter than 1 at edges)
//   depth         pixel-centre ray       distance from the eye along the camera ray     +inf
//   position      pixel-centre ray       world-space hit point                          0
//   instance_id   pixel-centre ray       instance slot index (see below)                0xFFFFFFFF
//   primitive_id  pixel-centre ray       triangle index within the instance's mesh      0xFFFFFFFF
//   mesh_id       pixel-centre ray       mesh slot index                                0xFFFFFFFF
//   user_id       pixel-centre ray       the instance's user_id (add/update_instance)   0xFFFFFFFF
//
// "Every sample" AOVs are antialiased exactly like the beauty image (what a denoiser expects);
// "pixel-centre ray" AOVs come from one unjittered ray through the pixel centre, so they name a
// single surface and are exact (a plane at distance d gives depth d at the centre of the image).
//
// Ids: `instance_id` is the instance's slot in the scene's flat instance table (the `index` of its
// handle: Scene::find_instance(id).index). It is stable for the instance's whole life (moving,
// hiding, re-masking or re-materialling it keeps it) and is the number the TLAS reports as a
// hit's instance; a slot freed by a removal is reused by a later addition. `mesh_id` is likewise
// the mesh's slot (Scene::find_mesh(id).index). Neither is the instance's `user_id`, which
// clients choose freely and need not be unique: the `user_id` AOV carries it as given (a client
// that uses 0xFFFFFFFF itself tells its hits from misses by instance_id or depth).

#include <cstdint>
#include <vector>

#include "engine/accel/ray.h"
#include "engine/core/math.h"
#include "engine/render/render_request.h"

namespace strata {

/// Value of id AOVs where nothing was hit.
constexpr uint32_t MISS_ID = INVALID_ID;

/// Which AOVs a frame carries, as a bit set over Aov.
class AovSet {
public:
    AovSet() = default;
    explicit AovSet(const std::vector<Aov>& aovs) {
        for (Aov a : aovs) add(a);
    }
    void add(Aov a) { m_bits |= 1u << unsigned(a); }
    bool has(Aov a) const { return (m_bits >> unsigned(a)) & 1u; }
    friend bool operator==(const AovSet&, const AovSet&) = default;
    /// True when any AOV that comes from the pixel-centre ray is present.
    bool needs_centre_ray() const {
        return has(Aov::Depth) || has(Aov::Position) || has(Aov::InstanceId) ||
               has(Aov::PrimitiveId) || has(Aov::MeshId) || has(Aov::UserId);
    }

private:
    uint32_t m_bits = 0;
};

/// The frame's pixels. Buffers of AOVs that were not requested stay empty.
struct FrameBuffers {
    uint32_t width = 0;
    uint32_t height = 0;
    AovSet aovs;
    std::vector<Vec3> color;  ///< always present
    std::vector<Vec3> albedo;
    std::vector<Vec3> normal;
    std::vector<float> depth;
    std::vector<Vec3> position;
    std::vector<uint32_t> instance_id;
    std::vector<uint32_t> primitive_id;
    std::vector<uint32_t> mesh_id;
    std::vector<uint32_t> user_id;

    std::size_t pixel_count() const { return std::size_t(width) * height; }

    /// Sizes the beauty buffer and those of `set`; contents are left for the renderer to write.
    void allocate(uint32_t w, uint32_t h, AovSet set) {
        width = w;
        height = h;
        aovs = set;
        const std::size_t n = pixel_count();
        color.resize(n);
        if (set.has(Aov::Albedo)) albedo.resize(n);
        if (set.has(Aov::Normal)) normal.resize(n);
        if (set.has(Aov::Depth)) depth.resize(n);
        if (set.has(Aov::Position)) position.resize(n);
        if (set.has(Aov::InstanceId)) instance_id.resize(n);
        if (set.has(Aov::PrimitiveId)) primitive_id.resize(n);
        if (set.has(Aov::MeshId)) mesh_id.resize(n);
        if (set.has(Aov::UserId)) user_id.resize(n);
    }

    /// Drops the buffers of the AOVs outside `set` (what a launch traced for its own use only).
    void keep_only(AovSet set) {
        auto drop = [&](Aov a, auto& buffer) {
            if (!set.has(a)) buffer = {};
        };
        drop(Aov::Albedo, albedo);
        drop(Aov::Normal, normal);
        drop(Aov::Depth, depth);
        drop(Aov::Position, position);
        drop(Aov::InstanceId, instance_id);
        drop(Aov::PrimitiveId, primitive_id);
        drop(Aov::MeshId, mesh_id);
        drop(Aov::UserId, user_id);
        aovs = set;
    }

    /// As allocate(), but keeps the buffers (and their contents) when they already have this
    /// size and set: for callers that write every pixel of many frames.
    void reserve_frame(uint32_t w, uint32_t h, AovSet set) {
        if (w == width && h == height && set == aovs && color.size() == pixel_count()) return;
        *this = FrameBuffers{};
        allocate(w, h, set);
    }
};

}  // namespace strata
