#pragma once
// Pick requests: the GET /v1/pick query (one pixel) and the POST /v1/pick body (a list of
// pixels), both into the engine's PickRequest. The camera override is a render's.

#include <map>
#include <string>

#include "engine/render/pick.h"
#include "protocol/json_document.h"
#include "protocol/problem.h"

namespace strata::protocol {

/// `{"width", "height", "pixels": [[x, y], ...], "camera": {...}}`; width, height and pixels
/// are required.
Parsed<PickRequest> parse_pick_body(const Json& body);

/// `x`, `y`, `width`, `height` (all required) and the camera override's `eye`, `target`, `up`,
/// `fov_y_deg`.
Parsed<PickRequest> parse_pick_query(const std::multimap<std::string, std::string>& params);

}  // namespace strata::protocol
