#include "protocol/assets/asset_batch.h"

#include <algorithm>
#include <cmath>

#include "engine/core/utf8.h"
#include "engine/image/texture_decode.h"
#include "engine/scene/field_table.h"
#include "engine/scene/scene.h"

namespace strata::assets {

namespace {

/// A name from the file as a display name the scene accepts: bytes that are not UTF-8 become
/// U+FFFD, control characters spaces, and it is cut (on a character) at MAX_NAME_BYTES.
std::string display_name(std::string_view raw) {
    std::string out;
    while (!raw.empty()) {
        const std::size_t n = utf8_sequence_length(raw);
        std::string_view piece = n == 0 ? std::string_view("\xEF\xBF\xBD") : raw.substr(0, n);
        if (n > 0 && is_control_code_point(utf8_code_point(raw, n))) piece = " ";
        if (out.size() + piece.size() > MAX_NAME_BYTES) break;
        out += piece;
        raw.remove_prefix(n == 0 ? 1 : n);
    }
    return out;
}

std::string label(const std::string& kind, std::size_t i, const std::string& name) {
    return kind + " " + std::to_string(i) + (name.empty() ? "" : " ('" + name + "')");
}

/// True when every normal is finite and not zero (what add_mesh accepts).
bool usable_normals(const std::vector<Vec3>& normals) {
    for (const Vec3& n : normals)
        if (!is_finite(n) || glm::dot(n, n) == 0.0f) return false;
    return true;
}

/// True when every tangent is finite with a non-zero direction; w becomes the sign it stands for
/// (glTF asks for exactly +1 or -1; exporters write 0.99999 and, rarely, 0).
bool usable_tangents(std::vector<Vec4>& tangents) {
    for (Vec4& t : tangents) {
        if (!is_finite(t) || glm::dot(Vec3(t), Vec3(t)) == 0.0f) return false;
        t.w = t.w < 0.0f ? -1.0f : 1.0f;
    }
    return true;
}

bool usable_uvs(const std::vector<glm::vec2>& uvs) {
    for (const glm::vec2& t : uvs)
        if (!std::isfinite(t.x) || !std::isfinite(t.y)) return false;
    return true;
}

/// Appends `e`, the edit that creates `id`, to the batch, listing `id` in `ids` (one of the
/// batch's lists) and among the edit ids.
void add_edit(AssetBatch& out, Edit&& e, const std::string& id, std::vector<std::string>& ids) {
    ids.push_back(id);
    out.edit_ids.push_back(id);
    out.batch.edits.emplace_back(std::move(e));
}

/// Adds the textures whose bytes came with the upload (the engine decodes them when it applies
/// the batch: a damaged PNG or JPEG refuses the whole import, naming the texture). Images the
/// upload does not hold, or in formats the engine does not decode, are named in a warning.
/// Returns each texture's id, empty for those left out.
std::vector<std::string> add_textures(std::vector<AssetTexture>& textures, const std::string& p,
                                      AssetBatch& out) {
    std::vector<std::string> texture_ids(textures.size());
    for (std::size_t i = 0; i < textures.size(); ++i) {
        AssetTexture& t = textures[i];
        const std::string what = label("texture", i, t.name.empty() ? t.uri : t.name);
        if (t.bytes.empty()) {
            out.warnings.push_back(what + " left out: its image is not part of the upload" +
                                   (t.uri.empty() ? std::string() : " ('" + t.uri + "')"));
            continue;
        }
        AddTexture e;
        e.id = p + ".texture" + std::to_string(i);
        e.name = display_name(t.name);
        e.color_space = t.color_space;
        e.data.assign(t.bytes.begin(), t.bytes.end());
        t.bytes = {};
        if (!texture_format(e.data)) {
            out.warnings.push_back(
                what + " left out: only PNG and JPEG images are decoded" +
                (t.mime_type.empty() ? std::string() : " (it is " + t.mime_type + ")"));
            continue;
        }
        texture_ids[i] = e.id;
        const std::string id = e.id;
        add_edit(out, std::move(e), id, out.textures);
    }
    return texture_ids;
}

/// Adds the materials, each with its textures when the batch holds them (`texture_ids`:
/// add_textures' answer).
void add_materials(const std::vector<AssetMaterial>& materials,
                   const std::vector<std::string>& texture_ids, const std::string& p,
                   AssetBatch& out) {
    for (std::size_t i = 0; i < materials.size(); ++i) {
        AddMaterial e;
        e.id = p + ".material" + std::to_string(i);
        e.material = materials[i].material;
        e.material.name = display_name(materials[i].name);
        for (std::size_t slot = 0; slot < TEXTURE_SLOT_COUNT; ++slot) {
            const int texture = materials[i].textures[slot];
            if (texture >= 0 && !texture_ids[std::size_t(texture)].empty())
                e.textures[slot] = texture_ids[std::size_t(texture)];
        }
        // An emissive factor without its texture would light the whole surface where the
        // texture lights parts of it: it goes too.
        const std::size_t emissive = slot_index(TextureSlot::Emissive);
        if (materials[i].textures[emissive] >= 0 && !e.textures[emissive] &&
            e.material.emission != Vec3(0.0f)) {
            e.material.emission = Vec3(0.0f);
            out.warnings.push_back(label("material", i, materials[i].name) +
                                   ": its emission is left out with its emissive texture");
        }
        const std::string id = e.id;
        add_edit(out, std::move(e), id, out.materials);
    }
}

/// Adds the meshes with their normals, uvs and tangents, or, for points and curves (linear, round),
/// their radii and strands; what the scene cannot hold is named in the warnings rather than
/// dropped silently.
void add_meshes(std::vector<AssetMesh>& meshes, const std::string& p, AssetBatch& out) {
    bool colors = false;
    for (std::size_t i = 0; i < meshes.size(); ++i) {
        AssetMesh& m = meshes[i];
        colors = colors || !m.colors.empty();
        AddMesh e;
        e.id = p + ".mesh" + std::to_string(i);
        e.name = display_name(m.name);
        e.kind = m.kind;
        e.positions = std::move(m.positions);
        e.triangles = std::move(m.triangles);
        e.radii = std::move(m.radii);
        e.strands = std::move(m.strands);
        if (usable_normals(m.normals)) {
            e.normals = std::move(m.normals);
        } else {
            out.warnings.push_back(label("mesh", i, m.name) +
                                   ": normals dropped (some are zero or not finite)");
        }
        for (auto [from, to, set] :
             {std::tuple{&m.uvs, &e.uvs, "0"}, std::tuple{&m.uvs1, &e.uvs1, "1"}}) {
            if (usable_uvs(*from)) {
                *to = std::move(*from);
            } else {
                out.warnings.push_back(label("mesh", i, m.name) + ": texture coordinates (set " +
                                       set + ") dropped (some are not finite)");
            }
        }
        // Tangents go with the normals they are orthogonal to (glTF: no TANGENT without NORMAL).
        if (!m.tangents.empty() && (e.normals.empty() || !usable_tangents(m.tangents))) {
            out.warnings.push_back(label("mesh", i, m.name) +
                                   (e.normals.empty() ? ": tangents without normals dropped"
                                                      : ": tangents dropped (some are zero or "
                                                        "not finite)") +
                                   "; normal maps use tangents the server makes");
        } else {
            e.tangents = std::move(m.tangents);
        }
        if (m.material >= 0) e.material = out.materials[std::size_t(m.material)];
        const std::string id = e.id;
        add_edit(out, std::move(e), id, out.meshes);
    }
    if (colors) out.warnings.push_back("vertex colours dropped: the scene has no vertex colours");
}

/// What the node tree asks of the scene's groups.
struct TreeShape {
    std::vector<bool> has_children;  ///< per node
    uint32_t deepest = 1;            ///< group levels needed, the asset's group included
};

/// The shape of the node tree `nodes` (parents come first).
TreeShape tree_shape(const std::vector<AssetNode>& nodes) {
    const std::size_t n = nodes.size();
    TreeShape shape;
    shape.has_children.assign(n, false);
    std::vector<uint32_t> depth(n, 1);  // a root node's group would sit under the asset's group
    for (std::size_t i = 0; i < n; ++i) {
        const int parent = nodes[i].parent;
        if (parent < 0) continue;
        shape.has_children[std::size_t(parent)] = true;
        depth[i] = depth[std::size_t(parent)] + 1;
    }
    for (std::size_t i = 0; i < n; ++i)
        if (shape.has_children[i]) shape.deepest = std::max(shape.deepest, depth[i] + 1);
    return shape;
}

/// An animated node's keyframes go to its group or instances, interpolated as glTF does (its
/// rotations by slerp).
template <class Edit>
void set_animation(Edit& e, const std::vector<Keyframe>& keys) {
    e.animation = keys;
    if (!keys.empty()) e.motion_interpolation = MotionInterpolation::Srt;
}

/// Adds one instance of each of `node`'s meshes under the group `parent` at `transform`
/// (animated as `keys` say); `id` is the node's, and tells its instances apart when it has
/// several meshes.
void add_instances(const AssetNode& node, const std::string& id, const Affine& transform,
                   const std::vector<Keyframe>& keys, const std::string& parent,
                   AssetBatch& out) {
    for (std::size_t k = 0; k < node.meshes.size(); ++k) {
        AddInstance e;
        e.id = id + (node.meshes.size() > 1 ? "." + std::to_string(k) : "");
        e.name = display_name(node.name);
        e.mesh = out.meshes[std::size_t(node.meshes[k])];
        e.transform = transform;
        set_animation(e, keys);
        e.parent = parent;
        const std::string instance_id = e.id;
        add_edit(out, std::move(e), instance_id, out.instances);
    }
}

/// Adds the node tree (`has_children`: tree_shape's) under the asset's group `p`, or, with
/// `flatten`, every node's instances directly under `p` at its world transform. A node whose
/// transform the scene cannot use is left out with its subtree, and a warning.
void add_nodes(const std::vector<AssetNode>& nodes, const std::vector<bool>& has_children,
               bool flatten, const std::string& p, AssetBatch& out) {
    const std::size_t n = nodes.size();
    std::vector<bool> placed(n, false);    // false: left out (with its subtree)
    std::vector<std::string> group_of(n);  // the group a node's children join
    std::vector<Affine> world(n);          // only used when flattening
    for (std::size_t i = 0; i < n; ++i) {
        const AssetNode& node = nodes[i];
        const int parent = node.parent;
        if (parent >= 0 && !placed[std::size_t(parent)]) continue;
        world[i] = parent >= 0 ? world[std::size_t(parent)] * node.local : node.local;
        const Affine& t = flatten ? world[i] : node.local;
        if (const char* why = transform_problem(t)) {
            out.warnings.push_back(label("node", i, node.name) +
                                   " left out with its children: its transform is unusable (" +
                                   why + ")");
            continue;
        }
        placed[i] = true;
        const std::string& parent_group =
            parent >= 0 && !flatten ? group_of[std::size_t(parent)] : p;
        if (flatten && !node.animation.empty())
            out.warnings.push_back(label("node", i, node.name) +
                                   "'s animation not imported: the node tree is flattened");
        static const std::vector<Keyframe> STILL;
        // A node with children is a group; a leaf's instances carry its transform themselves.
        Affine instance_transform = t;
        const std::vector<Keyframe>* instance_keys = flatten ? &STILL : &node.animation;
        std::string instance_parent = parent_group;
        if (has_children[i] && !flatten) {
            AddGroup g;
            g.id = p + ".group" + std::to_string(i);
            g.name = display_name(node.name);
            g.parent = parent_group;
            g.transform = node.local;
            set_animation(g, node.animation);
            instance_keys = &STILL;
            group_of[i] = g.id;
            const std::string id = g.id;
            add_edit(out, std::move(g), id, out.groups);
            instance_transform = Affine::identity();
            instance_parent = group_of[i];
        } else {
            group_of[i] = parent_group;
        }
        add_instances(node, p + ".node" + std::to_string(i), instance_transform, *instance_keys,
                      instance_parent, out);
    }
}

}  // namespace

AssetBatch asset_to_batch(Asset&& asset, const BatchOptions& options) {
    AssetBatch out;
    out.warnings = std::move(asset.warnings);
    const std::string& p = options.prefix;
    const std::vector<std::string> texture_ids = add_textures(asset.textures, p, out);
    add_materials(asset.materials, texture_ids, p, out);
    add_meshes(asset.meshes, p, out);

    // The asset's own group, then the node tree (nodes come parents first).
    {
        AddGroup g;
        g.id = p;
        g.parent = options.parent;
        g.asset = options.file;
        out.root_edit = out.batch.edits.size();
        add_edit(out, std::move(g), p, out.groups);
    }
    if (!options.instance) return out;
    const TreeShape shape = tree_shape(asset.nodes);
    const bool flatten = shape.deepest > MAX_GROUP_DEPTH;
    if (flatten)
        out.warnings.push_back("the node tree is " + std::to_string(shape.deepest) +
                               " levels deep, more than the scene's groups allow (" +
                               std::to_string(MAX_GROUP_DEPTH) +
                               "): flattened to world transforms under '" + p + "'");
    add_nodes(asset.nodes, shape.has_children, flatten, p, out);
    return out;
}

}  // namespace strata::assets
