#pragma once
// The intermediate asset as ONE engine edit batch: its materials, its meshes (each asset mesh
// once, so nodes that share a glTF mesh share one BLAS) and, unless asked not to, one instance
// per (node, mesh) at the node's world transform. The scene applies it atomically and the
// journal records it like any POST /v1/edits batch.
//
// Until the scene has groups, the node tree is flattened here: world = parent world * local.
// Mapping nodes to groups later means emitting one group per node instead of multiplying.

#include <string>
#include <vector>

#include "engine/scene/edits.h"
#include "protocol/assets/asset.h"

namespace strata::assets {

/// How the ids of what an asset creates are formed, and whether it is placed.
struct BatchOptions {
    std::string prefix;    ///< every id starts with it: "<prefix>.mesh0", "<prefix>.node3"
    bool instance = true;  ///< false: meshes and materials only
};

/// The batch and the ids it creates, in the order of its edits.
struct AssetBatch {
    EditBatch batch;
    std::vector<std::string> meshes;
    std::vector<std::string> materials;
    std::vector<std::string> instances;
    std::vector<std::string> edit_ids;  ///< the id each edit creates (for error messages)
    std::vector<std::string> warnings;  ///< the asset's, plus what the scene cannot hold yet
};

/// Builds the batch. Nodes whose world transform the scene cannot use (a zero scale, say) are
/// left unplaced with a warning naming them; nothing else is dropped silently.
AssetBatch asset_to_batch(Asset&& asset, const BatchOptions& options);

}  // namespace strata::assets
