#include "protocol/assets/assimp_import.h"

#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <vector>

#include <assimp/DefaultLogger.hpp>
#include <assimp/IOSystem.hpp>
#include <assimp/Importer.hpp>
#include <assimp/MemoryIOWrapper.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "engine/image/png.h"

namespace strata::assets {

namespace {

/// The name assimp is asked to read; its extension picks the reader.
constexpr const char* UPLOAD = "upload";

/// What assimp may open: the upload itself and its side files, from memory. Never a file of the
/// server: any other name does not exist.
class UploadFiles final : public Assimp::IOSystem {
public:
    UploadFiles(std::span<const uint8_t> bytes, std::string name, const SideFiles& side)
        : m_bytes(bytes), m_name(std::move(name)), m_side(side) {}

    bool Exists(const char* file) const override { return find(file).data() != nullptr; }
    char getOsSeparator() const override { return '/'; }
    Assimp::IOStream* Open(const char* file, const char* mode) override {
        if (mode == nullptr || std::strchr(mode, 'w') || std::strchr(mode, 'a')) return nullptr;
        const std::span<const uint8_t> data = find(file);
        if (data.data() == nullptr) return nullptr;
        return new Assimp::MemoryIOStream(data.data(), data.size());
    }
    void Close(Assimp::IOStream* stream) override { delete stream; }

private:
    std::span<const uint8_t> find(const char* file) const {
        if (file == nullptr) return {};
        std::string_view name(file);
        if (name.substr(0, 2) == "./") name.remove_prefix(2);
        if (name == m_name) return m_bytes;
        const std::string* side = find_side_file(m_side, name);
        if (!side) return {};
        return {reinterpret_cast<const uint8_t*>(side->data()), side->size()};
    }

    std::span<const uint8_t> m_bytes;
    std::string m_name;
    const SideFiles& m_side;
};

std::string text(const aiString& s) {
    return std::string(s.C_Str(), s.length);
}

std::string label(const char* kind, unsigned i, const aiString& name) {
    return std::string(kind) + " " + std::to_string(i) +
           (name.length > 0 ? " ('" + text(name) + "')" : "");
}

Vec3 vec(const aiVector3D& v) {
    return {v.x, v.y, v.z};
}

bool finite(const aiVector3D& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Step: meshes ------------------------------------------------------------------------------------

/// Converts mesh `m` (triangles only: assimp triangulated it), or says why it is left out.
std::optional<AssetMesh> convert_mesh(const aiMesh& m, unsigned index, const ErrorSink& sink,
                                      std::vector<std::string>& warnings,
                                      std::optional<protocol::Problem>& problem) {
    const std::string what = label("mesh", index, m.mName);
    if (!(m.mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) {
        warnings.push_back(what + " left out: points and lines are not imported");
        return std::nullopt;
    }
    if (m.mPrimitiveTypes & (aiPrimitiveType_POINT | aiPrimitiveType_LINE))
        warnings.push_back(what + ": its points and lines are left out");
    AssetMesh out;
    out.name = text(m.mName);
    out.material = int(m.mMaterialIndex);
    out.positions.reserve(m.mNumVertices);
    for (unsigned v = 0; v < m.mNumVertices; ++v) {
        if (!finite(m.mVertices[v])) {
            problem = sink.invalid(what, "vertex " + std::to_string(v) + " is not finite").error();
            return std::nullopt;
        }
        out.positions.push_back(vec(m.mVertices[v]));
    }
    for (unsigned f = 0; f < m.mNumFaces; ++f) {
        const aiFace& face = m.mFaces[f];
        if (face.mNumIndices != 3) continue;  // a point or a line of a mixed mesh
        const Triangle t{face.mIndices[0], face.mIndices[1], face.mIndices[2]};
        if (t.x >= m.mNumVertices || t.y >= m.mNumVertices || t.z >= m.mNumVertices) {
            problem = sink.invalid(what, "face " + std::to_string(f) + " names a vertex past its " +
                                             std::to_string(m.mNumVertices))
                          .error();
            return std::nullopt;
        }
        out.triangles.push_back(t);
    }
    if (m.HasNormals()) {
        out.normals.reserve(m.mNumVertices);
        for (unsigned v = 0; v < m.mNumVertices; ++v) out.normals.push_back(vec(m.mNormals[v]));
    }
    for (unsigned set = 0; set < 2; ++set) {
        if (!m.HasTextureCoords(set)) continue;
        std::vector<glm::vec2>& uvs = set == 0 ? out.uvs : out.uvs1;
        uvs.reserve(m.mNumVertices);
        for (unsigned v = 0; v < m.mNumVertices; ++v)
            uvs.emplace_back(m.mTextureCoords[set][v].x, m.mTextureCoords[set][v].y);
    }
    if (m.HasTextureCoords(2)) warnings.push_back(what + ": texture coordinate sets beyond 1 left out");
    if (m.HasVertexColors(0)) {
        out.colors.reserve(m.mNumVertices);
        for (unsigned v = 0; v < m.mNumVertices; ++v)
            out.colors.emplace_back(m.mColors[0][v].r, m.mColors[0][v].g, m.mColors[0][v].b);
    }
    if (m.HasBones())
        warnings.push_back(what + ": " + std::to_string(m.mNumBones) +
                           " bones left out (skins are not imported)");
    if (m.mNumAnimMeshes > 0)
        warnings.push_back(what + ": " + std::to_string(m.mNumAnimMeshes) +
                           " morph targets left out");
    return out;
}

// Step: textures and materials -------------------------------------------------------------------

/// An embedded texture as PNG or JPEG bytes: compressed ones as they are, raw texels (BGRA8)
/// encoded as PNG; nullopt for other compressed formats.
std::optional<AssetTexture> embedded(const aiTexture& t, const std::string& name) {
    AssetTexture out;
    out.name = name;
    if (t.mHeight == 0) {
        const std::string hint(t.achFormatHint);
        if (hint != "png" && hint != "jpg" && hint != "jpeg") return std::nullopt;
        out.mime_type = hint == "png" ? "image/png" : "image/jpeg";
        const auto* data = reinterpret_cast<const uint8_t*>(t.pcData);
        out.bytes.assign(data, data + t.mWidth);
        return out;
    }
    std::vector<uint8_t> rgba(std::size_t(t.mWidth) * t.mHeight * 4);
    for (std::size_t i = 0; i < std::size_t(t.mWidth) * t.mHeight; ++i) {
        const aiTexel& x = t.pcData[i];
        rgba[4 * i] = x.r;
        rgba[4 * i + 1] = x.g;
        rgba[4 * i + 2] = x.b;
        rgba[4 * i + 3] = x.a;
    }
    auto png = encode_png(rgba.data(), t.mWidth, t.mHeight, 4);
    if (!png) return std::nullopt;
    out.mime_type = "image/png";
    out.bytes.assign(png.value().begin(), png.value().end());
    return out;
}

/// Textures by the path a material names, each added once.
class TextureTable {
public:
    TextureTable(const aiScene& scene, const SideFiles& side, Asset& asset)
        : m_scene(scene), m_side(side), m_asset(asset) {}

    /// The texture `path` names (embedded "*N", an embedded file name, a side file, or only its
    /// uri) decoded in `space`; -1 when it is embedded in a format the renderer does not read (a
    /// warning says so).
    int get(const std::string& path, const std::string& material, TextureColorSpace space) {
        const auto key = std::pair(path, space);
        if (const auto it = m_index.find(key); it != m_index.end()) return it->second;
        int index = -1;
        if (const aiTexture* t = m_scene.GetEmbeddedTexture(path.c_str())) {
            if (auto tex = embedded(*t, path)) {
                tex->color_space = space;
                index = add(std::move(*tex));
            } else {
                m_asset.warnings.push_back(material + ": its embedded texture '" + path +
                                           "' is in a format other than PNG and JPEG; left out");
            }
        } else {
            AssetTexture tex;
            tex.name = path;
            tex.uri = path;
            tex.color_space = space;
            if (const std::string* file = find_side_file(m_side, path))
                tex.bytes.assign(file->begin(), file->end());
            index = add(std::move(tex));
        }
        m_index.emplace(key, index);
        return index;
    }

private:
    int add(AssetTexture&& t) {
        m_asset.textures.push_back(std::move(t));
        return int(m_asset.textures.size() - 1);
    }

    const aiScene& m_scene;
    const SideFiles& m_side;
    Asset& m_asset;
    std::map<std::pair<std::string, TextureColorSpace>, int> m_index;
};

float clamp01(float v) {
    return std::isfinite(v) ? std::min(std::max(v, 0.0f), 1.0f) : 0.0f;
}

/// The texture kinds the renderer does not read, for warnings (metalness, roughness and occlusion
/// come as separate images here, where the engine reads glTF's packed channels).
constexpr std::pair<aiTextureType, const char*> UNREAD_TEXTURES[] = {
    {aiTextureType_HEIGHT, "height (bump)"},
    {aiTextureType_SPECULAR, "specular"},    {aiTextureType_SHININESS, "shininess"},
    {aiTextureType_OPACITY, "opacity"},      {aiTextureType_AMBIENT, "ambient"},
    {aiTextureType_LIGHTMAP, "light map"},   {aiTextureType_REFLECTION, "reflection"},
    {aiTextureType_METALNESS, "metalness"},  {aiTextureType_DIFFUSE_ROUGHNESS, "roughness"},
    {aiTextureType_AMBIENT_OCCLUSION, "occlusion"}, {aiTextureType_DISPLACEMENT, "displacement"},
};

AssetMaterial convert_material(const aiMaterial& m, unsigned index, TextureTable& textures,
                               std::vector<std::string>& warnings) {
    AssetMaterial out;
    aiString name;
    if (m.Get(AI_MATKEY_NAME, name) == AI_SUCCESS) out.name = text(name);
    const std::string what = label("material", index, name);
    aiColor4D c;
    if (m.Get(AI_MATKEY_BASE_COLOR, c) == AI_SUCCESS || m.Get(AI_MATKEY_COLOR_DIFFUSE, c) == AI_SUCCESS)
        out.material.base_color = {clamp01(c.r), clamp01(c.g), clamp01(c.b)};
    float metallic = 0.0f, roughness = 0.0f, shininess = 0.0f;
    if (m.Get(AI_MATKEY_METALLIC_FACTOR, metallic) == AI_SUCCESS)
        out.material.metallic = clamp01(metallic);
    if (m.Get(AI_MATKEY_ROUGHNESS_FACTOR, roughness) == AI_SUCCESS) {
        out.material.roughness = clamp01(roughness);
    } else if (m.Get(AI_MATKEY_SHININESS, shininess) == AI_SUCCESS && std::isfinite(shininess) &&
               shininess >= 0.0f) {
        out.material.roughness = clamp01(std::pow(2.0f / (shininess + 2.0f), 0.25f));  // as OBJ
    }
    aiColor3D e;
    const bool emissive_map = m.GetTextureCount(aiTextureType_EMISSIVE) > 0;
    if (m.Get(AI_MATKEY_COLOR_EMISSIVE, e) != AI_SUCCESS || !std::isfinite(e.r + e.g + e.b))
        e = emissive_map ? aiColor3D(1.0f, 1.0f, 1.0f) : aiColor3D(0.0f, 0.0f, 0.0f);
    float intensity = 1.0f;  // glTF's KHR_materials_emissive_strength, FBX's factor
    if (m.Get(AI_MATKEY_EMISSIVE_INTENSITY, intensity) != AI_SUCCESS ||
        !std::isfinite(intensity) || intensity < 0.0f)
        intensity = 1.0f;
    intensity = std::min(intensity, 1e6f);
    out.material.emission =
        intensity * Vec3(std::max(e.r, 0.0f), std::max(e.g, 0.0f), std::max(e.b, 0.0f));
    // Each map with the texture coordinate set (assimp's uv channel) it reads.
    const auto map = [&](TextureSlot slot, aiTextureType type) {
        aiString path;
        unsigned channel = 0;
        if (m.GetTexture(type, 0, &path, nullptr, &channel) != AI_SUCCESS) return false;
        const TextureSlotInfo& info = TEXTURE_SLOTS[slot_index(slot)];
        out.texture(slot) = textures.get(text(path), what, info.space);
        if (channel > 1)
            warnings.push_back(what + ": its " + std::string(info.field) + " reads uv channel " +
                               std::to_string(channel) + "; channels 0 and 1 are imported, and "
                               "it reads channel 0");
        out.material.*(info.uv_set) = channel == 1 ? 1 : 0;
        return true;
    };
    if (!map(TextureSlot::BaseColor, aiTextureType_BASE_COLOR))
        map(TextureSlot::BaseColor, aiTextureType_DIFFUSE);
    map(TextureSlot::Normal, aiTextureType_NORMALS);
    if (emissive_map) map(TextureSlot::Emissive, aiTextureType_EMISSIVE);
    for (const auto& [type, kind] : UNREAD_TEXTURES)
        if (m.GetTextureCount(type) > 0)
            warnings.push_back(what + ": its " + std::string(kind) + " texture is not imported");
    return out;
}

// Step: the node tree -----------------------------------------------------------------------------

/// Appends `node` and its subtree, parents first; meshes left out (`kept[i]` -1) are dropped from
/// the nodes.
void add_nodes(const aiNode& node, int parent, const std::vector<int>& kept, uint32_t depth,
               Asset& asset, const ImportLimits& limits, bool& too_many) {
    if (asset.nodes.size() >= limits.max_nodes || depth > 4096) {
        too_many = true;
        return;
    }
    AssetNode out;
    out.name = text(node.mName);
    out.parent = parent;
    const aiMatrix4x4& t = node.mTransformation;
    out.local.m = {t.a1, t.a2, t.a3, t.a4, t.b1, t.b2, t.b3, t.b4, t.c1, t.c2, t.c3, t.c4};
    for (unsigned i = 0; i < node.mNumMeshes; ++i)
        if (node.mMeshes[i] < kept.size() && kept[node.mMeshes[i]] >= 0)
            out.meshes.push_back(kept[node.mMeshes[i]]);
    const int self = int(asset.nodes.size());
    asset.nodes.push_back(std::move(out));
    for (unsigned i = 0; i < node.mNumChildren; ++i)
        if (node.mChildren[i]) add_nodes(*node.mChildren[i], self, kept, depth + 1, asset, limits, too_many);
}

/// The file's counts against the budget, before anything is copied.
Imported<void> charge(const aiScene& s, const ImportLimits& limits, const ErrorSink& sink) {
    uint64_t vertices = 0, triangles = 0;
    for (unsigned i = 0; i < s.mNumMeshes; ++i) {
        vertices += s.mMeshes[i]->mNumVertices;
        triangles += s.mMeshes[i]->mNumFaces;
    }
    if (vertices > limits.max_vertices)
        return sink.too_large("", std::to_string(vertices) + " vertices: more than the " +
                                      std::to_string(limits.max_vertices) +
                                      " the scene's budget has room for (max_scene_vertices)");
    if (triangles > limits.max_triangles)
        return sink.too_large("", std::to_string(triangles) + " triangles: more than the " +
                                      std::to_string(limits.max_triangles) +
                                      " the scene's budget has room for (max_scene_triangles)");
    return {};
}

/// What the file holds that is not imported, scene-wide.
void scene_warnings(const aiScene& s, std::vector<std::string>& warnings) {
    const auto count = [&](unsigned n, const char* what) {
        if (n > 0) warnings.push_back(std::to_string(n) + " " + what + " left out");
    };
    count(s.mNumAnimations, "animations");
    count(s.mNumCameras, "cameras");
    count(s.mNumLights, "lights");
}

}  // namespace

Imported<Asset> import_assimp(std::span<const uint8_t> bytes, AssetFormat format,
                              const std::string& file, const ImportLimits& limits,
                              const SideFiles& side_files) {
    const ErrorSink sink(file);
    const std::string upload = std::string(UPLOAD) + "." + format_name(format);
    Assimp::Importer importer;
    importer.SetIOHandler(new UploadFiles(bytes, upload, side_files));
    importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
    const unsigned flags = aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                           aiProcess_SortByPType | aiProcess_ValidateDataStructure |
                           aiProcess_FlipUVs;
    const aiScene* scene = importer.ReadFile(upload, flags);
    if (!scene) {
        std::string why = importer.GetErrorString();
        if (why.empty()) why = "assimp could not read it";
        return sink.invalid("", "not a readable " + std::string(format_name(format)) +
                                    " file: " + why);
    }
    if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode)
        return sink.invalid("", "assimp read an incomplete scene (no node tree)");
    if (auto fits = charge(*scene, limits, sink); !fits) return Unexpected(fits.error());

    Asset asset;
    scene_warnings(*scene, asset.warnings);
    std::vector<int> kept(scene->mNumMeshes, -1);
    for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
        std::optional<protocol::Problem> problem;
        auto mesh = convert_mesh(*scene->mMeshes[i], i, sink, asset.warnings, problem);
        if (problem) return Unexpected(std::move(*problem));
        if (!mesh) continue;
        if (mesh->material >= int(scene->mNumMaterials)) mesh->material = -1;
        kept[i] = int(asset.meshes.size());
        asset.meshes.push_back(std::move(*mesh));
    }
    TextureTable textures(*scene, side_files, asset);
    for (unsigned i = 0; i < scene->mNumMaterials; ++i)
        asset.materials.push_back(convert_material(*scene->mMaterials[i], i, textures, asset.warnings));
    bool too_many = false;
    add_nodes(*scene->mRootNode, -1, kept, 1, asset, limits, too_many);
    if (too_many)
        return sink.too_large("", "more than " + std::to_string(limits.max_nodes) +
                                      " nodes, or a tree deeper than 4096");
    if (auto valid = validate_asset(asset, sink); !valid) return Unexpected(valid.error());
    return asset;
}

}  // namespace strata::assets
