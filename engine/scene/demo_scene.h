#pragma once
// The demo scene shared by strata-demo, `strata-server --demo` and the reference image test, and
// the short edit sequence the demo plays over it.

#include <cstdint>

#include "engine/scene/edits.h"

namespace strata {

/// Ground, a large glossy sphere, a ring of 12 small spheres sharing one mesh, a few boxes, a
/// waving flag (a plane mesh) and materials, with a camera looking at all of it.
EditBatch make_demo_scene();

/// Edits for step `step` (0-based) of the demo sequence; each exercises one kind of edit so the
/// rebuild reports show every row of the least-work table. There are DEMO_STEPS steps.
EditBatch make_demo_step(uint32_t step);
constexpr uint32_t DEMO_STEPS = 8;

/// Positions of the demo flag at animation time `t` (seconds).
std::vector<Vec3> demo_flag_positions(float t);

}  // namespace strata
