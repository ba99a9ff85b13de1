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
/// errors. A glTF mesh becomes one asset mesh per primitive, shared by every node that uses it.
/// External URIs (percent-decoded) are looked up in `side_files`.
///
/// Primitive modes: TRIANGLES; POINTS as a points mesh; LINES (one 2-vertex strand per line),
/// LINE_STRIP (one strand) and LINE_LOOP (one strand closed by repeating its first vertex) as a
/// linear round curve mesh, each strand with copies of its vertices in index order. glTF gives
/// points no size and lines no width, so they take asset.h's defaults, named in a warning: for
/// N points whose bounds have the diagonal D (1 when they coincide), radius 0.5 * D / sqrt(N);
/// for lines 0.002 * D. Their NORMAL, TEXCOORD_n and TANGENT are dropped with a warning; their
/// material applies. TRIANGLE_STRIP and TRIANGLE_FAN are refused.
Imported<Asset> import_gltf(std::span<const uint8_t> bytes, bool binary, const std::string& file,
                            const ImportLimits& limits, const SideFiles& side_files = {});

}  // namespace strata::assets
