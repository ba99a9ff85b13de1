#pragma once
// Imports as units (GET, DELETE and PUT /v1/assets/{id}). An asset is a group whose `asset` field
// is set (POST /v1/assets sets it to the uploaded file's name) together with every object whose
// id begins with the group's id and a '.' ("city" owns "city.mesh0", "city.node3.1"); when two
// asset ids are prefixes of one another the longer one owns ("city.park" owns "city.park.mesh0").
// The scene knows nothing of assets beyond the field: ownership is read from the ids each time,
// so it holds in snapshots, the journal, undo and older versions alike, and objects a client
// adds under an asset's prefix belong to it.

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "engine/scene/edits.h"
#include "engine/scene/scene.h"
#include "protocol/scene_json.h"

namespace strata::protocol {

/// What one asset owns, each list in slot order (groups: the asset's own group first).
struct AssetContents {
    GroupHandle group;
    std::vector<TextureHandle> textures;
    std::vector<MaterialHandle> materials;
    std::vector<MeshHandle> meshes;
    std::vector<GroupHandle> groups;
    std::vector<InstanceHandle> instances;
};

/// Every asset of the scene by id, with what it owns. O(objects x the dots in their ids).
std::map<std::string, AssetContents> scene_assets(const Scene& s);

/// The asset `id`, or nullopt when no group with that id has `asset` set. O(objects).
std::optional<AssetContents> find_asset(const Scene& s, std::string_view id);

/// An asset as GET /v1/assets lists it: id, file, name, counts and world bounds; with `ids`,
/// the ids of what it owns too (GET /v1/assets/{id}). The bounds walk its instances.
Json asset_to_json(const Scene& s, const AssetContents& a, bool ids);

/// The edits that remove everything `a` owns, in an order the scene accepts: instances, groups
/// (children first, the asset's own group last), meshes, materials, textures. Each edit's id is
/// appended to `edit_ids`. An object outside the asset that still uses one of its meshes,
/// materials or textures, or sits in one of its groups, makes the batch fail on that edit.
std::vector<Edit> removal_edits(const Scene& s, const AssetContents& a,
                                std::vector<std::string>& edit_ids);

}  // namespace strata::protocol
