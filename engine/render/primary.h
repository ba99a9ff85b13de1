#pragma once
// The hit-buffer launch: one pixel-centre primary ray per pixel, traced in 4x4 packets over the
// fixed TBB tile grid, producing per-pixel hits and an unshadowed preview shade
// (albedo * (sun N.L + sky) + emission). Frames for clients come from renderer.h; this path is
// what the differential tests compare and what the primary-ray benchmark measures.

#include <cstdint>
#include <optional>
#include <vector>

#include "engine/accel/tlas.h"
#include "engine/render/frame_state.h"

namespace strata {

struct PrimarySettings {
    uint32_t width = 0;
    uint32_t height = 0;
    std::optional<Camera> camera;  ///< overrides the scene camera
    uint32_t ray_mask = 0xFFFFFFFFu;
};

/// Per-pixel results, row-major from the top-left pixel. Misses have distance +inf and
/// instance/primitive INVALID_ID.
struct HitBuffers {
    uint32_t width = 0;
    uint32_t height = 0;
    std::vector<float> distance;
    std::vector<uint32_t> instance;   ///< instance slot
    std::vector<uint32_t> primitive;  ///< triangle index in the mesh
    std::vector<Vec3> normal;         ///< world-space unit geometric normal, facing the camera
    std::vector<Vec3> color;          ///< linear RGB

    /// Sizes every buffer for w x h and fills it with the miss values.
    void resize(uint32_t w, uint32_t h);
    /// Sizes every buffer for w x h, keeping the contents when the size is already right.
    void reserve_frame(uint32_t w, uint32_t h);
    std::size_t pixel_count() const { return std::size_t(width) * height; }
};

/// Traces the primary rays of one frame into `out` (reusing its buffers when they fit).
void render_primary(const TlasStrategy& tlas, const FrameState& frame,
                    const PrimarySettings& settings, HitBuffers& out);

}  // namespace strata
