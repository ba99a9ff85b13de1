#pragma once
// Files uploaded next to a model (an OBJ's MTL and images, a .gltf's buffers and images), found
// by the reference the model makes to them. Never the filesystem: a reference that names no
// uploaded file is simply not found.

#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace strata::assets {

/// Files uploaded next to the main one, keyed by their path relative to the main file's folder
/// in normal form (see normalize_reference): "tex/a.png", "../shared/b.png".
using SideFiles = std::map<std::string, std::string, std::less<>>;

/// A reference in normal form: '\' read as '/', empty and "." parts dropped, "x/.." folded;
/// leading ".." parts are kept (they can only match a side file above the model's folder).
/// nullopt for an absolute path ("/a", "C:/a") or one that holds a NUL.
std::optional<std::string> normalize_reference(std::string_view reference);

/// The side file a model's reference names, or nullptr. An absolute reference (a "D:\\art\\
/// wood.jpg" written on the exporter's machine), or one into a folder the upload lacks, finds the
/// file of its name at the top of the upload, as Blender and assimp's viewers look for textures;
/// one that climbs above the model's folder ("../x.png") finds only that.
const std::string* find_side_file(const SideFiles& files, std::string_view reference);

}  // namespace strata::assets
