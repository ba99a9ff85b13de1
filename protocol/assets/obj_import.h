#pragma once
// Wavefront OBJ with MTL materials into the intermediate asset, over Debian's tinyobjloader.
// Material libraries come only from the upload (`side_files`); a `mtllib` that names anything
// else is left out with a warning, never looked up on the server's filesystem.

#include <span>

#include "protocol/assets/asset.h"
#include "protocol/assets/side_files.h"

namespace strata::assets {

/// Reads one OBJ file: one mesh per material used, polygons fan-triangulated, one root node.
/// MTL: Kd is the base colour, Ns (with Ks) the roughness, Ke the emission, Pr/Pm when given,
/// map_Kd the base-colour texture (its bytes when the upload holds the image, looked up
/// relative to the MTL's folder first, then to the OBJ's).
Imported<Asset> import_obj(std::span<const uint8_t> bytes, const std::string& file,
                           const SideFiles& side_files, const ImportLimits& limits);

}  // namespace strata::assets
