#pragma once
// Draco-compressed glTF primitives (KHR_draco_mesh_compression), decoded with Debian's libdraco.
// The importer checks the extension's references and the counts the file declares (against the
// budget) before calling decode_draco_mesh; the decoded mesh must then have exactly those counts.

#include <cstdint>
#include <span>
#include <string>

#include "protocol/assets/asset.h"

namespace strata::assets {

/// Draco attribute unique ids of a primitive's attributes (-1: the primitive has none).
struct DracoAttributeIds {
    int position = -1;
    int normal = -1;
    int texcoord = -1;
    int texcoord1 = -1;
    int color = -1;
    int tangent = -1;
};

/// What the glTF accessors of the primitive declare: the decoded mesh must match.
struct DracoCounts {
    uint64_t vertices = 0;
    uint64_t indices = 0;
};

/// Decodes `bytes` (the extension's buffer view) into `out`'s positions, triangles and the
/// attributes `ids` names. An empty string on success, else what was wrong ("the Draco data is
/// a point cloud", "it decodes to 12 vertices where POSITION declares 2019", a non-finite value).
std::string decode_draco_mesh(std::span<const uint8_t> bytes, const DracoAttributeIds& ids,
                              const DracoCounts& declared, AssetMesh& out);

}  // namespace strata::assets
