#pragma once
// glTF 2.0 (.glb, and .gltf with embedded data: URIs) into the intermediate asset, over Debian's
// tinygltf. The filesystem callbacks are replaced: an external buffer is refused, an external
// image is kept as a name only; nothing reads the server's files.

#include <span>

#include "protocol/assets/asset.h"

namespace strata::assets {

/// Reads one glTF file. `binary`: a .glb container, else glTF JSON. `file` names the upload in
/// errors. Triangle primitives only; a glTF mesh becomes one asset mesh per primitive, shared by
/// every node that uses it.
Imported<Asset> import_gltf(std::span<const uint8_t> bytes, bool binary, const std::string& file,
                            const ImportLimits& limits);

}  // namespace strata::assets
