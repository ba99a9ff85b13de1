#include "protocol/assets/obj_import.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include <tiny_obj_loader.h>

namespace strata::assets {

namespace {

/// Looks material libraries up in the upload only.
class UploadMaterialReader : public tinyobj::MaterialReader {
public:
    explicit UploadMaterialReader(const SideFiles& files) : m_files(files) {}

    bool operator()(const std::string& name, std::vector<tinyobj::material_t>* materials,
                    std::map<std::string, int>* ids, std::string* warn, std::string* err) override {
        const std::string* file = find_side_file(m_files, name);
        if (!file) {
            missing.push_back(name);
            return false;
        }
        std::istringstream in(*file);
        const std::size_t before = materials->size();
        tinyobj::LoadMtl(ids, materials, &in, warn, err);
        // An MTL names its images relative to its own folder.
        const std::size_t slash = name.find_last_of("/\\");
        folders.resize(before, "");
        folders.resize(materials->size(),
                       slash == std::string::npos ? "" : name.substr(0, slash + 1));
        return true;
    }

    std::vector<std::string> missing;
    std::vector<std::string> folders;  ///< per material: its MTL's folder ("" or "dir/")

private:
    const SideFiles& m_files;
};

float unit(float v) {
    return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f;
}

/// Phong/Blinn exponent to a GGX-style perceptual roughness: alpha = sqrt(2 / (Ns + 2)) is the
/// usual Blinn-Phong match, and roughness = sqrt(alpha). No specular colour at all reads as
/// fully rough.
float roughness_from(const tinyobj::material_t& m) {
    const float ks = std::max({m.specular[0], m.specular[1], m.specular[2]});
    if (!(ks > 0.0f)) return 1.0f;
    const float ns = std::isfinite(m.shininess) ? std::clamp(m.shininess, 0.0f, 1e4f) : 0.0f;
    return unit(std::sqrt(std::sqrt(2.0f / (ns + 2.0f))));
}

std::string mime_of(const std::string& name) {
    std::string lower = name;
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (lower.ends_with(".png")) return "image/png";
    if (lower.ends_with(".jpg") || lower.ends_with(".jpeg")) return "image/jpeg";
    return "";
}

struct VertexKey {
    int v, vt, vn;
    bool operator==(const VertexKey&) const = default;
};
struct VertexKeyHash {
    std::size_t operator()(const VertexKey& k) const {
        return std::hash<uint64_t>()((uint64_t(uint32_t(k.v)) << 32) ^
                                     (uint64_t(uint32_t(k.vt)) << 16) ^ uint32_t(k.vn));
    }
};

/// What the text declares, counted before tinyobjloader holds all of it in memory.
struct Declared {
    uint64_t positions = 0;
    uint64_t triangles = 0;
};

/// A face, line or point element's index ("12", "-3", "4/5/6", "7//8") fits tinyobjloader's int;
/// false names the first part that does not (it would wrap silently).
bool indices_fit(std::string_view element, std::string_view& bad) {
    std::size_t i = 0;
    while (i <= element.size()) {
        const std::size_t end = std::min(element.find('/', i), element.size());
        std::string_view part = element.substr(i, end - i);
        if (!part.empty() && (part[0] == '-' || part[0] == '+')) part.remove_prefix(1);
        while (!part.empty() && part[0] == '0') part.remove_prefix(1);
        if (part.size() > 10 || (part.size() == 10 && part > "2147483647")) {
            bad = element.substr(i, end - i);
            return false;
        }
        i = end + 1;
    }
    return true;
}

/// Step 0: one pass over the text. Counts vertex positions and the triangles that faces declare
/// against the budget, and refuses an index that does not fit an int, all before parsing: an
/// over-budget file is refused without the memory that parsing it would take.
Imported<Declared> prescan(std::string_view text, const ErrorSink& sink,
                           const ImportLimits& limits) {
    Declared d;
    std::size_t line_no = 0;
    auto over = [&](uint64_t room, const char* declared, const char* unit) {
        return sink.too_large("line " + std::to_string(line_no),
                              "the file declares more than " + std::to_string(room) + " " +
                                  declared + "; the scene has room for " + std::to_string(room) +
                                  " " + unit);
    };
    for (std::size_t pos = 0; pos < text.size();) {
        const std::size_t eol = std::min(text.find('\n', pos), text.size());
        std::string_view line = text.substr(pos, eol - pos);
        pos = eol + 1;
        ++line_no;
        const std::size_t first = line.find_first_not_of(" \t");
        if (first == std::string_view::npos || first + 1 >= line.size()) continue;
        line.remove_prefix(first);
        if (line[1] != ' ' && line[1] != '\t') continue;
        const char key = line[0];
        if (key == 'v') {
            if (++d.positions > limits.max_vertices)
                return over(limits.max_vertices, "vertex positions",
                            "vertices (max_scene_vertices)");
            continue;
        }
        if (key != 'f' && key != 'l' && key != 'p') continue;
        uint64_t corners = 0;
        std::size_t i = 1;
        while (i < line.size()) {
            while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
            const std::size_t start = i;
            while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
            if (i == start) break;
            std::string_view bad;
            if (!indices_fit(line.substr(start, i - start), bad))
                return sink.invalid("line " + std::to_string(line_no),
                                    "index " + std::string(bad.substr(0, 40)) +
                                        " is out of range (indices are at most 2147483647)");
            ++corners;
        }
        if (key == 'f' && corners >= 3) d.triangles += corners - 2;
        if (d.triangles > limits.max_triangles)
            return over(limits.max_triangles, "triangles", "triangles (max_scene_triangles)");
    }
    return d;
}

/// What tinyobjloader read: the OBJ's arrays, its shapes and the MTL's materials.
struct ObjFile {
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::vector<tinyobj::material_t> mtl;
    std::vector<std::string> folders;  ///< each material's MTL folder in the upload
    std::vector<std::string> missing;  ///< mtllibs the upload does not hold
};

/// Step 1: parse, the MTL from the upload only, polygons kept whole (tinyobjloader's own
/// triangulation reads vertices before anything checked the indices).
Imported<ObjFile> parse_obj(std::string_view text, const SideFiles& side_files,
                            const ErrorSink& sink) {
    ObjFile obj;
    std::string warn, err;
    std::istringstream in{std::string(text)};
    UploadMaterialReader reader(side_files);
    bool ok = false;
    try {
        ok = tinyobj::LoadObj(&obj.attrib, &obj.shapes, &obj.mtl, &warn, &err, &in, &reader,
                              /*triangulate=*/false, /*default_vcols_fallback=*/false);
    } catch (const std::exception& e) {
        return sink.invalid("", std::string("not a valid OBJ file: ") + e.what());
    }
    if (!ok) return sink.invalid("", "not a valid OBJ file: " + err.substr(0, err.find('\n')));
    obj.folders = std::move(reader.folders);
    obj.missing = std::move(reader.missing);
    return obj;
}

/// Most warnings of unread maps listed (a file of thousands of materials must not make the
/// answer huge); the rest are counted.
constexpr std::size_t MAX_MAP_WARNINGS = 64;

/// The MTL maps the engine has no slot for, for warnings.
constexpr std::pair<std::string tinyobj::material_t::*, const char*> UNREAD_MAPS[] = {
    {&tinyobj::material_t::bump_texname, "map_Bump (a height map)"},
    {&tinyobj::material_t::displacement_texname, "disp"},
    {&tinyobj::material_t::alpha_texname, "map_d"},
    {&tinyobj::material_t::specular_texname, "map_Ks"},
    {&tinyobj::material_t::specular_highlight_texname, "map_Ns"},
    {&tinyobj::material_t::ambient_texname, "map_Ka"},
    {&tinyobj::material_t::reflection_texname, "refl"},
    {&tinyobj::material_t::roughness_texname, "map_Pr"},
    {&tinyobj::material_t::metallic_texname, "map_Pm"},
    {&tinyobj::material_t::sheen_texname, "map_Ps"},
};

/// Step 2: materials, with their diffuse (base colour), normal (`norm`) and emissive (`map_Ke`)
/// maps, and dissolve (`d`, or 1 - `Tr`) below 1 as blended alpha. Materials naming the same
/// image in the same colour space share one texture.
void read_materials(const ObjFile& obj, const SideFiles& side_files, Asset& asset) {
    std::map<std::pair<const std::string*, TextureColorSpace>, int> texture_of_file;
    std::size_t unlisted = 0;
    for (std::size_t i = 0; i < obj.mtl.size(); ++i) {
        const tinyobj::material_t& m = obj.mtl[i];
        AssetMaterial out;
        out.name = m.name;
        out.material.base_color = {unit(m.diffuse[0]), unit(m.diffuse[1]), unit(m.diffuse[2])};
        out.material.roughness = m.roughness > 0.0f ? unit(m.roughness) : roughness_from(m);
        out.material.metallic = unit(m.metallic);
        for (int c = 0; c < 3; ++c)
            out.material.emission[c] =
                std::isfinite(m.emission[c]) ? std::clamp(m.emission[c], 0.0f, 1e4f) : 0.0f;
        if (std::isfinite(m.dissolve) && m.dissolve < 1.0f) {
            out.material.alpha = unit(m.dissolve);
            out.material.alpha_mode = AlphaMode::Blend;
        }
        const std::string& folder = i < obj.folders.size() ? obj.folders[i] : "";
        const auto map = [&](const std::string& name, TextureSlot slot) {
            if (name.empty()) return;
            const TextureColorSpace space = TEXTURE_SLOTS[slot_index(slot)].space;
            const std::string* image =
                folder.empty() ? nullptr : find_side_file(side_files, folder + name);
            if (!image) image = find_side_file(side_files, name);
            if (auto shared = texture_of_file.find({image, space});
                image && shared != texture_of_file.end()) {
                out.texture(slot) = shared->second;
                return;
            }
            AssetTexture t;
            t.name = name;
            t.uri = name;
            t.mime_type = mime_of(name);
            t.color_space = space;
            if (image) t.bytes.assign(image->begin(), image->end());
            out.texture(slot) = int(asset.textures.size());
            if (image) texture_of_file.emplace(std::pair(image, space), out.texture(slot));
            asset.textures.push_back(std::move(t));
        };
        map(m.diffuse_texname, TextureSlot::BaseColor);
        map(m.normal_texname, TextureSlot::Normal);
        // An emissive map multiplies Ke; a map with no Ke (black) is read as Ke 1 1 1.
        if (!m.emissive_texname.empty() && out.material.emission == Vec3(0.0f))
            out.material.emission = Vec3(1.0f);
        map(m.emissive_texname, TextureSlot::Emissive);
        for (const auto& [member, keyword] : UNREAD_MAPS) {
            if ((m.*member).empty()) continue;
            if (asset.warnings.size() < MAX_MAP_WARNINGS)
                asset.warnings.push_back("material '" + m.name.substr(0, 64) + "': its " +
                                         keyword + " map '" + (m.*member).substr(0, 256) +
                                         "' is not imported");
            else
                ++unlisted;
        }
        asset.materials.push_back(std::move(out));
    }
    if (unlisted > 0)
        asset.warnings.push_back(std::to_string(unlisted) + " more warnings not listed");
}

/// Step 3: counts triangles against the budget before building anything.
Imported<void> count_faces(const ObjFile& obj, const ImportLimits& limits, const ErrorSink& sink) {
    uint64_t triangles = 0;
    for (std::size_t s = 0; s < obj.shapes.size(); ++s) {
        const tinyobj::mesh_t& m = obj.shapes[s].mesh;
        std::size_t corners = 0;
        for (unsigned char fv : m.num_face_vertices) {
            corners += fv;
            if (fv >= 3) triangles += fv - 2u;
        }
        if (corners != m.indices.size() || m.material_ids.size() != m.num_face_vertices.size())
            return sink.unsupported(
                "shape " + std::to_string(s) + " ('" + obj.shapes[s].name + "')",
                "a face has more than 255 corners");
    }
    if (triangles == 0) return sink.invalid("", "has no faces (points and lines are not imported)");
    if (triangles > limits.max_triangles)
        return sink.too_large("", "the asset holds " + std::to_string(triangles) +
                                      " triangles; the scene has room for " +
                                      std::to_string(limits.max_triangles) +
                                      " (max_scene_triangles)");
    return {};
}

/// Corners with the same (v, vt, vn) of one mesh, and the vertex each became.
using Weld = std::unordered_map<VertexKey, uint32_t, VertexKeyHash>;

/// Checks corner `idx` of face `f` of shape `s` against the arrays it indexes.
Imported<void> check_corner(const ObjFile& obj, const tinyobj::index_t& idx, std::size_t s,
                            std::size_t f, const ErrorSink& sink) {
    const std::size_t n_positions = obj.attrib.vertices.size() / 3;
    const std::size_t n_normals = obj.attrib.normals.size() / 3;
    const std::size_t n_uvs = obj.attrib.texcoords.size() / 2;
    auto outside = [&](const char* what, int index, std::size_t count, const char* of) {
        return sink.invalid("shape " + std::to_string(s) + " face " + std::to_string(f),
                            std::string(what) + " index " + std::to_string(index + 1) +
                                " is outside the " + std::to_string(count) + " " + of);
    };
    if (idx.vertex_index < 0 || std::size_t(idx.vertex_index) >= n_positions)
        return outside("vertex", idx.vertex_index, n_positions, "vertices");
    if (idx.normal_index >= 0 && std::size_t(idx.normal_index) >= n_normals)
        return outside("normal", idx.normal_index, n_normals, "normals");
    if (idx.texcoord_index >= 0 && std::size_t(idx.texcoord_index) >= n_uvs)
        return outside("texture coordinate", idx.texcoord_index, n_uvs, "texture coordinates");
    return {};
}

/// Step 4: one mesh per material; corners with the same (v, vt, vn) share a vertex.
Imported<void> build_meshes(const ObjFile& obj, const ErrorSink& sink, Asset& asset,
                            AssetNode& root, std::vector<Weld>& welds) {
    std::map<int, int> mesh_of_material;
    for (std::size_t s = 0; s < obj.shapes.size(); ++s) {
        const tinyobj::mesh_t& m = obj.shapes[s].mesh;
        std::size_t corner = 0;
        for (std::size_t f = 0; f < m.num_face_vertices.size(); ++f) {
            const unsigned fv = m.num_face_vertices[f];
            const std::size_t first = corner;
            corner += fv;
            if (fv < 3) continue;
            int material = m.material_ids[f];
            if (material < -1 || material >= int(obj.mtl.size())) material = -1;
            auto [it, added] = mesh_of_material.emplace(material, int(asset.meshes.size()));
            if (added) {
                AssetMesh mesh;
                mesh.material = material;
                mesh.name =
                    material >= 0 ? obj.mtl[std::size_t(material)].name : obj.shapes[s].name;
                asset.meshes.push_back(std::move(mesh));
                welds.emplace_back();
                root.meshes.push_back(it->second);
            }
            AssetMesh& mesh = asset.meshes[std::size_t(it->second)];
            Weld& weld = welds[std::size_t(it->second)];
            uint32_t ids[256];
            for (unsigned k = 0; k < fv; ++k) {
                const tinyobj::index_t& idx = m.indices[first + k];
                if (auto ok = check_corner(obj, idx, s, f, sink); !ok) return ok;
                const VertexKey key{idx.vertex_index, idx.texcoord_index, idx.normal_index};
                auto [w, fresh] = weld.emplace(key, uint32_t(mesh.positions.size()));
                if (fresh) {
                    const std::size_t v = std::size_t(idx.vertex_index) * 3;
                    const std::vector<float>& p = obj.attrib.vertices;
                    mesh.positions.push_back({p[v], p[v + 1], p[v + 2]});
                }
                ids[k] = w->second;
            }
            for (unsigned k = 1; k + 1 < fv; ++k)
                mesh.triangles.push_back({ids[0], ids[k], ids[k + 1]});
        }
    }
    return {};
}

/// Step 5: normals and uvs where every corner of a mesh has them (OBJ allows mixing).
void attach_attributes(const ObjFile& obj, const std::vector<Weld>& welds, Asset& asset) {
    const tinyobj::attrib_t& a = obj.attrib;
    for (std::size_t i = 0; i < asset.meshes.size(); ++i) {
        AssetMesh& mesh = asset.meshes[i];
        bool all_n = !a.normals.empty(), all_t = !a.texcoords.empty();
        std::vector<const VertexKey*> by_vertex(mesh.positions.size());
        for (const auto& [key, v] : welds[i]) {
            by_vertex[v] = &key;
            all_n = all_n && key.vn >= 0;
            all_t = all_t && key.vt >= 0;
        }
        for (const VertexKey* key : by_vertex) {
            if (all_n) {
                const std::size_t n = std::size_t(key->vn) * 3;
                mesh.normals.push_back({a.normals[n], a.normals[n + 1], a.normals[n + 2]});
            }
            if (all_t) {
                const std::size_t t = std::size_t(key->vt) * 2;
                // OBJ's v grows upward from the image's bottom row; the engine's (glTF's) grows
                // downward from the top row.
                mesh.uvs.push_back({a.texcoords[t], 1.0f - a.texcoords[t + 1]});
            }
        }
    }
}

}  // namespace

Imported<Asset> import_obj(std::span<const uint8_t> bytes, const std::string& file,
                           const SideFiles& side_files, const ImportLimits& limits) {
    const ErrorSink sink(file);
    const std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    if (auto declared = prescan(text, sink, limits); !declared)
        return Unexpected(std::move(declared).error());
    auto obj = parse_obj(text, side_files, sink);
    if (!obj) return Unexpected(std::move(obj).error());
    Asset asset;
    for (const std::string& name : obj->missing)
        asset.warnings.push_back("mtllib '" + name +
                                 "' is not part of the upload; its materials are left out");
    read_materials(*obj, side_files, asset);
    if (auto s = count_faces(*obj, limits, sink); !s) return Unexpected(std::move(s).error());
    AssetNode root;
    root.name = file;
    std::vector<Weld> welds;
    if (auto s = build_meshes(*obj, sink, asset, root, welds); !s)
        return Unexpected(std::move(s).error());
    attach_attributes(*obj, welds, asset);
    asset.nodes.push_back(std::move(root));
    if (auto ok = check_budget(asset, limits, sink); !ok) return Unexpected(ok.error());
    if (auto ok = validate_asset(asset, sink); !ok) return Unexpected(ok.error());
    return asset;
}

}  // namespace strata::assets
