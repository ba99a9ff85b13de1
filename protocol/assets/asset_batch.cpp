#include "protocol/assets/asset_batch.h"

namespace strata::assets {

namespace {

std::string label(const std::string& kind, std::size_t i, const std::string& name) {
    return kind + " " + std::to_string(i) + (name.empty() ? "" : " ('" + name + "')");
}

}  // namespace

AssetBatch asset_to_batch(Asset&& asset, const BatchOptions& options) {
    AssetBatch out;
    out.warnings = std::move(asset.warnings);
    const std::string& p = options.prefix;

    // Step 1: materials.
    std::size_t textures_dropped = 0;
    for (std::size_t i = 0; i < asset.materials.size(); ++i) {
        AddMaterial e;
        e.id = p + ".material" + std::to_string(i);
        e.material = asset.materials[i].material;
        if (asset.materials[i].base_color_texture >= 0) ++textures_dropped;
        out.materials.push_back(e.id);
        out.edit_ids.push_back(e.id);
        out.batch.edits.emplace_back(std::move(e));
    }
    // Step 2: meshes. The scene's meshes hold positions and triangles; what else the file had
    // is named in the warnings rather than dropped silently.
    bool normals = false, uvs = false, colors = false;
    for (std::size_t i = 0; i < asset.meshes.size(); ++i) {
        AssetMesh& m = asset.meshes[i];
        normals = normals || !m.normals.empty();
        uvs = uvs || !m.uvs.empty();
        colors = colors || !m.colors.empty();
        AddMesh e;
        e.id = p + ".mesh" + std::to_string(i);
        e.positions = std::move(m.positions);
        e.triangles = std::move(m.triangles);
        if (m.material >= 0) e.material = out.materials[std::size_t(m.material)];
        out.meshes.push_back(e.id);
        out.edit_ids.push_back(e.id);
        out.batch.edits.emplace_back(std::move(e));
    }
    if (normals) out.warnings.push_back("vertex normals dropped: the scene has no per-vertex normals yet");
    if (uvs) out.warnings.push_back("texture coordinates dropped: the scene has no uvs yet");
    if (colors) out.warnings.push_back("vertex colours dropped: the scene has no vertex colours");
    if (textures_dropped)
        out.warnings.push_back(std::to_string(textures_dropped) +
                               " base-colour texture reference(s) dropped: materials have no "
                               "textures yet");
    if (!options.instance) return out;

    // Step 3: the node tree flattened to world transforms (parents come first).
    std::vector<Affine> world(asset.nodes.size());
    for (std::size_t i = 0; i < asset.nodes.size(); ++i) {
        const AssetNode& node = asset.nodes[i];
        world[i] = node.parent >= 0 ? world[std::size_t(node.parent)] * node.local : node.local;
        if (node.meshes.empty()) continue;
        if (const char* why = transform_problem(world[i])) {
            out.warnings.push_back(label("node", i, node.name) + " not placed: its world "
                                                                  "transform is unusable (" +
                                   why + ")");
            continue;
        }
        for (std::size_t k = 0; k < node.meshes.size(); ++k) {
            AddInstance e;
            e.id = p + ".node" + std::to_string(i) +
                   (node.meshes.size() > 1 ? "." + std::to_string(k) : "");
            e.mesh = out.meshes[std::size_t(node.meshes[k])];
            e.transform = world[i];
            out.instances.push_back(e.id);
            out.edit_ids.push_back(e.id);
            out.batch.edits.emplace_back(std::move(e));
        }
    }
    return out;
}

}  // namespace strata::assets
