#include "protocol/assets/gltf_import.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <limits>
#include <map>

#include <glm/gtc/quaternion.hpp>
#include <nlohmann/json.hpp>

#include "engine/scene/budget.h"
#include "protocol/assets/draco_decode.h"
#include "protocol/assets/tinygltf_config.h"

namespace strata::assets {

namespace {

// Filesystem callbacks: tinygltf reaches the filesystem only through these, and they reach only
// the upload's side files (user data: the SideFiles). Every file a model names "exists" so that
// the read that follows names what is missing (tinygltf would otherwise answer "file not found").
bool any_file_exists(const std::string&, void*) {
    return true;
}
std::string keep_path(const std::string& path, void*) {
    return path;
}
bool read_side_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                    void* user) {
    const auto* files = static_cast<const SideFiles*>(user);
    if (const std::string* file = files ? find_side_file(*files, path) : nullptr) {
        out->assign(file->begin(), file->end());
        return true;
    }
    if (err)
        *err += "external file '" + path +
                "' refused: it is not part of the upload (upload a .glb, a .gltf whose buffers "
                "are data: URIs, or a tar archive holding the .gltf and its files)\n";
    return false;
}
bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
    if (err) *err += "writing files is not allowed\n";
    return false;
}

/// Keeps a data: URI image's encoded bytes as they are; decoding is the renderer's business. An
/// image in a buffer view is copied later, after its range is checked (tinygltf hands this
/// callback a pointer into the buffer without checking the view lies inside it).
bool keep_encoded_image(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                        const unsigned char* bytes, int size, void*) {
    if (image->bufferView < 0 && size > 0) image->image.assign(bytes, bytes + size);
    image->as_is = true;
    return true;
}

/// What one pass over the JSON text finds before tinygltf builds its model of it.
/// The most warnings an import lists; the rest are counted.
constexpr std::size_t MAX_WARNINGS = 64;

struct JsonShape {
    uint32_t deepest = 0;     ///< deepest nesting of `[`/`{` (counting stops past the limit)
    uint64_t primitives = 0;  ///< objects in every "primitives" array
};

/// The nesting and the primitives of JSON text, strings skipped; stops past `depth_limit`.
JsonShape json_shape(std::string_view text, uint32_t depth_limit) {
    JsonShape shape;
    uint32_t depth = 0;
    uint32_t primitives_at = 0;   // the depth inside a "primitives" array; 0: none open
    bool primitives_key = false;  // the last string was the key "primitives"
    std::size_t string_start = 0;
    bool in_string = false;
    for (std::size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (in_string) {
            if (c == '\\') {
                ++i;
            } else if (c == '"') {
                in_string = false;
                primitives_key = text.substr(string_start, i - string_start) == "primitives";
            }
            continue;
        }
        if (c == '"') {
            in_string = true;
            string_start = i + 1;
        } else if (c == '[' || c == '{') {
            if (c == '{' && depth == primitives_at && primitives_at != 0) ++shape.primitives;
            shape.deepest = std::max(shape.deepest, ++depth);
            if (c == '[' && primitives_key && primitives_at == 0) primitives_at = depth;
            primitives_key = false;
            if (shape.deepest > depth_limit) return shape;
        } else if ((c == ']' || c == '}') && depth > 0) {
            if (depth == primitives_at) primitives_at = 0;
            --depth;
        } else if (c != ':' && c != ' ' && c != '\n' && c != '\r' && c != '\t') {
            primitives_key = false;
        }
    }
    return shape;
}

/// Draco-compressed primitives (draco_decode.h).
constexpr const char* DRACO = "KHR_draco_mesh_compression";

/// Texture transforms (offset, rotation, scale), baked into the texture coordinates of the
/// meshes that use the material (one per material: its textures share the mesh's uvs).
constexpr const char* TEXTURE_TRANSFORM = "KHR_texture_transform";

/// A material's emissive factor multiplier (emissiveFactor stays within [0, 1]).
constexpr const char* EMISSIVE_STRENGTH = "KHR_materials_emissive_strength";

/// A material shown as its base colour, without lighting.
constexpr const char* UNLIT = "KHR_materials_unlit";

/// The extensions this importer reads: a file may require them, and they are not warned about.
bool is_read_extension(std::string_view name) {
    return name == DRACO || name == TEXTURE_TRANSFORM || name == EMISSIVE_STRENGTH ||
           name == UNLIT;
}

/// One texture reference of a glTF material, whichever its kind.
struct TextureRef {
    TextureSlot slot;
    const char* path;  ///< where the material holds it, for messages
    int index;
    int tex_coord;
    const tinygltf::ExtensionMap* extensions;
};

/// A 2x3 affine map of texture coordinates, row-major: u' = m[0] u + m[1] v + m[2], v' = ...
using UvTransform = std::array<float, 6>;

/// KHR_texture_transform's matrix, T * R * S as its specification writes it.
UvTransform uv_transform(double ox, double oy, double rotation, double sx, double sy) {
    const double c = std::cos(rotation), s = std::sin(rotation);
    return {float(c * sx), float(s * sy), float(ox), float(-s * sx), float(c * sy), float(oy)};
}

/// The JSON chunk of a .glb, for json_shape (the container is checked again by tinygltf).
std::string_view glb_json(std::span<const uint8_t> bytes) {
    if (bytes.size() < 20) return {};
    uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    if (length > bytes.size() - 20) return {};
    return {reinterpret_cast<const char*>(bytes.data()) + 20, length};
}

/// Where a Draco primitive's indices accessor goes before tinygltf reads the file: tinygltf 2.7
/// refuses an indices accessor without a buffer view, which is what a Draco primitive has.
constexpr const char* DRACO_INDICES = "strata_indices";

/// The document with each Draco primitive's "indices" moved into its extension object (as
/// DRACO_INDICES), or nullopt when there is nothing to move (or the JSON does not parse:
/// tinygltf says what is wrong with it).
std::optional<std::string> move_draco_indices(std::string_view json) {
    if (json.find(DRACO) == std::string_view::npos) return std::nullopt;
    nlohmann::json doc = nlohmann::json::parse(json, nullptr, false);
    if (doc.is_discarded() || !doc.is_object() || !doc.contains("meshes") ||
        !doc["meshes"].is_array())
        return std::nullopt;
    bool moved = false;
    for (nlohmann::json& mesh : doc["meshes"]) {
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
            continue;
        for (nlohmann::json& prim : mesh["primitives"]) {
            if (!prim.is_object() || !prim.contains("indices") || !prim.contains("extensions"))
                continue;
            nlohmann::json& ext = prim["extensions"];
            if (!ext.is_object() || !ext.contains(DRACO) || !ext[DRACO].is_object()) continue;
            ext[DRACO][DRACO_INDICES] = prim["indices"];
            prim.erase("indices");
            moved = true;
        }
    }
    if (!moved) return std::nullopt;
    return doc.dump();
}

/// `bytes` (a .glb when `binary`) with its JSON replaced by `json`.
std::string with_json(std::span<const uint8_t> bytes, bool binary, std::string json) {
    if (!binary) return json;
    // A .glb: 12-byte header, the JSON chunk (length, type, data padded to 4 bytes), the rest.
    const std::size_t old_chunk = 8 + glb_json(bytes).size();
    while (json.size() % 4 != 0) json.push_back(' ');
    std::string out(reinterpret_cast<const char*>(bytes.data()), 12);
    const auto put32 = [&out](std::size_t at, uint32_t v) { std::memcpy(out.data() + at, &v, 4); };
    const std::size_t rest = bytes.size() - 12 - old_chunk;
    out.resize(20);
    put32(12, uint32_t(json.size()));
    std::memcpy(out.data() + 16, bytes.data() + 16, 4);  // the chunk type, "JSON"
    out += json;
    out.append(reinterpret_cast<const char*>(bytes.data()) + 12 + old_chunk, rest);
    // The header's total length moves with the JSON only (glb_container_problem has checked it
    // against the file), so bytes past it stay past it, as tinygltf would have read them.
    uint32_t declared = 0;
    std::memcpy(&declared, bytes.data() + 8, 4);
    put32(8, uint32_t(int64_t(declared) + int64_t(json.size()) - int64_t(old_chunk - 8)));
    return out;
}

/// What is wrong with a .glb's container, or "" when its header and chunks fit in `bytes`.
/// tinygltf 2.7 checks the BIN chunk's length without its 8-byte chunk header, so a chunk that
/// claims up to 8 bytes more than the file holds would be read past its end: checked here first.
std::string glb_container_problem(std::span<const uint8_t> bytes) {
    const auto u32 = [&bytes](std::size_t at) {
        uint32_t v = 0;
        std::memcpy(&v, bytes.data() + at, 4);
        return uint64_t(v);
    };
    if (bytes.size() < 20) return "a .glb has a 12-byte header and a JSON chunk";
    if (std::memcmp(bytes.data(), "glTF", 4) != 0) return "a .glb starts with \"glTF\"";
    const uint64_t length = u32(8);
    if (length > bytes.size())
        return "its header says " + std::to_string(length) + " bytes; the file has " +
               std::to_string(bytes.size());
    const uint64_t json_end = 20 + u32(12);
    if (json_end > length) return "its JSON chunk runs past the length in its header";
    if (json_end == length) return {};
    if (json_end + 8 > length) return "a chunk after the JSON chunk has no chunk header";
    if (json_end + 8 + u32(json_end) > length)
        return "its BIN chunk of " + std::to_string(u32(json_end)) +
               " bytes runs past the length in its header";
    return {};
}

/// A checked view of one accessor's elements.
struct AccessorView {
    const uint8_t* base = nullptr;
    std::size_t stride = 0;
    std::size_t count = 0;
    int component = 0;  ///< TINYGLTF_COMPONENT_TYPE_*
    int width = 0;      ///< components per element
    bool normalized = false;

    /// Component `c` of element `i` as a float (normalized integers mapped to [0, 1]).
    float get(std::size_t i, int c) const {
        const uint8_t* p = base + i * stride;
        switch (component) {
            case TINYGLTF_COMPONENT_TYPE_FLOAT: {
                float v;
                std::memcpy(&v, p + 4 * c, 4);
                return v;
            }
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                return normalized ? p[c] / 255.0f : float(p[c]);
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                uint16_t v;
                std::memcpy(&v, p + 2 * c, 2);
                return normalized ? v / 65535.0f : float(v);
            }
            default:
                return 0.0f;
        }
    }
    /// Element `i` of a scalar integer accessor.
    uint32_t index(std::size_t i) const {
        const uint8_t* p = base + i * stride;
        switch (component) {
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
                return p[0];
            case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
                uint16_t v;
                std::memcpy(&v, p, 2);
                return v;
            }
            default: {
                uint32_t v;
                std::memcpy(&v, p, 4);
                return v;
            }
        }
    }
};

const char* mode_name(int mode) {
    switch (mode) {
        case TINYGLTF_MODE_POINTS:
            return "POINTS";
        case TINYGLTF_MODE_LINE:
            return "LINES";
        case TINYGLTF_MODE_LINE_LOOP:
            return "LINE_LOOP";
        case TINYGLTF_MODE_LINE_STRIP:
            return "LINE_STRIP";
        case TINYGLTF_MODE_TRIANGLE_STRIP:
            return "TRIANGLE_STRIP";
        case TINYGLTF_MODE_TRIANGLE_FAN:
            return "TRIANGLE_FAN";
        default:
            return "unknown";
    }
}

/// The primitive modes imported: triangles, points, and lines as linear curves (the strips and
/// fans of triangles are not).
bool imported_mode(int mode) {
    return mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_POINTS ||
           mode == TINYGLTF_MODE_LINE || mode == TINYGLTF_MODE_LINE_LOOP ||
           mode == TINYGLTF_MODE_LINE_STRIP;
}

/// The strands of a line primitive whose vertices, in index order, are `order` (indices into
/// its vertices; a loop's closing vertex is appended to it): LINES one 2-vertex strand per
/// line, LINE_STRIP one strand, LINE_LOOP one strand closed by repeating its first vertex.
/// Returns why the vertices make no lines, or "".
std::string line_strands(int mode, std::vector<uint32_t>& order, std::vector<uint32_t>& strands) {
    const std::size_t n = order.size();
    if (mode == TINYGLTF_MODE_LINE) {
        if (n == 0 || n % 2 != 0)
            return std::to_string(n) + " vertices do not make whole lines (2 each)";
        strands.assign(n / 2, 2);
        return {};
    }
    if (n < 2)
        return std::string(mode_name(mode)) + " of " + std::to_string(n) +
               " vertices: it needs 2 or more";
    if (mode == TINYGLTF_MODE_LINE_LOOP) order.push_back(order.front());
    strands = {uint32_t(order.size())};
    return {};
}

float unit(double v) {
    return float(std::clamp(v, 0.0, 1.0));
}

/// The texture coordinate sets a material's textures read (0 and 1), with each set's transform
/// (that of its first texture) and the set the normal texture reads.
struct MaterialUvs {
    std::array<bool, 2> reads = {};
    std::array<std::optional<UvTransform>, 2> transform = {};
    std::size_t normal_set = 0;
};

class GltfReader {
public:
    GltfReader(const tinygltf::Model& model, const ErrorSink& sink, const ImportLimits& limits)
        : m_model(model), m_sink(sink), m_limits(limits) {}

    Imported<Asset> read() {
        warn_unread_features();
        if (auto ok = read_materials(); !ok) return Unexpected(ok.error());
        if (auto ok = read_nodes(); !ok) return Unexpected(ok.error());
        if (auto ok = read_animation(); !ok) return Unexpected(ok.error());
        bake_texture_transforms();
        if (auto ok = check_budget(m_asset, m_limits, m_sink); !ok) return Unexpected(ok.error());
        if (auto ok = validate_asset(m_asset, m_sink); !ok) return Unexpected(ok.error());
        if (m_unlisted_warnings > 0)
            m_asset.warnings.push_back(std::to_string(m_unlisted_warnings) +
                                       " more warnings not listed");
        return std::move(m_asset);
    }

private:
    /// accessors[i], checked against its buffer view and buffer.
    Imported<AccessorView> accessor(int i, const std::string& use) {
        const std::string where = use + " (accessors[" + std::to_string(i) + "])";
        if (i < 0 || std::size_t(i) >= m_model.accessors.size())
            return m_sink.invalid(use, "accessor " + std::to_string(i) + " does not exist (" +
                                           std::to_string(m_model.accessors.size()) +
                                           " accessors)");
        const tinygltf::Accessor& a = m_model.accessors[std::size_t(i)];
        if (a.sparse.isSparse)
            return m_sink.unsupported(where, "sparse accessors are not supported");
        if (a.bufferView < 0 || std::size_t(a.bufferView) >= m_model.bufferViews.size())
            return m_sink.invalid(where,
                                  "bufferView " + std::to_string(a.bufferView) + " does not exist");
        const tinygltf::BufferView& view = m_model.bufferViews[std::size_t(a.bufferView)];
        if (view.buffer < 0 || std::size_t(view.buffer) >= m_model.buffers.size())
            return m_sink.invalid(where,
                                  "buffer " + std::to_string(view.buffer) + " does not exist");
        const std::vector<unsigned char>& data = m_model.buffers[std::size_t(view.buffer)].data;
        if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
            return m_sink.invalid(where, "its buffer view lies outside buffer " +
                                             std::to_string(view.buffer) + " (" +
                                             std::to_string(data.size()) + " bytes)");
        const int size = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        const int width = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (size <= 0 || width <= 0)
            return m_sink.invalid(where, "unknown component type or element type");
        const std::size_t element = std::size_t(size) * std::size_t(width);
        const std::size_t stride = view.byteStride ? view.byteStride : element;
        if (stride < element)
            return m_sink.invalid(
                where, "byteStride " + std::to_string(stride) + " is smaller than one element");
        AccessorView out;
        out.count = a.count;
        out.stride = stride;
        out.component = a.componentType;
        out.width = width;
        out.normalized = a.normalized;
        if (a.count == 0) return out;
        // Overflow-safe: offset + stride * (count - 1) + element <= byteLength.
        const std::size_t room = view.byteLength;
        if (a.byteOffset > room || element > room - a.byteOffset ||
            (a.count - 1) > (room - a.byteOffset - element) / stride)
            return m_sink.invalid(where, std::to_string(a.count) + " elements from byte " +
                                             std::to_string(a.byteOffset) +
                                             " run past its buffer view (" + std::to_string(room) +
                                             " bytes)");
        out.base = data.data() + view.byteOffset + a.byteOffset;
        return out;
    }

    Imported<void> read_materials() {
        for (std::size_t i = 0; i < m_model.materials.size(); ++i) {
            const tinygltf::Material& gm = m_model.materials[i];
            const std::string where = "materials[" + std::to_string(i) + "]";
            auto m = read_material(gm, where);
            if (!m) return Unexpected(m.error());
            m_asset.materials.push_back(std::move(m).value());
        }
        return {};
    }

    /// Material `gm`'s factors, modes and textures.
    Imported<AssetMaterial> read_material(const tinygltf::Material& gm, const std::string& where) {
        const auto& pbr = gm.pbrMetallicRoughness;
        AssetMaterial m;
        m.name = gm.name;
        for (double v : pbr.baseColorFactor)
            if (!std::isfinite(v)) return m_sink.invalid(where, "baseColorFactor is not finite");
        for (double v : gm.emissiveFactor)
            if (!std::isfinite(v)) return m_sink.invalid(where, "emissiveFactor is not finite");
        if (!std::isfinite(pbr.metallicFactor) || !std::isfinite(pbr.roughnessFactor) ||
            !std::isfinite(gm.alphaCutoff) || !std::isfinite(gm.normalTexture.scale) ||
            !std::isfinite(gm.occlusionTexture.strength))
            return m_sink.invalid(where, "metallicFactor, roughnessFactor, alphaCutoff, "
                                         "normalTexture.scale or occlusionTexture.strength is "
                                         "not finite");
        Material& out = m.material;
        if (pbr.baseColorFactor.size() >= 3)
            out.base_color = {unit(pbr.baseColorFactor[0]), unit(pbr.baseColorFactor[1]),
                              unit(pbr.baseColorFactor[2])};
        if (pbr.baseColorFactor.size() >= 4) out.alpha = unit(pbr.baseColorFactor[3]);
        out.metallic = unit(pbr.metallicFactor);
        out.roughness = unit(pbr.roughnessFactor);
        if (gm.emissiveFactor.size() >= 3) {
            auto strength = read_emissive_strength(gm, where);
            if (!strength) return Unexpected(strength.error());
            out.emission = strength.value() * Vec3(unit(gm.emissiveFactor[0]),
                                                   unit(gm.emissiveFactor[1]),
                                                   unit(gm.emissiveFactor[2]));
        }
        if (gm.alphaMode == "MASK") {
            out.alpha_mode = AlphaMode::Mask;
        } else if (gm.alphaMode == "BLEND") {
            out.alpha_mode = AlphaMode::Blend;
        } else if (!gm.alphaMode.empty() && gm.alphaMode != "OPAQUE") {
            return m_sink.invalid(where, "alphaMode '" + gm.alphaMode.substr(0, 64) +
                                             "' is none of OPAQUE, MASK and BLEND");
        }
        out.alpha_cutoff = unit(gm.alphaCutoff);
        out.normal_scale = float(std::clamp(gm.normalTexture.scale, -100.0, 100.0));
        out.occlusion_strength = unit(gm.occlusionTexture.strength);
        out.unlit = gm.extensions.count(UNLIT) != 0;
        warn_unread_material(gm, where);
        if (auto ok = read_material_textures(gm, where, m); !ok) return Unexpected(ok.error());
        return m;
    }

    /// Material `gm`'s textures into `m`, each slot with its texture coordinate set (0 or 1; a
    /// higher one reads set 0, with a warning). The first texture's sampler becomes the
    /// material's; each set's first KHR_texture_transform is baked into that set's coordinates
    /// (bake_texture_transforms), and another texture that transforms the same set otherwise
    /// is named in a warning.
    Imported<void> read_material_textures(const tinygltf::Material& gm, const std::string& where,
                                          AssetMaterial& m) {
        const auto& pbr = gm.pbrMetallicRoughness;
        const TextureRef refs[] = {
            {TextureSlot::BaseColor, "pbrMetallicRoughness.baseColorTexture",
             pbr.baseColorTexture.index, pbr.baseColorTexture.texCoord,
             &pbr.baseColorTexture.extensions},
            {TextureSlot::MetallicRoughness, "pbrMetallicRoughness.metallicRoughnessTexture",
             pbr.metallicRoughnessTexture.index, pbr.metallicRoughnessTexture.texCoord,
             &pbr.metallicRoughnessTexture.extensions},
            {TextureSlot::Normal, "normalTexture", gm.normalTexture.index,
             gm.normalTexture.texCoord, &gm.normalTexture.extensions},
            {TextureSlot::Occlusion, "occlusionTexture", gm.occlusionTexture.index,
             gm.occlusionTexture.texCoord, &gm.occlusionTexture.extensions},
            {TextureSlot::Emissive, "emissiveTexture", gm.emissiveTexture.index,
             gm.emissiveTexture.texCoord, &gm.emissiveTexture.extensions},
        };
        bool mapped = false;
        MaterialUvs& uvs = m_material_uvs.emplace_back();
        for (const TextureRef& ref : refs) {
            if (ref.index < 0) continue;
            const std::string at = where + "." + ref.path;
            const TextureSlotInfo& info = TEXTURE_SLOTS[slot_index(ref.slot)];
            auto t = read_texture(ref.index, at, info.space);
            if (!t) return Unexpected(t.error());
            int tex_coord = ref.tex_coord;
            auto transform = read_texture_transform(*ref.extensions, at, tex_coord);
            if (!transform) return Unexpected(transform.error());
            for (const auto& [name, value] : *ref.extensions)
                if (name != TEXTURE_TRANSFORM)
                    warn_once(at + ".extensions." + name + " not imported");
            if (!mapped) {
                mapped = true;
                m.material.base_color_sampler = read_sampler(ref.index);
            } else if (!(read_sampler(ref.index) == m.material.base_color_sampler)) {
                warn_once(at + "'s sampler (wrap or filter) differs from the material's first "
                               "texture's: the scene reads all of a material's textures through "
                               "that one");
            }
            if (tex_coord > 1) {
                warn_once(at + " reads TEXCOORD_" + std::to_string(tex_coord) +
                          ": sets 0 and 1 are imported, and it reads TEXCOORD_0");
                tex_coord = 0;
            }
            const std::size_t set = std::size_t(tex_coord);
            if (!uvs.reads[set]) {
                uvs.reads[set] = true;
                uvs.transform[set] = transform.value();
            } else if (transform.value() != uvs.transform[set]) {
                warn_once(at + " transforms TEXCOORD_" + std::to_string(set) +
                          " otherwise (KHR_texture_transform) than the material's first texture "
                          "that reads it: it is read through the first one's");
            }
            if (ref.slot == TextureSlot::Normal) uvs.normal_set = set;
            m.material.*(info.uv_set) = uint32_t(set);
            m.texture(ref.slot) = t.value();
        }
        return {};
    }

    /// KHR_materials_emissive_strength's emissiveStrength (1 without it): a finite number >= 0.
    Imported<float> read_emissive_strength(const tinygltf::Material& gm, const std::string& where) {
        const auto it = gm.extensions.find(EMISSIVE_STRENGTH);
        if (it == gm.extensions.end() || !it->second.Has("emissiveStrength")) return 1.0f;
        const tinygltf::Value& v = it->second.Get("emissiveStrength");
        const double strength = v.IsNumber() ? v.GetNumberAsDouble() : -1.0;
        if (!std::isfinite(strength) || strength < 0.0 || strength > 1e6)
            return m_sink.invalid(where + ".extensions." + EMISSIVE_STRENGTH,
                                  "emissiveStrength must be a number from 0 to 1e6");
        return float(strength);
    }

    /// A texture's KHR_texture_transform, if it has one: offset, rotation and scale (their
    /// defaults when absent); its texCoord replaces `tex_coord`.
    Imported<std::optional<UvTransform>> read_texture_transform(
        const tinygltf::ExtensionMap& extensions, const std::string& where, int& tex_coord) {
        const auto it = extensions.find(TEXTURE_TRANSFORM);
        if (it == extensions.end()) return std::optional<UvTransform>();
        const tinygltf::Value& t = it->second;
        const std::string at = where + ".extensions." + TEXTURE_TRANSFORM;
        if (!t.IsObject()) return m_sink.invalid(at, "is not an object");
        const auto number = [&](const tinygltf::Value& v, double& out) {
            if (!v.IsNumber()) return false;
            out = v.GetNumberAsDouble();
            return std::isfinite(out) && std::abs(out) < 1e6;
        };
        const auto pair = [&](const char* key, double& a, double& b) {
            if (!t.Has(key)) return true;
            const tinygltf::Value& v = t.Get(key);
            return v.IsArray() && v.ArrayLen() == 2 && number(v.Get(0), a) && number(v.Get(1), b);
        };
        double ox = 0, oy = 0, sx = 1, sy = 1, rotation = 0;
        if (!pair("offset", ox, oy) || !pair("scale", sx, sy) ||
            (t.Has("rotation") && !number(t.Get("rotation"), rotation)))
            return m_sink.invalid(at, "offset and scale must be two finite numbers each, and "
                                      "rotation a finite number");
        if (t.Has("texCoord")) {
            if (!t.Get("texCoord").IsInt() || t.Get("texCoord").GetNumberAsInt() < 0)
                return m_sink.invalid(at, "texCoord must be a whole number >= 0");
            tex_coord = t.Get("texCoord").GetNumberAsInt();
        }
        return std::optional(uv_transform(ox, oy, rotation, sx, sy));
    }

    /// Each mesh's texture coordinates through its material's texture transforms, one per set.
    void bake_texture_transforms() {
        for (AssetMesh& mesh : m_asset.meshes) {
            const MaterialUvs* uvs = material_uvs(mesh.material);
            if (!uvs) continue;
            for (std::size_t set = 0; set < 2; ++set) {
                const std::optional<UvTransform>& m = uvs->transform[set];
                if (!m) continue;
                for (glm::vec2& uv : set == 0 ? mesh.uvs : mesh.uvs1)
                    uv = {(*m)[0] * uv.x + (*m)[1] * uv.y + (*m)[2],
                          (*m)[3] * uv.x + (*m)[4] * uv.y + (*m)[5]};
                // A rotation or mirror turns the directions in which u and v grow: the file's
                // tangents no longer follow them, and the server makes them from the new uvs.
                const bool turns = (*m)[1] != 0.0f || (*m)[3] != 0.0f || (*m)[0] < 0.0f ||
                                   (*m)[4] < 0.0f;
                if (turns && set == uvs->normal_set) mesh.tangents.clear();
            }
        }
    }

    /// What material `i`'s textures read, or null (no such material, or one without textures).
    const MaterialUvs* material_uvs(int i) const {
        return i >= 0 && std::size_t(i) < m_material_uvs.size() ? &m_material_uvs[std::size_t(i)]
                                                                : nullptr;
    }

    /// textures[i]'s sampler (i is a valid index) as the engine's: one wrap mode for both axes
    /// (wrapS's; a different wrapT is named in a warning) and the magnification filter.
    TextureSampler read_sampler(int i) {
        TextureSampler out;
        const int s = m_model.textures[std::size_t(i)].sampler;
        if (s < 0 || std::size_t(s) >= m_model.samplers.size()) return out;  // glTF: repeat, linear
        const tinygltf::Sampler& sampler = m_model.samplers[std::size_t(s)];
        auto wrap = [](int mode) {
            return mode == TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE     ? TextureWrap::Clamp
                   : mode == TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT ? TextureWrap::Mirror
                                                                   : TextureWrap::Repeat;
        };
        out.wrap = wrap(sampler.wrapS);
        if (wrap(sampler.wrapT) != out.wrap)
            warn_once("samplers[" + std::to_string(s) +
                      "]: wrapS and wrapT differ; both axes use wrapS");
        if (sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST)
            out.filter = TextureFilter::Nearest;
        return out;
    }

    /// textures[i]'s image as an asset texture (each image once).
    Imported<int> read_texture(int i, const std::string& use, TextureColorSpace space) {
        if (std::size_t(i) >= m_model.textures.size())
            return m_sink.invalid(use, "texture " + std::to_string(i) + " does not exist");
        const int source = m_model.textures[std::size_t(i)].source;
        if (source < 0 || std::size_t(source) >= m_model.images.size())
            return m_sink.invalid("textures[" + std::to_string(i) + "]",
                                  "image " + std::to_string(source) + " does not exist");
        // An image is one texture per colour space it is read in (a file may use one image as
        // colour and as data).
        if (auto it = m_images.find({source, space}); it != m_images.end()) return it->second;
        const tinygltf::Image& image = m_model.images[std::size_t(source)];
        // Images that share a buffer view share one texture: a file naming one view from many
        // images must not multiply its bytes.
        if (auto it = m_views.find({image.bufferView, space});
            image.bufferView >= 0 && it != m_views.end()) {
            m_images.emplace(std::pair(source, space), it->second);
            return it->second;
        }
        AssetTexture t;
        t.name = image.name;
        t.mime_type = image.mimeType;
        t.uri = image.uri;
        t.color_space = space;
        if (image.bufferView >= 0) {
            const std::string at = "images[" + std::to_string(source) + "]";
            if (std::size_t(image.bufferView) >= m_model.bufferViews.size())
                return m_sink.invalid(
                    at, "bufferView " + std::to_string(image.bufferView) + " does not exist");
            const tinygltf::BufferView& view = m_model.bufferViews[std::size_t(image.bufferView)];
            if (view.buffer < 0 || std::size_t(view.buffer) >= m_model.buffers.size())
                return m_sink.invalid(at, "its buffer view names no buffer");
            const std::vector<unsigned char>& data = m_model.buffers[std::size_t(view.buffer)].data;
            if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
                return m_sink.invalid(at, "its buffer view lies outside its buffer");
            const auto begin = data.begin() + std::ptrdiff_t(view.byteOffset);
            t.bytes.assign(begin, begin + std::ptrdiff_t(view.byteLength));
        } else if (!image.image.empty()) {
            t.bytes.assign(image.image.begin(), image.image.end());
        }
        const int index = int(m_asset.textures.size());
        m_asset.textures.push_back(std::move(t));
        m_images.emplace(std::pair(source, space), index);
        if (image.bufferView >= 0) m_views.emplace(std::pair(image.bufferView, space), index);
        return index;
    }

    /// The asset meshes of glTF mesh `i`, one per primitive, read once.
    Imported<std::vector<int>> read_mesh(int i) {
        if (auto it = m_meshes.find(i); it != m_meshes.end()) return it->second;
        if (i < 0 || std::size_t(i) >= m_model.meshes.size())
            return m_sink.invalid("meshes", "mesh " + std::to_string(i) + " does not exist (" +
                                                std::to_string(m_model.meshes.size()) + " meshes)");
        const tinygltf::Mesh& gm = m_model.meshes[std::size_t(i)];
        std::vector<int> out;
        for (std::size_t p = 0; p < gm.primitives.size(); ++p) {
            const std::string where =
                "meshes[" + std::to_string(i) + "].primitives[" + std::to_string(p) + "]";
            auto mesh = read_primitive(gm.primitives[p], where);
            if (!mesh) return Unexpected(mesh.error());
            mesh.value().name = gm.name;
            out.push_back(int(m_asset.meshes.size()));
            m_asset.meshes.push_back(std::move(mesh.value()));
        }
        if (out.empty())
            return m_sink.invalid("meshes[" + std::to_string(i) + "]", "has no primitives");
        m_meshes.emplace(i, out);
        return out;
    }

    Imported<AssetMesh> read_primitive(const tinygltf::Primitive& prim, const std::string& where) {
        const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
        if (!imported_mode(mode))
            return m_sink.unsupported(where, std::string("mode ") + std::to_string(mode) + " (" +
                                                 mode_name(mode) +
                                                 ") is not supported; only triangles (4), "
                                                 "points (0) and lines (1, 2, 3)");
        if (!prim.targets.empty()) warn_once("morph targets ignored (the base shape is kept)");
        AssetMesh mesh;
        mesh.material = prim.material;
        if (prim.material >= int(m_model.materials.size()))
            return m_sink.invalid(where,
                                  "material " + std::to_string(prim.material) + " does not exist");
        if (const auto draco = prim.extensions.find(DRACO); draco != prim.extensions.end()) {
            if (mode != TINYGLTF_MODE_TRIANGLES)
                return m_sink.unsupported(where + ".extensions." + DRACO,
                                          "Draco-compressed points and lines are not imported");
            return read_draco_primitive(prim, draco->second, where, std::move(mesh));
        }
        // Step 1: positions, against the budget left before allocating.
        const auto pos_it = prim.attributes.find("POSITION");
        if (pos_it == prim.attributes.end())
            return m_sink.invalid(where, "has no POSITION attribute");
        auto pos = accessor(pos_it->second, where + ".attributes.POSITION");
        if (!pos) return Unexpected(pos.error());
        const AccessorView& pv = pos.value();
        if (pv.component != TINYGLTF_COMPONENT_TYPE_FLOAT || pv.width != 3)
            return m_sink.unsupported(where + ".attributes.POSITION",
                                      "positions must be float VEC3");
        if (pv.count == 0) return m_sink.invalid(where + ".attributes.POSITION", "has no vertices");
        if (mode != TINYGLTF_MODE_TRIANGLES)
            return read_points_or_lines(prim, mode, pv, where, std::move(mesh));
        if (auto ok = charge_vertices(pv.count, where); !ok) return Unexpected(ok.error());
        mesh.positions.resize(pv.count);
        for (std::size_t v = 0; v < pv.count; ++v)
            mesh.positions[v] = {pv.get(v, 0), pv.get(v, 1), pv.get(v, 2)};
        // Step 2: triangles, every index checked.
        if (auto ok = read_triangles(prim, where, pv.count, mesh); !ok)
            return Unexpected(ok.error());
        // Step 3: optional attributes, one per vertex.
        if (auto ok = read_attribute(prim, "NORMAL", where, pv.count, 3, mesh); !ok)
            return Unexpected(ok.error());
        if (auto ok = read_attribute(prim, "TEXCOORD_0", where, pv.count, 2, mesh); !ok)
            return Unexpected(ok.error());
        if (reads_second_set(prim, where)) {
            if (auto ok = read_attribute(prim, "TEXCOORD_1", where, pv.count, 2, mesh); !ok)
                return Unexpected(ok.error());
        }
        if (auto ok = read_attribute(prim, "COLOR_0", where, pv.count, 3, mesh); !ok)
            return Unexpected(ok.error());
        if (auto ok = read_attribute(prim, "TANGENT", where, pv.count, 4, mesh); !ok)
            return Unexpected(ok.error());
        return mesh;
    }

    /// Whether the primitive's material reads TEXCOORD_1 and the primitive has it (when it
    /// lacks it, a warning says the textures read TEXCOORD_0).
    bool reads_second_set(const tinygltf::Primitive& prim, const std::string& where) {
        const MaterialUvs* uvs = material_uvs(prim.material);
        if (!uvs || !uvs->reads[1]) return false;
        if (prim.attributes.count("TEXCOORD_1") != 0) return true;
        warn_once(where + ": its material's textures read TEXCOORD_1, which it lacks; they read "
                          "TEXCOORD_0");
        return false;
    }

    /// The primitive's indices accessor (it has one), unsigned SCALAR.
    Imported<AccessorView> index_accessor(const tinygltf::Primitive& prim,
                                          const std::string& where) {
        auto idx = accessor(prim.indices, where + ".indices");
        if (!idx) return Unexpected(idx.error());
        const AccessorView& iv = idx.value();
        if (iv.width != 1 || (iv.component != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                              iv.component != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                              iv.component != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
            return m_sink.invalid(where + ".indices", "indices must be unsigned SCALAR");
        return idx;
    }

    /// Index `at` of the primitive (`iv`: its indices, or none: the vertices in order), checked
    /// against its `vertices`.
    Imported<uint32_t> vertex_at(const tinygltf::Primitive& prim, const AccessorView& iv,
                                 std::size_t at, std::size_t vertices, const std::string& where) {
        const uint32_t v = prim.indices >= 0 ? iv.index(at) : uint32_t(at);
        if (v >= vertices)
            return m_sink.invalid(where + ".indices", "index " + std::to_string(at) + " is " +
                                                          std::to_string(v) + ", outside the " +
                                                          std::to_string(vertices) + " vertices");
        return v;
    }

    /// The primitive's triangles (its indices, or its vertices in order), every index checked,
    /// against the budget left.
    Imported<void> read_triangles(const tinygltf::Primitive& prim, const std::string& where,
                                  std::size_t vertices, AssetMesh& mesh) {
        std::size_t n_indices = vertices;
        AccessorView iv;
        if (prim.indices >= 0) {
            auto idx = index_accessor(prim, where);
            if (!idx) return Unexpected(idx.error());
            iv = idx.value();
            n_indices = iv.count;
        }
        if (auto ok = charge_triangles(n_indices, where); !ok) return Unexpected(ok.error());
        mesh.triangles.resize(n_indices / 3);
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
            for (int k = 0; k < 3; ++k) {
                auto v = vertex_at(prim, iv, 3 * t + std::size_t(k), vertices, where);
                if (!v) return Unexpected(v.error());
                mesh.triangles[t][k] = v.value();
            }
        }
        return {};
    }

    /// A POINTS, LINES, LINE_STRIP or LINE_LOOP primitive (`pv`: its positions) as a points or
    /// linear curve mesh: its vertices in index order (each line with copies of its own), each
    /// with the default radius (asset.h; glTF gives points no size and lines no width). COLOR_0
    /// is read; NORMAL, TEXCOORD_n and TANGENT are dropped with a warning.
    Imported<AssetMesh> read_points_or_lines(const tinygltf::Primitive& prim, int mode,
                                             const AccessorView& pv, const std::string& where,
                                             AssetMesh mesh) {
        // Step 1: which vertices, in which order, and the strands they make.
        auto read = read_order(prim, where, pv.count, mode == TINYGLTF_MODE_LINE_LOOP);
        if (!read) return Unexpected(read.error());
        std::vector<uint32_t>& order = read.value();
        const bool points = mode == TINYGLTF_MODE_POINTS;
        mesh.kind = points ? MeshKind::Points : MeshKind::Curves;
        if (points && order.empty()) return m_sink.invalid(where + ".indices", "has no indices");
        if (!points) {
            if (const std::string why = line_strands(mode, order, mesh.strands); !why.empty())
                return m_sink.invalid(where, why);
        }
        // Step 2: positions and colours in that order.
        mesh.positions.resize(order.size());
        for (std::size_t i = 0; i < order.size(); ++i)
            mesh.positions[i] = {pv.get(order[i], 0), pv.get(order[i], 1), pv.get(order[i], 2)};
        AssetMesh source;
        if (auto ok = read_attribute(prim, "COLOR_0", where, pv.count, 3, source); !ok)
            return Unexpected(ok.error());
        for (std::size_t i = 0; i < order.size() && !source.colors.empty(); ++i)
            mesh.colors.push_back(source.colors[order[i]]);
        // Step 3: the radii, and what points and curves cannot carry.
        const float r =
            points ? default_point_radius(mesh.positions) : default_line_radius(mesh.positions);
        mesh.radii.assign(order.size(), r);
        warn_once(where + ": " + mode_name(mode) +
                  (points ? " have no size in glTF: each point has radius " + radius_text(r) +
                                " (0.5 * D / sqrt(N), D the diagonal of their bounds)"
                          : " have no width in glTF: their radius is " + radius_text(r) +
                                " (0.002 * D, D the diagonal of their bounds)"));
        warn_surface_attributes(prim, where);
        return mesh;
    }

    /// The vertices a point or line primitive draws, in order: its indices (each checked) or
    /// all its `vertices`; counted against the budget (with a loop's closing vertex) first.
    Imported<std::vector<uint32_t>> read_order(const tinygltf::Primitive& prim,
                                               const std::string& where, std::size_t vertices,
                                               bool loop) {
        std::size_t n = vertices;
        AccessorView iv;
        if (prim.indices >= 0) {
            auto idx = index_accessor(prim, where);
            if (!idx) return Unexpected(idx.error());
            iv = idx.value();
            n = iv.count;
        }
        if (auto ok = charge_vertices(n + (loop ? 1 : 0), where); !ok)
            return Unexpected(ok.error());
        if (auto ok = charge_mesh(0, where); !ok) return Unexpected(ok.error());
        std::vector<uint32_t> order(n);
        for (std::size_t i = 0; i < n; ++i) {
            auto v = vertex_at(prim, iv, i, vertices, where);
            if (!v) return Unexpected(v.error());
            order[i] = v.value();
        }
        return order;
    }

    /// Names the attributes of a point or line primitive that points and curves cannot carry.
    void warn_surface_attributes(const tinygltf::Primitive& prim, const std::string& where) {
        std::string names;
        for (const auto& [name, index] : prim.attributes)
            if (name == "NORMAL" || name == "TANGENT" || name.starts_with("TEXCOORD_"))
                names += (names.empty() ? "" : ", ") + name.substr(0, 32);
        if (!names.empty())
            warn_once(where + ": " + names +
                      " dropped: points and curves carry no normals, texture coordinates or "
                      "tangents");
    }

    /// Counts a primitive's vertices against the budget before they are allocated.
    Imported<void> charge_vertices(std::size_t count, const std::string& where) {
        m_vertices += count;
        if (m_vertices > m_limits.max_vertices)
            return m_sink.too_large(
                where, "the asset holds at least " + std::to_string(m_vertices) +
                           " vertices; the scene has room for " +
                           std::to_string(m_limits.max_vertices) + " (max_scene_vertices)");
        return {};
    }

    /// Checks that `n_indices` make whole triangles and counts them against the budget.
    Imported<void> charge_triangles(std::size_t n_indices, const std::string& where) {
        if (n_indices % 3 != 0 || n_indices == 0)
            return m_sink.invalid(
                where, std::to_string(n_indices) + " indices do not make whole triangles");
        return charge_mesh(n_indices / 3, where);
    }

    /// Counts a primitive's mesh of `triangles` triangles (none for points and curves) against
    /// the budget.
    Imported<void> charge_mesh(std::size_t triangles, const std::string& where) {
        // Each primitive becomes a mesh, which also costs MESH_OVERHEAD_TRIANGLES (budget.h).
        m_triangles += triangles + MESH_OVERHEAD_TRIANGLES;
        if (m_triangles > m_limits.max_triangles)
            return m_sink.too_large(
                where, "the asset holds at least " + std::to_string(m_triangles) +
                           " triangles, each mesh counted with " +
                           std::to_string(MESH_OVERHEAD_TRIANGLES) +
                           " more; the scene has room for " +
                           std::to_string(m_limits.max_triangles) + " (max_scene_triangles)");
        return {};
    }

    /// accessors[i] as a Draco primitive declares it: no buffer view, only its type and count.
    Imported<const tinygltf::Accessor*> declared(int i, const std::string& use) {
        if (i < 0 || std::size_t(i) >= m_model.accessors.size())
            return m_sink.invalid(use, "accessor " + std::to_string(i) + " does not exist (" +
                                           std::to_string(m_model.accessors.size()) +
                                           " accessors)");
        return &m_model.accessors[std::size_t(i)];
    }

    /// A KHR_draco_mesh_compression primitive: the counts its accessors declare go against the
    /// budget first, then its buffer view is decoded (draco_decode.h) and must match them.
    Imported<AssetMesh> read_draco_primitive(const tinygltf::Primitive& prim,
                                             const tinygltf::Value& ext, const std::string& where,
                                             AssetMesh mesh) {
        const std::string at = where + ".extensions." + DRACO;
        const tinygltf::Value& view_index = ext.Get("bufferView");
        const tinygltf::Value& ids = ext.Get("attributes");
        if (!ext.IsObject() || !view_index.IsInt() || !ids.IsObject())
            return m_sink.invalid(at, "needs an integer bufferView and an attributes object");
        // Step 1: the declared counts, against the budget.
        const auto pos_it = prim.attributes.find("POSITION");
        if (pos_it == prim.attributes.end())
            return m_sink.invalid(where, "has no POSITION attribute");
        auto pos = declared(pos_it->second, where + ".attributes.POSITION");
        if (!pos) return Unexpected(pos.error());
        if (pos.value()->componentType != TINYGLTF_COMPONENT_TYPE_FLOAT ||
            pos.value()->type != TINYGLTF_TYPE_VEC3)
            return m_sink.unsupported(where + ".attributes.POSITION",
                                      "positions must be float VEC3");
        const std::size_t vertices = pos.value()->count;
        if (vertices == 0) return m_sink.invalid(where + ".attributes.POSITION", "has no vertices");
        // The indices accessor was moved into the extension object (move_draco_indices).
        const tinygltf::Value& indices = ext.Get(DRACO_INDICES);
        if (!indices.IsInt()) return m_sink.invalid(where, "a Draco primitive needs indices");
        auto idx = declared(indices.Get<int>(), where + ".indices");
        if (!idx) return Unexpected(idx.error());
        if (idx.value()->type != TINYGLTF_TYPE_SCALAR)
            return m_sink.invalid(where + ".indices", "indices must be SCALAR");
        if (auto ok = charge_vertices(vertices, where); !ok) return Unexpected(ok.error());
        if (auto ok = charge_triangles(idx.value()->count, where); !ok)
            return Unexpected(ok.error());
        // Step 2: which Draco attribute holds each glTF attribute the importer reads.
        DracoAttributeIds draco;
        for (auto [name, id] :
             {std::pair{"POSITION", &draco.position}, std::pair{"NORMAL", &draco.normal},
              std::pair{"TEXCOORD_0", &draco.texcoord}, std::pair{"TEXCOORD_1", &draco.texcoord1},
              std::pair{"COLOR_0", &draco.color}, std::pair{"TANGENT", &draco.tangent}}) {
            if (prim.attributes.find(name) == prim.attributes.end()) continue;
            if (id == &draco.texcoord1 && !reads_second_set(prim, at)) continue;
            const tinygltf::Value& v = ids.Get(name);
            if (!v.IsInt() || v.Get<int>() < 0)
                return m_sink.invalid(at + ".attributes",
                                      std::string(name) + " has no Draco attribute id");
            *id = v.Get<int>();
        }
        // Step 3: the compressed bytes, then the decoded mesh.
        const int vi = view_index.Get<int>();
        if (vi < 0 || std::size_t(vi) >= m_model.bufferViews.size())
            return m_sink.invalid(at, "bufferView " + std::to_string(vi) + " does not exist");
        const tinygltf::BufferView& view = m_model.bufferViews[std::size_t(vi)];
        if (view.buffer < 0 || std::size_t(view.buffer) >= m_model.buffers.size())
            return m_sink.invalid(at, "its buffer view names no buffer");
        const std::vector<unsigned char>& data = m_model.buffers[std::size_t(view.buffer)].data;
        if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
            return m_sink.invalid(at, "its buffer view lies outside its buffer");
        const std::span<const uint8_t> bytes(data.data() + view.byteOffset, view.byteLength);
        const std::string error =
            decode_draco_mesh(bytes, draco, {vertices, idx.value()->count}, mesh);
        if (!error.empty()) return m_sink.invalid(at, error);
        return mesh;
    }

    Imported<void> read_attribute(const tinygltf::Primitive& prim, const char* name,
                                  const std::string& where, std::size_t vertices, int width,
                                  AssetMesh& mesh) {
        const auto it = prim.attributes.find(name);
        if (it == prim.attributes.end()) return {};
        const std::string use = where + ".attributes." + name;
        auto acc = accessor(it->second, use);
        if (!acc) return Unexpected(acc.error());
        const AccessorView& a = acc.value();
        const bool is_color = width == 3 && std::string_view(name) == "COLOR_0";
        const bool ok_width = a.width == width || (is_color && a.width == 4);
        // Normals are float; uvs and colours may also be normalized unsigned bytes or shorts.
        const bool small_int = a.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ||
                               a.component == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
        // Tangents are float VEC4 (w: the bitangent's sign).
        const bool ok_type = a.component == TINYGLTF_COMPONENT_TYPE_FLOAT ||
                             ((width == 2 || is_color) && small_int && a.normalized);
        if (!ok_width || !ok_type)
            return m_sink.invalid(use, "unexpected element or component type");
        if (a.count != vertices)
            return m_sink.invalid(use, std::to_string(a.count) + " elements for " +
                                           std::to_string(vertices) + " vertices");
        for (std::size_t v = 0; v < vertices; ++v) {
            if (width == 2) {
                std::vector<glm::vec2>& uvs =
                    std::string_view(name) == "TEXCOORD_1" ? mesh.uvs1 : mesh.uvs;
                uvs.push_back({a.get(v, 0), a.get(v, 1)});
                if (!std::isfinite(uvs.back().x) || !std::isfinite(uvs.back().y))
                    return m_sink.invalid(use, "element " + std::to_string(v) + " is not finite");
                continue;
            }
            if (width == 4) {
                const Vec4 t{a.get(v, 0), a.get(v, 1), a.get(v, 2), a.get(v, 3)};
                if (!is_finite(t))
                    return m_sink.invalid(use, "element " + std::to_string(v) + " is not finite");
                mesh.tangents.push_back(t);
                continue;
            }
            const Vec3 value{a.get(v, 0), a.get(v, 1), a.get(v, 2)};
            if (!is_finite(value))
                return m_sink.invalid(use, "element " + std::to_string(v) + " is not finite");
            if (is_color)
                mesh.colors.push_back(glm::clamp(value, Vec3(0.0f), Vec3(1.0f)));
            else
                mesh.normals.push_back(value);
        }
        return {};
    }

    /// nodes[i]'s local transform: a column-major matrix or translation, rotation, scale.
    Imported<Affine> local_transform(const tinygltf::Node& n, const std::string& where) {
        Affine out;
        if (n.matrix.size() == 16) {
            for (double v : n.matrix)
                if (!std::isfinite(v)) return m_sink.invalid(where, "matrix is not finite");
            if (std::abs(n.matrix[3]) > 1e-6 || std::abs(n.matrix[7]) > 1e-6 ||
                std::abs(n.matrix[11]) > 1e-6 || std::abs(n.matrix[15] - 1.0) > 1e-6)
                return m_sink.invalid(where, "matrix is not affine (last row is not 0 0 0 1)");
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 4; ++c) out.at(r, c) = float(n.matrix[std::size_t(c * 4 + r)]);
            return out;
        }
        if (!n.matrix.empty()) return m_sink.invalid(where, "matrix must have 16 numbers");
        Vec3 t(0.0f), s(1.0f);
        Vec4 q(0.0f, 0.0f, 0.0f, 1.0f);
        if (n.translation.size() == 3) t = {n.translation[0], n.translation[1], n.translation[2]};
        if (n.scale.size() == 3) s = {n.scale[0], n.scale[1], n.scale[2]};
        if (n.rotation.size() == 4)
            q = {n.rotation[0], n.rotation[1], n.rotation[2], n.rotation[3]};
        if (!is_finite(t) || !is_finite(s) || !std::isfinite(q.x) || !std::isfinite(q.y) ||
            !std::isfinite(q.z) || !std::isfinite(q.w))
            return m_sink.invalid(where, "translation, rotation or scale is not finite");
        if (glm::length(q) < 1e-6f) return m_sink.invalid(where, "rotation is a zero quaternion");
        return Affine::trs(t, Affine::rotation_quaternion(q), s);
    }

    /// The scene's node trees, parents first; each node reached once (cycles and shared
    /// children are refused).
    Imported<void> read_nodes() {
        const std::size_t count = m_model.nodes.size();
        if (count > m_limits.max_nodes)
            return m_sink.too_large("nodes", std::to_string(count) + " nodes; at most " +
                                                 std::to_string(m_limits.max_nodes));
        // Step 1: the roots: the default scene's, else the first scene's, else every node no
        // other node lists as a child; with no nodes at all, every mesh at the origin.
        std::vector<int> roots;
        if (!m_model.scenes.empty()) {
            const int s = m_model.defaultScene >= 0 ? m_model.defaultScene : 0;
            if (std::size_t(s) >= m_model.scenes.size())
                return m_sink.invalid("scene", "scene " + std::to_string(s) + " does not exist");
            roots = m_model.scenes[std::size_t(s)].nodes;
        } else {
            std::vector<bool> is_child(count, false);
            for (const tinygltf::Node& n : m_model.nodes)
                for (int c : n.children)
                    if (c >= 0 && std::size_t(c) < count) is_child[std::size_t(c)] = true;
            for (std::size_t i = 0; i < count; ++i)
                if (!is_child[i]) roots.push_back(int(i));
        }
        if (count == 0) {
            for (std::size_t i = 0; i < m_model.meshes.size(); ++i) {
                auto meshes = read_mesh(int(i));
                if (!meshes) return Unexpected(meshes.error());
                AssetNode node;
                node.name = m_model.meshes[i].name;
                node.meshes = meshes.value();
                m_asset.nodes.push_back(std::move(node));
            }
            return {};
        }
        // Step 2: depth first with an explicit stack (a deep chain must not overflow ours).
        m_asset_node.assign(count, -1);
        std::vector<bool> seen(count, false);
        std::vector<std::pair<int, int>> stack;  // (glTF node, parent asset node)
        for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, -1);
        while (!stack.empty()) {
            const auto [g, parent] = stack.back();
            stack.pop_back();
            if (g < 0 || std::size_t(g) >= count)
                return m_sink.invalid(parent < 0 ? "scenes" : "nodes",
                                      "node " + std::to_string(g) + " does not exist (" +
                                          std::to_string(count) + " nodes)");
            const std::string where = "nodes[" + std::to_string(g) + "]";
            if (seen[std::size_t(g)])
                return m_sink.invalid(where,
                                      "is reached twice (a cycle, or a node with two "
                                      "parents)");
            seen[std::size_t(g)] = true;
            const tinygltf::Node& n = m_model.nodes[std::size_t(g)];
            AssetNode node;
            node.name = n.name;
            node.parent = parent;
            auto local = local_transform(n, where);
            if (!local) return Unexpected(local.error());
            node.local = local.value();
            if (n.mesh >= 0) {
                auto meshes = read_mesh(n.mesh);
                if (!meshes) return Unexpected(meshes.error());
                node.meshes = meshes.value();
            }
            const int self = int(m_asset.nodes.size());
            m_asset_node[std::size_t(g)] = self;
            m_asset.nodes.push_back(std::move(node));
            for (auto c = n.children.rbegin(); c != n.children.rend(); ++c)
                stack.emplace_back(*c, self);
        }
        return {};
    }

    // Step: animation ----------------------------------------------------------------------------

    /// One channel of a node: its key times and values (xyz, or a quaternion's xyzw).
    struct Channel {
        std::vector<float> times;
        std::vector<Vec4> values;
        bool step = false;  ///< STEP: each value holds until the next key
    };
    /// A node's translation, rotation and scale channels (empty: the node's own value).
    using NodeChannels = std::array<Channel, 3>;

    /// The first animation's translation, rotation and scale channels, as keyframes of the nodes
    /// they move (glTF's animations are node TRS over seconds: the scene's keyframe animation).
    /// Morph weights are named in a warning; a node whose keys the scene cannot use keeps its
    /// rest transform, with a warning.
    Imported<void> read_animation() {
        if (m_model.animations.empty()) return {};
        const tinygltf::Animation& anim = m_model.animations[0];
        std::map<int, NodeChannels> moved;  // glTF node -> its channels
        for (std::size_t c = 0; c < anim.channels.size(); ++c) {
            const tinygltf::AnimationChannel& ch = anim.channels[c];
            const std::string where = "animations[0].channels[" + std::to_string(c) + "]";
            if (ch.target_path == "weights") {
                warn_once("animations[0]: morph target weights not imported");
                continue;
            }
            const int path = ch.target_path == "translation" ? 0
                             : ch.target_path == "rotation"  ? 1
                             : ch.target_path == "scale"     ? 2
                                                             : -1;
            if (path < 0)
                return m_sink.invalid(where, "target.path '" + ch.target_path.substr(0, 64) +
                                                 "' is not translation, rotation, scale or "
                                                 "weights");
            if (ch.target_node < 0 || std::size_t(ch.target_node) >= m_asset_node.size())
                return m_sink.invalid(where, "target.node " + std::to_string(ch.target_node) +
                                                 " does not exist");
            if (ch.sampler < 0 || std::size_t(ch.sampler) >= anim.samplers.size())
                return m_sink.invalid(where, "sampler " + std::to_string(ch.sampler) +
                                                 " does not exist");
            if (m_asset_node[std::size_t(ch.target_node)] < 0) continue;  // not imported
            auto channel = read_channel(anim.samplers[std::size_t(ch.sampler)], path, where);
            if (!channel) return Unexpected(channel.error());
            moved[ch.target_node][std::size_t(path)] = std::move(channel.value());
        }
        for (auto& [g, channels] : moved) {
            const std::string where = "nodes[" + std::to_string(g) + "]";
            if (m_model.nodes[std::size_t(g)].matrix.size() == 16)
                return m_sink.invalid(where, "is animated but has a matrix (glTF: only TRS)");
            node_keyframes(m_model.nodes[std::size_t(g)], channels, where,
                           m_asset.nodes[std::size_t(m_asset_node[std::size_t(g)])]);
        }
        return {};
    }

    /// A sampler's keys: increasing finite times within MAX_SCENE_TIME, float values (three, or
    /// a non-zero quaternion for rotation); CUBICSPLINE keeps the values, not the tangents.
    Imported<Channel> read_channel(const tinygltf::AnimationSampler& s, int path,
                                   const std::string& where) {
        auto input = accessor(s.input, where + "'s input");
        if (!input) return Unexpected(input.error());
        auto output = accessor(s.output, where + "'s output");
        if (!output) return Unexpected(output.error());
        const AccessorView& in = input.value();
        const AccessorView& out = output.value();
        const int width = path == 1 ? 4 : 3;
        if (in.component != TINYGLTF_COMPONENT_TYPE_FLOAT || in.width != 1 ||
            out.component != TINYGLTF_COMPONENT_TYPE_FLOAT || out.width != width)
            return m_sink.unsupported(where, "keys must be float scalars and float VEC" +
                                                 std::to_string(width) + " values");
        const bool cubic = s.interpolation == "CUBICSPLINE";
        if (in.count == 0 || in.count > MAX_ANIMATION_KEYS)
            return m_sink.invalid(where, std::to_string(in.count) + " keys: 1 to " +
                                             std::to_string(MAX_ANIMATION_KEYS));
        if (out.count != in.count * (cubic ? 3 : 1))
            return m_sink.invalid(where, std::to_string(out.count) + " values for " +
                                             std::to_string(in.count) + " keys");
        if (cubic)
            warn_once(where + ": CUBICSPLINE tangents ignored (keys interpolated linearly)");
        Channel ch;
        ch.step = s.interpolation == "STEP";
        for (std::size_t k = 0; k < in.count; ++k) {
            const float t = in.get(k, 0);
            if (!(std::abs(t) <= MAX_SCENE_TIME) || (k > 0 && !(t > ch.times.back())))
                return m_sink.invalid(where, "key " + std::to_string(k) +
                                                 ": times must be finite and increasing");
            Vec4 v(0.0f);
            const std::size_t at = cubic ? 3 * k + 1 : k;  // a cubic key: in, value, out
            for (int c = 0; c < width; ++c) v[c] = out.get(at, c);
            if (!is_finite(Vec3(v)) || !std::isfinite(v.w) ||
                (path == 1 && glm::length(v) < 1e-6f))
                return m_sink.invalid(where, "value " + std::to_string(k) +
                                                 " is not finite (or a zero quaternion)");
            ch.times.push_back(t);
            ch.values.push_back(v);
        }
        return ch;
    }

    /// A channel's value at time `t` (its ends outside its keys).
    static Vec4 sample(const Channel& ch, float t, bool rotation) {
        if (!(t > ch.times.front())) return ch.values.front();
        if (!(t < ch.times.back())) return ch.values.back();
        const std::size_t k = std::size_t(
            std::upper_bound(ch.times.begin(), ch.times.end(), t) - ch.times.begin());
        const Vec4 a = ch.values[k - 1], b = ch.values[k];
        if (ch.step) return a;
        const float u = (t - ch.times[k - 1]) / (ch.times[k] - ch.times[k - 1]);
        if (!rotation) return a + (b - a) * u;
        const glm::quat q = glm::slerp(glm::normalize(glm::quat(a.w, a.x, a.y, a.z)),
                                       glm::normalize(glm::quat(b.w, b.x, b.y, b.z)), u);
        return {q.x, q.y, q.z, q.w};
    }

    /// Keyframes at every time any channel has a key, missing channels at the node's own TRS.
    void node_keyframes(const tinygltf::Node& n, const NodeChannels& channels,
                        const std::string& where, AssetNode& node) {
        std::vector<float> times;
        for (const Channel& ch : channels)
            times.insert(times.end(), ch.times.begin(), ch.times.end());
        std::sort(times.begin(), times.end());
        times.erase(std::unique(times.begin(), times.end()), times.end());
        const auto rest = [&](const std::vector<double>& v, Vec4 fallback) {
            for (std::size_t i = 0; i < v.size() && i < 4; ++i) fallback[int(i)] = float(v[i]);
            return fallback;
        };
        const Vec4 fixed[3] = {rest(n.translation, Vec4(0.0f)), rest(n.rotation, {0, 0, 0, 1}),
                               rest(n.scale, Vec4(1.0f))};
        std::vector<Keyframe> keys;
        keys.reserve(std::min(times.size(), MAX_ANIMATION_KEYS));
        for (std::size_t k = 0; k < times.size() && k < MAX_ANIMATION_KEYS; ++k) {
            Vec4 trs[3];
            for (int c = 0; c < 3; ++c)
                trs[c] = channels[std::size_t(c)].times.empty()
                             ? fixed[c]
                             : sample(channels[std::size_t(c)], times[k], c == 1);
            const Affine t = Affine::trs(Vec3(trs[0]), Affine::rotation_quaternion(trs[1]),
                                         Vec3(trs[2]));
            if (const char* why = transform_problem(t)) {
                warn_once(where + ": its animation is not imported: at " +
                          std::to_string(times[k]) + " s its transform is unusable (" + why +
                          ")");
                return;
            }
            keys.push_back({times[k], t});
        }
        if (times.size() > MAX_ANIMATION_KEYS)
            warn_once(where + ": keys past " + std::to_string(MAX_ANIMATION_KEYS) +
                      " not imported");
        node.animation = std::move(keys);
    }

    /// What the file holds that no Strata object can carry: named in warnings, never dropped
    /// in silence.
    void warn_unread_features() {
        const auto count = [&](std::size_t n, const char* what) {
            if (n > 0) warn_once(std::to_string(n) + " " + what + " not imported");
        };
        if (const std::size_t total = m_model.animations.size(); total > 1)
            warn_once(std::to_string(total - 1) + (total == 2 ? " animation" : " animations") +
                      " after the first not imported");
        count(m_model.skins.size(), "skins");
        count(m_model.cameras.size(), "cameras");
        std::string unread;
        std::size_t listed = 0, more = 0;
        for (const std::string& name : m_model.extensionsUsed) {
            if (is_read_extension(name)) continue;
            if (listed++ < 16)
                unread += (unread.empty() ? "" : ", ") + name.substr(0, 64);
            else
                ++more;
        }
        if (more > 0) unread += " and " + std::to_string(more) + " more";
        if (!unread.empty()) warn_once("extensionsUsed: " + unread + " not imported (ignored)");
    }

    /// The parts of material `gm` the engine's material has no place for.
    void warn_unread_material(const tinygltf::Material& gm, const std::string& where) {
        for (const auto& [name, value] : gm.extensions)
            if (name != EMISSIVE_STRENGTH && name != UNLIT)
                warn_once(where + ".extensions." + name + " not imported");
    }

    /// Adds a warning unless it was given already; past MAX_WARNINGS they are only counted (a
    /// file of thousands of materials must not make the answer, or this search, huge).
    void warn_once(const std::string& what) {
        if (std::find(m_asset.warnings.begin(), m_asset.warnings.end(), what) !=
            m_asset.warnings.end())
            return;
        if (m_asset.warnings.size() >= MAX_WARNINGS) {
            ++m_unlisted_warnings;
            return;
        }
        m_asset.warnings.push_back(what);
    }

    const tinygltf::Model& m_model;
    const ErrorSink& m_sink;
    const ImportLimits& m_limits;
    Asset m_asset;
    /// Per material (read_material_textures): the texture coordinate sets its textures read.
    std::vector<MaterialUvs> m_material_uvs;
    std::map<int, std::vector<int>> m_meshes;  ///< glTF mesh -> asset meshes
    std::vector<int> m_asset_node;  ///< glTF node -> asset node, -1: not in the imported scene
    /// (glTF image, colour space) -> asset texture
    std::map<std::pair<int, TextureColorSpace>, int> m_images;
    /// (buffer view holding an image, colour space) -> asset texture
    std::map<std::pair<int, TextureColorSpace>, int> m_views;
    uint64_t m_vertices = 0;
    uint64_t m_triangles = 0;
    std::size_t m_unlisted_warnings = 0;  ///< past MAX_WARNINGS
};

/// What a glTF says of itself before anything is read: its `asset.version` and the extensions it
/// requires. Read with nlohmann's SAX parser (no document is built); "" and none when absent.
struct GltfPreamble {
    std::string version;
    std::vector<std::string> required;
};

/// The SAX events of the top-level `asset.version` and `extensionsRequired`; the rest is skipped.
class PreambleReader : public nlohmann::json_sax<nlohmann::json> {
public:
    explicit PreambleReader(GltfPreamble& out) : m_out(out) {}
    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(number_integer_t) override { return true; }
    bool number_unsigned(number_unsigned_t) override { return true; }
    bool number_float(number_float_t, const string_t&) override { return true; }
    bool binary(binary_t&) override { return true; }
    bool string(string_t& value) override {
        if (m_depth == 2 && m_top == "asset" && m_key == "version")
            m_out.version = value.substr(0, 16);
        if (m_depth == 2 && m_top == "extensionsRequired" && m_out.required.size() < 16)
            m_out.required.push_back(value.substr(0, 64));
        return true;
    }
    bool start_object(std::size_t) override { return enter(); }
    bool start_array(std::size_t) override { return enter(); }
    bool end_object() override { return leave(); }
    bool end_array() override { return leave(); }
    bool key(string_t& key) override {
        if (m_depth == 1) m_top = key;
        if (m_depth == 2) m_key = key;
        return true;
    }
    bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override {
        return false;  // tinygltf reports it
    }

private:
    bool enter() {
        ++m_depth;
        if (m_depth == 2) m_key.clear();
        return true;
    }
    bool leave() {
        if (--m_depth == 1) m_key.clear();
        return true;
    }
    GltfPreamble& m_out;
    int m_depth = 0;
    std::string m_top;  ///< the top-level member being read
    std::string m_key;  ///< the member of `asset` being read
};

GltfPreamble gltf_preamble(std::string_view json) {
    GltfPreamble out;
    PreambleReader reader(out);
    (void)nlohmann::json::sax_parse(json, &reader, nlohmann::json::input_format_t::json, false);
    return out;
}

/// Refuses what tinygltf would misreport: glTF 1.0 ("asset object not found") and required
/// extensions other than the ones read here ("invalid bufferView").
Imported<void> check_preamble(const GltfPreamble& p, const ErrorSink& sink) {
    if (!p.version.empty() && p.version.rfind("2.", 0) != 0)
        return sink.unsupported("asset.version",
                                "glTF " + p.version +
                                    " is not supported; only glTF 2.0 is imported (convert the "
                                    "file, for example with gltf-pipeline or Blender)");
    std::string names;
    for (const std::string& e : p.required)
        if (!is_read_extension(e)) names += (names.empty() ? "" : ", ") + e;
    if (names.empty()) return {};
    return sink.unsupported("extensionsRequired",
                            "the file requires " + names +
                                ", which Strata does not import (a required extension cannot "
                                "be ignored)");
}

/// tinygltf's message, one line, without its trailing newline.
std::string first_line(const std::string& text) {
    std::string out = text.substr(0, text.find('\n'));
    return out.empty() ? "could not be parsed" : out;
}

}  // namespace

Imported<Asset> import_gltf(std::span<const uint8_t> bytes, bool binary, const std::string& file,
                            const ImportLimits& limits, const SideFiles& side_files) {
    const ErrorSink sink(file);
    if (bytes.size() > std::numeric_limits<unsigned int>::max())
        return sink.too_large("", "the file is larger than 4 GiB");
    if (binary) {
        if (const std::string problem = glb_container_problem(bytes); !problem.empty())
            return sink.invalid("", "not a valid .glb: " + problem);
    }
    // Step 1: refuse JSON nested deeper than any glTF needs (tinygltf recurses over extras).
    const std::string_view json =
        binary ? glb_json(bytes)
               : std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    const JsonShape shape = json_shape(json, limits.max_json_depth);
    if (shape.deepest > limits.max_json_depth)
        return sink.invalid(
            "", "JSON nested deeper than " + std::to_string(limits.max_json_depth) + " levels");
    // Each primitive becomes a mesh, which costs MESH_OVERHEAD_TRIANGLES of the budget at
    // least: too many are refused before tinygltf holds a model of every one.
    if (shape.primitives * MESH_OVERHEAD_TRIANGLES > limits.max_triangles)
        return sink.too_large("", "the file declares " + std::to_string(shape.primitives) +
                                      " primitives, each mesh counted with " +
                                      std::to_string(MESH_OVERHEAD_TRIANGLES) +
                                      " triangles at least; the scene has room for " +
                                      std::to_string(limits.max_triangles) +
                                      " (max_scene_triangles)");
    // Step 2: a version and required extensions this importer reads.
    if (auto ok = check_preamble(gltf_preamble(json), sink); !ok) return Unexpected(ok.error());
    // Step 3: parse with the filesystem closed: external files come from the side files only.
    const std::optional<std::string> moved = json.empty() ? std::nullopt : move_draco_indices(json);
    const std::string rewritten = moved ? with_json(bytes, binary, *moved) : std::string();
    if (moved) bytes = {reinterpret_cast<const uint8_t*>(rewritten.data()), rewritten.size()};
    tinygltf::TinyGLTF loader;
    loader.SetFsCallbacks({&any_file_exists, &keep_path, &read_side_file, &refuse_write,
                           const_cast<SideFiles*>(&side_files)});
    loader.SetImageLoader(&keep_encoded_image, nullptr);
    loader.SetStoreOriginalJSONForExtrasAndExtensions(false);
    tinygltf::Model model;
    std::string err, warn;
    bool ok = false;
    try {
        ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(),
                                                  unsigned(bytes.size()), "")
                    : loader.LoadASCIIFromString(&model, &err, &warn,
                                                 reinterpret_cast<const char*>(bytes.data()),
                                                 unsigned(bytes.size()), "");
    } catch (const std::exception& e) {
        return sink.invalid("", std::string("not valid glTF: ") + e.what());
    }
    if (!ok) {
        if (err.find("external file") != std::string::npos)
            return sink.unsupported("buffers", first_line(err));
        return sink.invalid("", "not valid glTF: " + first_line(err.empty() ? warn : err));
    }
    // Step 4: the model into the intermediate form, every reference checked.
    return GltfReader(model, sink, limits).read();
}

}  // namespace strata::assets
