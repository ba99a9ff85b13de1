#pragma once
// What `strata import FILE` uploads: the file alone, or, when it names side files (an OBJ's MTL
// libraries and their map_Kd images, a .gltf's external buffers and images), a tar archive of the
// model and those files built in memory, each at its path relative to the model's folder (POST
// /v1/assets with ?format=tar, protocol/README.md "Archives").

#include <string>
#include <vector>

namespace strata::cli {

/// One upload, ready to send.
struct PackedAsset {
    std::string bytes;                    ///< the model file, or the tar archive
    bool archive = false;                 ///< bytes is a tar of the model and `side_files`
    std::string model_path;               ///< the model's path inside the archive
    std::vector<std::string> side_files;  ///< archive paths of the files packed with it
};

/// Reads `file` and the files it names. A named file that cannot be read, an absolute
/// reference, or a file outside the model's folder that is not a .mtl, .bin, .png or .jpg (an
/// untrusted model must not make the upload carry arbitrary local files) is an error (the
/// message says which file names what); nothing is sent then.
bool pack_asset(const std::string& file, PackedAsset& out, std::string& error);

/// A POSIX ustar archive of `files` (archive path, bytes), GNU long names past 255 bytes.
std::string write_tar(const std::vector<std::pair<std::string, std::string>>& files);

}  // namespace strata::cli
