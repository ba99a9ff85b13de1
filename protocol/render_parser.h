#pragma once
// Render requests: the POST /v1/render body and the GET /v1/render query string, both into the
// engine's RenderRequest. A camera override may name only some fields; the engine completes it
// from the scene camera of the version the launch renders.

#include <map>
#include <optional>
#include <string>

#include "engine/render/render_request.h"
#include "engine/scene/edits.h"
#include "protocol/framing.h"
#include "protocol/json_document.h"
#include "protocol/problem.h"

namespace strata::protocol {

/// Largest width or height (the schema bound; the server also caps width * height).
constexpr uint32_t MAX_RENDER_SIDE = 65536;
/// Most processes one frame is split across (`split`).
constexpr uint32_t MAX_RENDER_SPLIT = 16;

class FieldReader;

/// A camera override `{"eye", "target", "up", "fov_y_deg"}` (every member optional) at /camera.
SetCamera read_camera_override(FieldReader& r, const Json& v);

/// Query parameters as the JSON body they stand for: numbers and booleans as text, `aovs`,
/// `band` and vectors as comma-separated lists, `eye`, `target`, `up` and `fov_y_deg` into a
/// "camera" object, `frame_group` / `frame_instance` into a "frame" object (the id as text). A
/// parameter given twice, or "camera" itself, is an error.
Parsed<Json> query_to_body(const std::multimap<std::string, std::string>& params);

/// `{"width", "height", "format", "spp", "aovs", "compression", "accumulate", "exposure",
/// "filter", "camera": {"eye", "target", "up", "fov_y_deg"}, "band": [y0, rows], "split"}`,
/// every member optional. `split` (how many processes render the frame, [1, MAX_RENDER_SPLIT],
/// 1 when absent) is written to `*split`; without `split` the member is refused as unknown (a
/// caller that cannot split). A split above 1 with `band` or `accumulate`, or above the height,
/// is a value error at /split; the engine checks the band itself (check_render_request).
/// `frame` ({"group": id} or {"instance": id}) is written to `*frame` when given; without
/// `frame` the member is refused as unknown, like `split`.
Parsed<RenderRequest> parse_render_body(const Json& body, uint32_t* split = nullptr,
                                        std::optional<FrameTarget>* frame = nullptr);

/// The same members as query parameters: numbers and booleans as text, `aovs`, `band` and
/// vectors as comma-separated lists, and the camera override as `eye`, `target`, `up`,
/// `fov_y_deg`, and `frame` as `frame_group` or `frame_instance`.
Parsed<RenderRequest> parse_render_query(const std::multimap<std::string, std::string>& params,
                                         uint32_t* split = nullptr,
                                         std::optional<FrameTarget>* frame = nullptr);

}  // namespace strata::protocol
