#pragma once
// The frame renderer: spp samples per pixel over a fixed tile grid scheduled by TBB, each sample
// a path of at most two surfaces traced in 4x4 packets through the TlasStrategy:
//
//   1. camera ray (jittered inside the pixel, intersect16, coherent);
//   2. direct light: a shadow ray toward the sun per lit hit (occluded16) - hard shadows from a
//      directional sun - and, when the scene has lights or emitting meshes, one toward a point
//      chosen on them (next-event estimation, light_table.h), weighted against bounce rays that
//      reach the same emitter by multiple importance sampling (power heuristic);
//   3. one bounce: a direction drawn from the BRDF (intersect16, incoherent). A miss gathers the
//      sky dome; a hit gathers its emission (MIS-weighted when it is in the light table), the sun
//      and one light point with shadow rays (occluded16) and the sky as base_color * sky(n),
//      unoccluded (the path ends there). Against fireflies, the second
//      surface shades the sun with its roughness raised to at least MIN_SECONDARY_ROUGHNESS and
//      the first surface's roughness (path regularisation: a rough floor sees no pin-point
//      caustics of the sun in a chrome ball, a mirror still reflects sharp highlights), and each
//      bounce's contribution is clamped to INDIRECT_CLAMP per channel;
//   4. emission of the first surface adds directly.
//
// Nothing is allocated per pixel or per sample. Launches read only the FrameState and the
// acceleration structures. See aov_buffers.h for what each AOV holds and accumulator.h for
// progressive refinement.

#include <cstdint>

#include "engine/accel/tlas.h"
#include "engine/core/result.h"
#include "engine/render/accumulator.h"
#include "engine/render/aov_filter.h"
#include "engine/render/frame.h"
#include "engine/render/frame_state.h"
#include "engine/render/render_request.h"

namespace strata {

/// Largest per-channel radiance one bounce may add to a sample.
constexpr float INDIRECT_CLAMP = 8.0f;
/// Least roughness the second surface of a path shades the sun with.
constexpr float MIN_SECONDARY_ROUGHNESS = 0.5f;

class Renderer {
public:
    /// Renders `request` (already checked) from `frame` through `tlas`. Not thread-safe: the
    /// engine serialises launches. Errors: a frame too large to accumulate or to allocate.
    Result<Frame> render(const TlasStrategy& tlas, const FrameState& frame,
                         const RenderRequest& request);

private:
    Accumulator m_accumulator;
    /// The filter's working memory, kept for frames up to KEEP_FILTER_SCRATCH_PIXELS (what an
    /// interactive view filters frame after frame), freed after larger ones.
    FilterScratch m_filter_scratch;
};

/// Largest frame whose filter memory a Renderer keeps (1280x720: about 90 MB).
constexpr uint64_t KEEP_FILTER_SCRATCH_PIXELS = 1280ull * 720;

}  // namespace strata
