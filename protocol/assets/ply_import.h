#pragma once
// PLY (ASCII, binary little- and big-endian) into the intermediate asset: a small reader of our
// own. Vertices (x y z, optional nx ny nz, red green blue, u v / s t), faces (a list of vertex
// indices, polygons fan-triangulated); every other element is read and skipped.

#include <span>

#include "protocol/assets/asset.h"

namespace strata::assets {

/// Reads one PLY file into one mesh at one root node. Counts in the header are checked against
/// `limits` and against the bytes that follow before anything is allocated.
Imported<Asset> import_ply(std::span<const uint8_t> bytes, const std::string& file,
                           const ImportLimits& limits);

}  // namespace strata::assets
