#pragma once
// The wire forms of an instance transform: 12 or 16 numbers (row-major; 16 means a 4x4 matrix
// whose last row must be 0 0 0 1), or {"translate": [3], "rotate_deg": [3] | "quaternion": [4],
// "scale": number | [3]} composed as translate * rotate * scale.

#include <string>

#include "engine/core/math.h"
#include "protocol/json_fields.h"

namespace strata::protocol {

/// Reads a transform at `ptr`. Degeneracy is left to the engine's validation.
Affine parse_transform(FieldReader& r, const Json& v, const std::string& ptr);

}  // namespace strata::protocol
