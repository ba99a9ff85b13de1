#pragma once
// The intermediate asset as ONE engine edit batch: its textures (those whose PNG or JPEG bytes came
// with the upload), its materials, its meshes (each asset mesh
// once, so nodes that share a glTF mesh share one BLAS), and, unless asked not to, the node tree
// as scene-graph groups with one instance per (node, mesh). The scene applies it atomically and
// the journal records it like any POST /v1/edits batch.
//
// The tree: one group named by the prefix holds the whole asset (move it, hide it or remove it
// with one edit) and marks it as an asset (its `asset` field: protocol/asset_index.h); without
// instances it is created too, empty. A node with children becomes a group at its local transform; a node's meshes
// become instances under its own group, or, for a leaf node, directly under its parent's group
// at the node's local transform (most nodes are leaves: no group each). A tree deeper than the
// scene's group depth is flattened to world transforms under the asset's group instead.

#include <optional>
#include <string>
#include <vector>

#include "engine/scene/edits.h"
#include "protocol/assets/asset.h"

namespace strata::assets {

/// How the ids of what an asset creates are formed, and where it is placed.
struct BatchOptions {
    std::string prefix;    ///< every id starts with it: "<prefix>.mesh0", "<prefix>.node3"
    bool instance = true;  ///< false: meshes and materials only
    std::optional<std::string> parent = {};  ///< the group the asset's group joins; nullopt: root
    std::string file = {};  ///< the uploaded file's name: the asset's group's `asset` field
};

/// The batch and the ids it creates, in the order of its edits.
struct AssetBatch {
    EditBatch batch;
    std::vector<std::string> textures;
    std::vector<std::string> meshes;
    std::vector<std::string> materials;
    std::vector<std::string> groups;
    std::vector<std::string> instances;
    std::vector<std::string> edit_ids;  ///< the id each edit creates (for error messages)
    std::vector<std::string> warnings;  ///< the asset's, plus what the scene cannot hold yet
    std::size_t root_edit = 0;          ///< the edit that adds the asset's own group
};

/// Builds the batch. Nodes whose transform the scene cannot use (a zero scale, say) are left
/// out with their subtree and a warning naming them; normals that are zero or not finite are
/// dropped for their mesh with a warning; nothing else is dropped silently.
AssetBatch asset_to_batch(Asset&& asset, const BatchOptions& options);

}  // namespace strata::assets
