#pragma once
// Per-op readers shared by edit_parser.cpp and mesh_op_parser.cpp (internal to the protocol).

#include <string>

#include "engine/scene/edits.h"
#include "protocol/edit_parser.h"
#include "protocol/json_fields.h"

namespace strata::protocol::detail {

Edit parse_add_mesh(FieldReader& r, const Json& v, const std::string& ptr, EditSource& src);
Edit parse_update_mesh(FieldReader& r, const Json& v, const std::string& ptr, EditSource& src);

}  // namespace strata::protocol::detail
