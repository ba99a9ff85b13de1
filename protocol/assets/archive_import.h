#pragma once
// A model uploaded with its side files in one tar archive: the archive read (tar_reader.h), its
// one model found, the other files handed to the importer by their path relative to the model's
// folder, the model imported. Errors name the archive, the entry and what is wrong.

#include <span>
#include <string>

#include "protocol/assets/asset.h"
#include "protocol/assets/tar_reader.h"

namespace strata::assets {

/// An archive's model, imported.
struct ArchiveAsset {
    Asset asset;
    AssetFormat format = AssetFormat::Obj;
    std::string model;  ///< the model's path inside the archive
};

/// Imports the one model (.obj, .gltf, .glb, .ply or an assimp format, by extension) of a tar
/// archive, with the archive's other files as its side files. None or several models: Invalid, naming them. An
/// importer's error names the file as "<archive>: <model path>".
Imported<ArchiveAsset> import_archive(std::span<const uint8_t> body, const std::string& archive,
                                      const ImportLimits& limits, const TarLimits& tar_limits = {});

}  // namespace strata::assets
