#pragma once
// The hit-buffer launch: one pixel-centre primary ray per pixel, traced in 4x4 packets over the
// fixed TBB tile grid, producing per-pixel hits and an unshadowed preview shade
// (albedo * (sun N.L + sky) + emission). Frames for clients come from renderer.h; this path is
// what the differential tests compare and what the primary-ray benchmark measures.

#include <cstdint>
#include <optional>

#include "engine/accel/tlas.h"
#include "engine/render/aov_buffers.h"
#include "engine/render/frame_state.h"

namespace strata {

struct PrimarySettings {
    uint32_t width = 0;
    uint32_t height = 0;
    std::optional<Camera> camera;  ///< overrides the scene camera
    uint32_t ray_mask = 0xFFFFFFFFu;
};

/// The AOVs a primary launch writes: hit distance (depth), instance slot, triangle, world normal
/// facing the camera, and the preview shade in `color`.
AovSet primary_aovs();

/// Traces the primary rays of one frame into `out`'s primary_aovs() (reusing its buffers when
/// they fit). Misses have depth +inf, instance and primitive MISS_ID, normal 0 and the sky colour.
void render_primary(const TlasStrategy& tlas, const FrameState& frame,
                    const PrimarySettings& settings, FrameBuffers& out);

}  // namespace strata
