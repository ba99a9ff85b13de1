#pragma once
// glTF 2.0 (.glb, and .gltf with data: URIs or with its buffers and images uploaded next to it
// in an archive) into the intermediate asset, over Debian's tinygltf. The filesystem callbacks
// are replaced: an external buffer or image is read from the upload's side files only; a buffer
// the upload lacks is refused, an image it lacks is kept as a name; nothing reads the server's
// files.

#include <span>

#include "protocol/assets/asset.h"
#include "protocol/assets/side_files.h"

namespace strata::assets {

/// Reads one glTF file. `binary`: a .glb container, else glTF JSON. `file` names the upload in
/// errors. Triangle primitives only; a glTF mesh becomes one asset mesh per primitive, shared by
/// every node that uses it. External URIs (percent-decoded) are looked up in `side_files`.
Imported<Asset> import_gltf(std::span<const uint8_t> bytes, bool binary, const std::string& file,
                            const ImportLimits& limits, const SideFiles& side_files = {});

}  // namespace strata::assets
