#pragma once
// What an import hands back from the sandboxed child process (sandbox.h) to the server: the
// imported asset (or the problem that refused it) as bytes through a pipe. The reader treats the
// bytes as untrusted (a parser the child ran may have been subverted): every count is checked
// against the bytes left before anything is allocated, every enum against its range, and the
// asset is checked again (validate_asset) once decoded.

#include <optional>
#include <string>
#include <string_view>

#include "protocol/assets/asset.h"

namespace strata::assets {

/// An import's result: the asset, the format it was read as and, for an archive, the model's
/// path inside it.
struct ImportOutcome {
    Asset asset;
    AssetFormat format = AssetFormat::Obj;
    std::optional<std::string> model;
};

/// The result as bytes.
std::string encode_outcome(const Imported<ImportOutcome>& result);

/// The bytes back, or why they are not a result (the message names the byte at fault).
Expected<Imported<ImportOutcome>, std::string> decode_outcome(std::string_view bytes);

}  // namespace strata::assets
