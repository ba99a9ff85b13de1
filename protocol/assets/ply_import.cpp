#include "protocol/assets/ply_import.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>

namespace strata::assets {

namespace {

enum class PlyType : uint8_t { Int8, Uint8, Int16, Uint16, Int32, Uint32, Float32, Float64 };

std::optional<PlyType> type_named(std::string_view n) {
    if (n == "char" || n == "int8") return PlyType::Int8;
    if (n == "uchar" || n == "uint8") return PlyType::Uint8;
    if (n == "short" || n == "int16") return PlyType::Int16;
    if (n == "ushort" || n == "uint16") return PlyType::Uint16;
    if (n == "int" || n == "int32") return PlyType::Int32;
    if (n == "uint" || n == "uint32") return PlyType::Uint32;
    if (n == "float" || n == "float32") return PlyType::Float32;
    if (n == "double" || n == "float64") return PlyType::Float64;
    return std::nullopt;
}

std::size_t size_of(PlyType t) {
    static constexpr std::size_t SIZES[] = {1, 1, 2, 2, 4, 4, 4, 8};
    return SIZES[int(t)];
}

bool is_integral(PlyType t) {
    return t != PlyType::Float32 && t != PlyType::Float64;
}

/// Most corners one face may list (a polygon beyond this is not a mesh face).
constexpr double MAX_FACE_CORNERS = 65536;
/// Longest header accepted.
constexpr std::size_t MAX_HEADER = 1 << 16;
/// The scalar properties of a row that are kept (the first ones; later ones feed nothing).
constexpr std::size_t MAX_ROW_VALUES = 64;

struct PlyProperty {
    std::string name;
    PlyType type = PlyType::Float32;
    bool list = false;
    PlyType count_type = PlyType::Uint8;
};

struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

enum class PlyEncoding : uint8_t { Ascii, Little, Big };

struct PlyHeader {
    PlyEncoding encoding = PlyEncoding::Ascii;
    std::vector<PlyElement> elements;
    std::size_t body = 0;  ///< offset of the first byte after end_header
    /// Lines skipped (no keyword PLY knows, as old writers put free text without `comment`):
    /// the first MAX_SKIPPED_NAMED named, all counted.
    std::vector<std::string> skipped;
    std::size_t skipped_count = 0;
};

/// Skipped header lines named in warnings, at most (a 64 KiB header could hold thousands).
constexpr std::size_t MAX_SKIPPED_NAMED = 8;

std::vector<std::string_view> split(std::string_view line) {
    std::vector<std::string_view> out;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
        const std::size_t start = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
        if (i > start) out.push_back(line.substr(start, i - start));
    }
    return out;
}

using Words = std::vector<std::string_view>;

/// A `format <encoding> 1.0` line.
Imported<PlyEncoding> read_format(const Words& words, const std::string& where,
                                  const ErrorSink& sink) {
    if (words.size() != 3 || words[2] != "1.0")
        return sink.unsupported(where, "expected 'format <encoding> 1.0'");
    if (words[1] == "ascii") return PlyEncoding::Ascii;
    if (words[1] == "binary_little_endian") return PlyEncoding::Little;
    if (words[1] == "binary_big_endian") return PlyEncoding::Big;
    return sink.unsupported(where, "unknown encoding '" + std::string(words[1]) + "'");
}

/// A `property <type> <name>` or `property list <count type> <type> <name>` line.
Imported<PlyProperty> read_property(const Words& words, const std::string& where,
                                    const ErrorSink& sink) {
    PlyProperty p;
    if (words.size() == 5 && words[1] == "list") {
        const auto ct = type_named(words[2]);
        const auto vt = type_named(words[3]);
        if (!ct || !vt || !is_integral(*ct)) return sink.invalid(where, "bad list property types");
        p.list = true;
        p.count_type = *ct;
        p.type = *vt;
        p.name = words[4];
        return p;
    }
    if (words.size() != 3)
        return sink.invalid(where,
                            "expected 'property <type> <name>' or 'property list "
                            "<count type> <type> <name>'");
    const auto t = type_named(words[1]);
    if (!t) return sink.invalid(where, "unknown type '" + std::string(words[1]) + "'");
    p.type = *t;
    p.name = words[2];
    return p;
}

Imported<PlyHeader> read_header(std::string_view text, const ErrorSink& sink) {
    PlyHeader h;
    std::size_t pos = 0;
    int line_no = 0;
    bool format_seen = false;
    while (true) {
        const std::size_t nl = text.find('\n', pos);
        if (nl == std::string_view::npos || nl > MAX_HEADER)
            return sink.invalid("header", "no end_header within the first 64 KiB");
        const std::string_view line = text.substr(pos, nl - pos);
        pos = nl + 1;
        ++line_no;
        const Words words = split(line);
        const std::string where = "header line " + std::to_string(line_no);
        if (line_no == 1) {
            if (words.size() != 1 || words[0] != "ply")
                return sink.invalid("header", "does not start with 'ply'");
            continue;
        }
        if (words.empty() || words[0] == "comment" || words[0] == "obj_info") continue;
        if (words[0] == "end_header") break;
        if (words[0] == "format") {
            auto encoding = read_format(words, where, sink);
            if (!encoding) return Unexpected(encoding.error());
            h.encoding = encoding.value();
            format_seen = true;
        } else if (words[0] == "element") {
            uint64_t count = 0;
            if (words.size() != 3 ||
                std::from_chars(words[2].data(), words[2].data() + words[2].size(), count).ec !=
                    std::errc())
                return sink.invalid(where, "expected 'element <name> <count>'");
            h.elements.push_back({std::string(words[1]), count, {}});
        } else if (words[0] == "property") {
            if (h.elements.empty()) return sink.invalid(where, "a property before any element");
            auto property = read_property(words, where, sink);
            if (!property) return Unexpected(property.error());
            h.elements.back().properties.push_back(std::move(property.value()));
        } else if (h.skipped_count++ < MAX_SKIPPED_NAMED) {
            // Blender 2.4x wrote "Created by Blender3D ..." without `comment`; assimp and Blender
            // read such files, and so do we, saying so.
            h.skipped.push_back(where + " skipped: unknown keyword '" +
                                std::string(words[0].substr(0, 40)) + "'");
        }
    }
    if (!format_seen) return sink.invalid("header", "has no format line");
    h.body = pos;
    return h;
}

/// Reads the body's values one at a time, in any of the three encodings.
class ValueReader {
public:
    ValueReader(std::span<const uint8_t> body, PlyEncoding encoding)
        : m_p(body.data()), m_end(body.data() + body.size()), m_encoding(encoding) {}

    std::size_t remaining() const { return std::size_t(m_end - m_p); }

    /// The next value as a double; false at the end of the data or on a malformed number.
    bool read(PlyType t, double& out) {
        if (m_encoding == PlyEncoding::Ascii) return read_text(t, out);
        const std::size_t n = size_of(t);
        if (remaining() < n) return false;
        uint8_t b[8];
        std::memcpy(b, m_p, n);
        m_p += n;
        if (m_encoding == PlyEncoding::Big) std::reverse(b, b + n);
        switch (t) {
            case PlyType::Int8:
                out = int8_t(b[0]);
                break;
            case PlyType::Uint8:
                out = b[0];
                break;
            case PlyType::Int16: {
                int16_t v;
                std::memcpy(&v, b, 2);
                out = v;
                break;
            }
            case PlyType::Uint16: {
                uint16_t v;
                std::memcpy(&v, b, 2);
                out = v;
                break;
            }
            case PlyType::Int32: {
                int32_t v;
                std::memcpy(&v, b, 4);
                out = v;
                break;
            }
            case PlyType::Uint32: {
                uint32_t v;
                std::memcpy(&v, b, 4);
                out = v;
                break;
            }
            case PlyType::Float32: {
                float v;
                std::memcpy(&v, b, 4);
                out = v;
                break;
            }
            case PlyType::Float64:
                std::memcpy(&out, b, 8);
                break;
        }
        return true;
    }

private:
    bool read_text(PlyType t, double& out) {
        while (m_p < m_end && std::isspace(*m_p)) ++m_p;
        const uint8_t* start = m_p;
        while (m_p < m_end && !std::isspace(*m_p)) ++m_p;
        if (m_p == start) return false;
        const char* first = reinterpret_cast<const char*>(start);
        const char* last = reinterpret_cast<const char*>(m_p);
        const auto [end, ec] = std::from_chars(first, last, out);
        if (ec != std::errc() || end != last) return false;
        if (is_integral(t) && out != std::floor(out)) return false;
        return true;
    }

    const uint8_t* m_p;
    const uint8_t* m_end;
    PlyEncoding m_encoding;
};

/// Which vertex property feeds which attribute.
struct VertexSlots {
    int x = -1, y = -1, z = -1, nx = -1, ny = -1, nz = -1, r = -1, g = -1, b = -1, u = -1, v = -1;
    int radius = -1;
    float color_scale = 1.0f;
};

VertexSlots vertex_slots(const PlyElement& e) {
    VertexSlots s;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        if (p.list) continue;
        const std::string& n = p.name;
        const int k = int(i);
        if (n == "x") s.x = k;
        if (n == "y") s.y = k;
        if (n == "z") s.z = k;
        if (n == "nx") s.nx = k;
        if (n == "ny") s.ny = k;
        if (n == "nz") s.nz = k;
        if (n == "red" || n == "diffuse_red") s.r = k;
        if (n == "green" || n == "diffuse_green") s.g = k;
        if (n == "blue" || n == "diffuse_blue") s.b = k;
        if (n == "u" || n == "s" || n == "texture_u" || n == "texture_s") s.u = k;
        if (n == "v" || n == "t" || n == "texture_v" || n == "texture_t") s.v = k;
        if (n == "radius" && i < MAX_ROW_VALUES) s.radius = k;
    }
    if (s.r >= 0) {
        const PlyType t = e.properties[std::size_t(s.r)].type;
        s.color_scale = t == PlyType::Uint8    ? 1.0f / 255.0f
                        : t == PlyType::Uint16 ? 1.0f / 65535.0f
                                               : 1.0f;
    }
    return s;
}

/// What one element's rows feed: the vertex attributes, or the face list.
struct ElementPlan {
    std::string where;  ///< "element face"
    bool is_vertex = false;
    bool is_face = false;
    VertexSlots slots;
    int face_list = -1;  ///< the face element's vertex_indices property
};

/// Reads a PLY body element by element into one mesh.
class PlyBody {
public:
    PlyBody(const PlyHeader& header, std::span<const uint8_t> bytes, const std::string& file,
            const ImportLimits& limits)
        : m_in(bytes.subspan(header.body), header.encoding), m_sink(file), m_limits(limits) {
        m_mesh.name = file;
        m_warnings = header.skipped;
        if (header.skipped_count > header.skipped.size())
            m_warnings.push_back(std::to_string(header.skipped_count - header.skipped.size()) +
                                 " more header lines with unknown keywords skipped");
    }

    /// Step 1: the declared count must fit the bytes that follow (each element takes at least
    /// one byte per property) and, for vertices and faces, the budget.
    Imported<ElementPlan> plan(const PlyElement& e) {
        ElementPlan plan;
        plan.where = "element " + e.name;
        plan.is_vertex = e.name == "vertex";
        plan.is_face = e.name == "face";
        const std::string& where = plan.where;
        if (e.count > 0 && e.properties.empty()) return m_sink.invalid(where, "has no properties");
        if (e.count > m_in.remaining())
            return m_sink.invalid(
                where, "declares " + std::to_string(e.count) + " elements, more than the " +
                           std::to_string(m_in.remaining()) + " bytes that follow");
        if (plan.is_vertex) {
            if (m_have_vertices) return m_sink.invalid(where, "a second vertex element");
            m_have_vertices = true;
            plan.slots = vertex_slots(e);
            if (plan.slots.x < 0 || plan.slots.y < 0 || plan.slots.z < 0)
                return m_sink.invalid(where, "has no x, y and z properties");
            if (e.count > m_limits.max_vertices)
                return m_sink.too_large(
                    where, std::to_string(e.count) + " vertices; the scene has room for " +
                               std::to_string(m_limits.max_vertices) + " (max_scene_vertices)");
            m_mesh.positions.reserve(e.count);
        }
        if (plan.is_face) {
            for (std::size_t i = 0; i < e.properties.size(); ++i)
                if (e.properties[i].list && (e.properties[i].name == "vertex_indices" ||
                                             e.properties[i].name == "vertex_index"))
                    plan.face_list = int(i);
            if (plan.face_list < 0) return m_sink.invalid(where, "has no vertex_indices list");
            if (!is_integral(e.properties[std::size_t(plan.face_list)].type))
                return m_sink.invalid(where, "vertex_indices must be integers");
            m_declared_faces += e.count;
            if (e.count > m_limits.max_triangles)
                return m_sink.too_large(where, std::to_string(e.count) +
                                                   " faces; the scene has room for " +
                                                   std::to_string(m_limits.max_triangles) +
                                                   " triangles (max_scene_triangles)");
            m_mesh.triangles.reserve(e.count);
        }
        return plan;
    }

    /// Step 2: every row, every property read (so that binary offsets stay right).
    Imported<void> read(const PlyElement& e, const ElementPlan& plan) {
        for (uint64_t i = 0; i < e.count; ++i) {
            const std::string at = plan.where + " " + std::to_string(i);
            if (auto ok = read_row(e, plan, at); !ok) return ok;
            if (plan.is_vertex) add_vertex(plan.slots);
            if (plan.is_face && m_corners.size() < 3) ++m_skipped_faces;
            if (plan.is_face && m_corners.size() >= 3) {
                for (std::size_t c = 1; c + 1 < m_corners.size(); ++c)
                    m_mesh.triangles.push_back({m_corners[0], m_corners[c], m_corners[c + 1]});
                if (m_mesh.triangles.size() > m_limits.max_triangles)
                    return m_sink.too_large(plan.where, "more than " +
                                                            std::to_string(m_limits.max_triangles) +
                                                            " triangles (max_scene_triangles)");
            }
        }
        return {};
    }

    /// Step 3: the mesh (or, without faces, the point cloud) as an asset of one node, its
    /// optional attributes checked.
    Imported<Asset> finish() {
        if (!m_have_vertices) return m_sink.invalid("header", "has no vertex element");
        Asset asset;
        asset.warnings = std::move(m_warnings);
        if (m_mesh.triangles.empty() && m_declared_faces > 0)
            return m_sink.invalid(
                "element face",
                "none of its " + std::to_string(m_declared_faces) + " faces has 3 corners or more");
        if (m_mesh.triangles.empty()) {
            if (auto ok = make_points(asset.warnings); !ok) return Unexpected(ok.error());
        }
        if (m_skipped_faces)
            asset.warnings.push_back(std::to_string(m_skipped_faces) +
                                     " faces with fewer than 3 corners skipped");
        // Non-finite optional attributes are dropped rather than refusing the whole file.
        if (!std::all_of(m_mesh.normals.begin(), m_mesh.normals.end(),
                         [](const Vec3& n) { return is_finite(n); })) {
            m_mesh.normals.clear();
            asset.warnings.push_back("normals dropped: some are not finite");
        }
        AssetNode root;
        root.name = m_mesh.name;
        root.meshes = {0};
        asset.meshes.push_back(std::move(m_mesh));
        asset.nodes.push_back(std::move(root));
        if (auto ok = check_budget(asset, m_limits, m_sink); !ok) return Unexpected(ok.error());
        if (auto ok = validate_asset(asset, m_sink); !ok) return Unexpected(ok.error());
        return asset;
    }

private:
    /// The vertices as a point cloud: each with its `radius` (checked, naming the vertex) or the
    /// default radius; the normals and texture coordinates points cannot carry are dropped.
    Imported<void> make_points(std::vector<std::string>& warnings) {
        const std::size_t n = m_mesh.positions.size();
        m_mesh.kind = MeshKind::Points;
        if (m_radii.size() == n && n > 0) {
            for (std::size_t v = 0; v < n; ++v)
                if (!std::isfinite(m_radii[v]) || !(m_radii[v] > 0.0f) ||
                    double(m_radii[v]) > MAX_COORDINATE)
                    return m_sink.invalid("element vertex " + std::to_string(v),
                                          "radius " + radius_text(m_radii[v]) +
                                              " is not a finite number > 0 and at most 1e15");
            m_mesh.radii = std::move(m_radii);
        } else {
            const float r = default_point_radius(m_mesh.positions);
            m_mesh.radii.assign(n, r);
            warnings.push_back("no faces: the " + std::to_string(n) +
                               " vertices are points, without a radius property; each has radius " +
                               radius_text(r) +
                               " (0.5 * D / sqrt(N), D the diagonal of their bounds)");
        }
        if (!m_mesh.normals.empty() || !m_mesh.uvs.empty())
            warnings.push_back("normals and texture coordinates dropped: points carry none");
        m_mesh.normals.clear();
        m_mesh.uvs.clear();
        return {};
    }

    /// One row's properties into m_row (scalars) and m_corners (the face list).
    Imported<void> read_row(const PlyElement& e, const ElementPlan& plan, const std::string& at) {
        for (std::size_t k = 0; k < e.properties.size(); ++k) {
            const PlyProperty& p = e.properties[k];
            double value = 0.0;
            if (!p.list) {
                if (!m_in.read(p.type, value))
                    return m_sink.invalid(at,
                                          "property " + p.name + ": missing or malformed value");
                if (k < std::size(m_row)) m_row[k] = value;
                continue;
            }
            double n = 0.0;
            if (!m_in.read(p.count_type, n) || n < 0 || n > MAX_FACE_CORNERS)
                return m_sink.invalid(at, "property " + p.name + ": bad list length");
            const bool keep = plan.is_face && int(k) == plan.face_list;
            if (keep) m_corners.clear();
            for (uint32_t c = 0; c < uint32_t(n); ++c) {
                if (!m_in.read(p.type, value))
                    return m_sink.invalid(at,
                                          "property " + p.name + ": missing or malformed value");
                if (!keep) continue;
                if (value < 0 || value >= double(m_mesh.positions.size()))
                    return m_sink.invalid(at, "vertex index " + std::to_string(int64_t(value)) +
                                                  " is outside the " +
                                                  std::to_string(m_mesh.positions.size()) +
                                                  " vertices read before it");
                m_corners.push_back(uint32_t(value));
            }
        }
        return {};
    }

    void add_vertex(const VertexSlots& slots) {
        auto get = [&](int slot) {
            return slot >= 0 && std::size_t(slot) < std::size(m_row) ? float(m_row[slot]) : 0.0f;
        };
        m_mesh.positions.push_back({get(slots.x), get(slots.y), get(slots.z)});
        if (slots.nx >= 0 && slots.ny >= 0 && slots.nz >= 0)
            m_mesh.normals.push_back({get(slots.nx), get(slots.ny), get(slots.nz)});
        if (slots.r >= 0 && slots.g >= 0 && slots.b >= 0)
            m_mesh.colors.push_back(
                glm::clamp(Vec3(get(slots.r), get(slots.g), get(slots.b)) * slots.color_scale,
                           Vec3(0.0f), Vec3(1.0f)));
        // PLY's v, like OBJ's, grows upward; the engine's grows downward.
        if (slots.u >= 0 && slots.v >= 0) m_mesh.uvs.push_back({get(slots.u), 1.0f - get(slots.v)});
        // Kept as read (checked only if the file turns out to be a point cloud).
        if (slots.radius >= 0) m_radii.push_back(get(slots.radius));
    }

    ValueReader m_in;
    ErrorSink m_sink;
    const ImportLimits& m_limits;
    AssetMesh m_mesh;
    bool m_have_vertices = false;
    uint64_t m_skipped_faces = 0;
    uint64_t m_declared_faces = 0;  ///< over face elements' headers
    std::vector<float> m_radii;     ///< the vertices' `radius` property, when they have one
    double m_row[MAX_ROW_VALUES] = {};
    std::vector<uint32_t> m_corners;
    std::vector<std::string> m_warnings;  ///< the header's, then the body's
};

}  // namespace

Imported<Asset> import_ply(std::span<const uint8_t> bytes, const std::string& file,
                           const ImportLimits& limits) {
    const ErrorSink sink(file);
    auto parsed = read_header(
        std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), sink);
    if (!parsed) return Unexpected(parsed.error());
    PlyBody body(parsed.value(), bytes, file, limits);
    for (const PlyElement& e : parsed.value().elements) {
        auto plan = body.plan(e);
        if (!plan) return Unexpected(plan.error());
        if (auto ok = body.read(e, plan.value()); !ok) return Unexpected(ok.error());
    }
    return body.finish();
}

}  // namespace strata::assets
