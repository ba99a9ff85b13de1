#pragma once
// One entry point over the importers: bytes of a named format in, the intermediate asset out.

#include <span>

#include "protocol/assets/asset.h"
#include "protocol/assets/obj_import.h"

namespace strata::assets {

/// Reads `bytes` as `format`. `file` names the upload in errors; `side_files` are files uploaded
/// with it (an OBJ's MTL and images, a .gltf's buffers and images), looked up by the name the
/// model gives them (side_files.h), never on the filesystem. No exception
/// escapes: a library that throws becomes an Invalid error.
Imported<Asset> import_asset(AssetFormat format, std::span<const uint8_t> bytes,
                             const std::string& file, const ImportLimits& limits,
                             const SideFiles& side_files = {});

}  // namespace strata::assets
