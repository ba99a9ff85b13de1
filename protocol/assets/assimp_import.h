#pragma once
// The formats Debian's libassimp reads and Strata has no importer of its own for (FBX, COLLADA,
// STL, 3DS, OFF, DirectX .x, ...), read with assimp from the upload's bytes and converted into the
// same intermediate asset as the other importers. Assimp sees only the upload and its side files
// (an IOSystem of our own: it never opens a file of the server), and, like every importer, runs
// in the sandboxed child (sandbox.h), which bounds what a crash or a runaway parse can cost.
//
// What is kept: triangle meshes (polygons triangulated) with normals and texture coordinates set
// 0 (v flipped to the engine's convention, as glTF), materials (base or diffuse colour, metallic
// and roughness factors where the file has them, else a roughness from the Phong shininess, the
// emissive colour unless an emissive texture would be lost with it, the diffuse or base-colour
// texture when it is embedded or a side file), the node tree with its transforms. Everything
// else is named in the warnings: points and lines, bones, morph targets, animations, cameras,
// lights, texture coordinate sets beyond 1, and texture kinds the renderer does not read.

#include <span>
#include <string>

#include "protocol/assets/asset.h"
#include "protocol/assets/side_files.h"

namespace strata::assets {

/// Reads `bytes`, a file of assimp format `format` (format_is_assimp(format)).
Imported<Asset> import_assimp(std::span<const uint8_t> bytes, AssetFormat format,
                              const std::string& file, const ImportLimits& limits,
                              const SideFiles& side_files);

}  // namespace strata::assets
