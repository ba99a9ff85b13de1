#pragma once
// Picking: what lies under given pixels of the committed scene, one ray per pixel and no frame.
// The rays are those of a render of the same size and camera through the pixels' centres, so a
// pick agrees with the instance_id and depth AOVs of that render.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "engine/accel/tlas.h"
#include "engine/core/result.h"
#include "engine/render/frame_state.h"
#include "engine/scene/edits.h"
#include "engine/scene/object_fields.h"

namespace strata {

/// Most pixels one pick may ask about.
constexpr std::size_t MAX_PICK_PIXELS = 10000;

struct PickPixel {
    uint32_t x = 0;  ///< column, 0 at the left
    uint32_t y = 0;  ///< row, 0 at the top
};

struct PickRequest {
    uint32_t width = 0;  ///< the image the pixels belong to
    uint32_t height = 0;
    std::vector<PickPixel> pixels;
    /// Overrides the scene camera, as a render's override does.
    std::optional<SetCamera> camera;
    /// The scene time the animated instances show, as a render's (RenderRequest::time).
    std::optional<float> time;
};

/// The surface under one pixel, named with client ids.
struct PickHit {
    std::string instance;
    std::string mesh;
    std::vector<std::string> group_path;  ///< the groups from the root down to its parent
    uint32_t primitive = 0;  ///< triangle index in the mesh
    float distance = 0.0f;   ///< along the unit-length camera ray
    Vec3 position{0.0f};     ///< world space
    Vec3 normal{0.0f};       ///< world-space geometric normal, unit length, facing the camera
    uint32_t user_id = 0;
    /// The instance's fields (object_fields.h); picks report those its table marks as labels.
    FieldValues<InstanceFields> fields;
};

struct PickResult {
    uint64_t version = 0;                      ///< the committed version the rays saw
    std::vector<std::optional<PickHit>> hits;  ///< one per requested pixel; nullopt: nothing
};

/// Why `request` cannot be picked (size, pixel count, pixels outside the image), or success.
Status check_pick_request(const PickRequest& request);

/// One ray per pixel of `request` through `tlas`, with `camera` (already resolved), reported
/// with the ids `scene` gives the hit instances. `scene` must be at `frame`'s version.
std::vector<std::optional<PickHit>> pick_pixels(const TlasStrategy& tlas, const FrameState& frame,
                                                const Scene& scene, const Camera& camera,
                                                const PickRequest& request);

}  // namespace strata
