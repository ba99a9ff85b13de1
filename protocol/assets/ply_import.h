#pragma once
// PLY (ASCII, binary little- and big-endian) into the intermediate asset: a small reader of our
// own. Vertices (x y z, optional nx ny nz, red green blue, u v / s t, radius), faces (a list of
// vertex indices, polygons fan-triangulated); every other element is read and skipped.
//
// A file without faces (no face element, or one of 0 faces) is a point cloud: a points mesh, one
// sphere per vertex. Its radius is the vertex's `radius` property (a finite number > 0) or, for a
// file without one, default_point_radius (asset.h): 0.5 * D / sqrt(N) for N points whose bounds
// have the diagonal D (1 when they coincide), named in a warning. Normals and texture
// coordinates are dropped from a point cloud, with a warning; `radius` is ignored with faces.

#include <span>

#include "protocol/assets/asset.h"

namespace strata::assets {

/// Reads one PLY file into one mesh at one root node. Counts in the header are checked against
/// `limits` and against the bytes that follow before anything is allocated.
Imported<Asset> import_ply(std::span<const uint8_t> bytes, const std::string& file,
                           const ImportLimits& limits);

}  // namespace strata::assets
