#include "protocol/assets/asset.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>

#include "engine/scene/budget.h"

namespace strata::assets {

namespace {

std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = char(std::tolower(static_cast<unsigned char>(c)));
    return out;
}

std::string_view trim(std::string_view v) {
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.remove_suffix(1);
    while (!v.empty() && (v.front() == ' ' || v.front() == '\t')) v.remove_prefix(1);
    return v;
}

}  // namespace

/// Each format's name, in the order of the enum.
constexpr const char* FORMAT_NAMES[] = {"glb", "gltf", "obj", "ply", "fbx", "dae", "stl", "3ds",
                                        "off", "x",   "ac",   "ase", "lwo", "ms3d", "b3d", "dxf",
                                        "3mf", "amf", "smd",  "nff", "cob", "xgl"};
static_assert(std::size(FORMAT_NAMES) == std::size_t(LAST_ASSET_FORMAT) + 1);

const char* format_name(AssetFormat f) {
    return std::size_t(f) < std::size(FORMAT_NAMES) ? FORMAT_NAMES[std::size_t(f)] : "?";
}

std::optional<AssetFormat> format_from_name(std::string_view name) {
    const std::string n = lower(name);
    for (std::size_t i = 0; i < std::size(FORMAT_NAMES); ++i)
        if (n == FORMAT_NAMES[i]) return AssetFormat(i);
    if (n == "zgl") return AssetFormat::Xgl;  // compressed XGL
    return std::nullopt;
}

std::string format_names() {
    std::string out;
    for (const char* name : FORMAT_NAMES) out += (out.empty() ? "" : ", ") + std::string(name);
    return out;
}

/// The Content-Types an upload may name its format with.
constexpr std::pair<const char*, AssetFormat> MEDIA_TYPES[] = {
    {"model/gltf-binary", AssetFormat::Glb},     {"model/gltf+json", AssetFormat::Gltf},
    {"model/obj", AssetFormat::Obj},             {"application/ply", AssetFormat::Ply},
    {"model/ply", AssetFormat::Ply},             {"model/x-ply", AssetFormat::Ply},
    {"model/vnd.collada+xml", AssetFormat::Dae}, {"model/stl", AssetFormat::Stl},
    {"model/x.stl-binary", AssetFormat::Stl},    {"model/x.stl-ascii", AssetFormat::Stl},
    {"model/3mf", AssetFormat::ThreeMf},
};

std::optional<AssetFormat> format_from_media_type(std::string_view type) {
    const std::string t = lower(trim(type.substr(0, type.find(';'))));
    for (const auto& [name, format] : MEDIA_TYPES)
        if (t == name) return format;
    return std::nullopt;
}

std::vector<std::string> media_type_names() {
    std::vector<std::string> out;
    for (const auto& [name, format] : MEDIA_TYPES) out.emplace_back(name);
    return out;
}

uint64_t Asset::vertex_count() const {
    uint64_t n = 0;
    for (const AssetMesh& m : meshes) n += m.positions.size();
    return n;
}

uint64_t Asset::triangle_count() const {
    uint64_t n = 0;
    for (const AssetMesh& m : meshes) n += m.triangles.size();
    return n;
}

namespace {

/// The diagonal of the bounds of `positions`, 1 when it is 0 (one point, or all coincide).
double diagonal_or_one(const std::vector<Vec3>& positions) {
    if (positions.empty()) return 1.0;
    Vec3 lo = positions[0], hi = positions[0];
    for (const Vec3& p : positions) {
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    }
    const glm::dvec3 d = glm::dvec3(hi) - glm::dvec3(lo);
    const double diagonal = std::sqrt(glm::dot(d, d));
    return diagonal > 0.0 && std::isfinite(diagonal) ? diagonal : 1.0;
}

/// `r` as a radius the scene accepts: > 0 as a float, at most MAX_COORDINATE.
float usable_radius(double r) {
    return float(std::clamp(r, double(std::numeric_limits<float>::min()), MAX_COORDINATE));
}

}  // namespace

float default_point_radius(const std::vector<Vec3>& positions) {
    const double n = double(std::max<std::size_t>(positions.size(), 1));
    return usable_radius(0.5 * diagonal_or_one(positions) / std::sqrt(n));
}

float default_line_radius(const std::vector<Vec3>& positions) {
    return usable_radius(0.002 * diagonal_or_one(positions));
}

std::string radius_text(float radius) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", double(radius));
    return text;
}

Unexpected<protocol::Problem> ErrorSink::make(protocol::ProblemType type, std::string element,
                                              const std::string& message) const {
    protocol::Problem p = protocol::make_problem(
        type, m_file + (element.empty() ? "" : ": " + element) + ": " + message);
    p.file = m_file;
    if (!element.empty()) p.element = std::move(element);
    return Unexpected(std::move(p));
}

Imported<void> check_budget(const Asset& asset, const ImportLimits& limits, const ErrorSink& sink) {
    const uint64_t v = asset.vertex_count();
    // Each mesh also costs MESH_OVERHEAD_TRIANGLES of the budget (budget.h).
    const uint64_t t = asset.triangle_count() + asset.meshes.size() * MESH_OVERHEAD_TRIANGLES;
    if (v > limits.max_vertices)
        return sink.too_large(
            "", "the asset holds " + std::to_string(v) + " vertices; the scene has room for " +
                    std::to_string(limits.max_vertices) + " (max_scene_vertices)");
    if (t > limits.max_triangles)
        return sink.too_large(
            "", "the asset holds " + std::to_string(t) +
                    " triangles, each of its meshes counted with " +
                    std::to_string(MESH_OVERHEAD_TRIANGLES) + " more; the scene has room for " +
                    std::to_string(limits.max_triangles) + " (max_scene_triangles)");
    if (asset.nodes.size() > limits.max_nodes)
        return sink.too_large("", "the asset holds " + std::to_string(asset.nodes.size()) +
                                      " nodes; at most " + std::to_string(limits.max_nodes));
    return {};
}

namespace {

/// Positions finite and within MAX_COORDINATE.
Imported<void> check_positions(const AssetMesh& m, const std::string& where,
                               const ErrorSink& sink) {
    for (std::size_t v = 0; v < m.positions.size(); ++v)
        if (!is_finite(m.positions[v]) ||
            glm::any(glm::greaterThan(glm::abs(m.positions[v]), Vec3(float(MAX_COORDINATE)))))
            return sink.invalid(
                where, "position " + std::to_string(v) + " is not finite or lies beyond 1e15");
    return {};
}

/// A triangle mesh's triangles: some, each inside the mesh; no radii or strands.
Imported<void> check_triangles(const AssetMesh& m, const std::string& where,
                               const ErrorSink& sink) {
    const std::size_t n = m.positions.size();
    if (m.triangles.empty()) return sink.invalid(where, "has no vertices or no triangles");
    if (!m.radii.empty() || !m.strands.empty())
        return sink.invalid(where,
                            "is a triangle mesh: radii and strands are for points and curves");
    for (std::size_t t = 0; t < m.triangles.size(); ++t) {
        const Triangle& tri = m.triangles[t];
        for (int k = 0; k < 3; ++k)
            if (tri[k] >= n)
                return sink.invalid(where, "triangle " + std::to_string(t) + " uses vertex " +
                                               std::to_string(tri[k]) + " of only " +
                                               std::to_string(n));
    }
    return {};
}

/// A points or curve mesh's primitives: no triangles and no surface attributes, one radius per
/// vertex (finite, > 0, at most MAX_COORDINATE), and, for curves, linear strands that use every
/// vertex; points have no strands.
Imported<void> check_points_or_curves(const AssetMesh& m, const std::string& where,
                                      const ErrorSink& sink) {
    const std::size_t n = m.positions.size();
    const std::string kind = m.kind == MeshKind::Points ? "a points mesh" : "a curve mesh";
    if (!m.triangles.empty()) return sink.invalid(where, "is " + kind + ": it takes no triangles");
    if (!m.normals.empty() || !m.uvs.empty() || !m.uvs1.empty() || !m.tangents.empty())
        return sink.invalid(where, "is " + kind +
                                       ": normals, texture coordinates and tangents are for "
                                       "triangle meshes");
    if (m.radii.size() != n)
        return sink.invalid(where, "has " + std::to_string(m.radii.size()) + " radii for " +
                                       std::to_string(n) + " vertices");
    for (std::size_t v = 0; v < n; ++v)
        if (!std::isfinite(m.radii[v]) || !(m.radii[v] > 0.0f) ||
            double(m.radii[v]) > MAX_COORDINATE)
            return sink.invalid(where, "radius " + std::to_string(v) +
                                           " is not a finite number > 0 and at most 1e15");
    if (m.kind == MeshKind::Points) {
        if (!m.strands.empty())
            return sink.invalid(where, "is a points mesh: strands are for curve meshes");
        return {};
    }
    std::size_t bad = 0;
    const std::string why = strands_problem(CurveBasis::Linear, m.strands, n, bad);
    if (!why.empty()) return sink.invalid(where, why);
    return {};
}

/// One mesh: its vertices, its primitives of its kind and its attributes.
Imported<void> check_mesh(const AssetMesh& m, const std::string& where, std::size_t materials,
                          const ErrorSink& sink) {
    const std::size_t n = m.positions.size();
    if (n == 0)
        return sink.invalid(where, m.kind == MeshKind::Triangles ? "has no vertices or no triangles"
                                                                 : "has no vertices");
    if (n > UINT32_MAX) return sink.too_large(where, "has more than 2^32 vertices");
    if (auto ok = check_positions(m, where, sink); !ok) return ok;
    auto primitives = m.kind == MeshKind::Triangles ? check_triangles(m, where, sink)
                                                    : check_points_or_curves(m, where, sink);
    if (!primitives) return primitives;
    for (const auto& [count, what] :
         {std::pair{m.normals.size(), "normals"}, std::pair{m.uvs.size(), "uvs"},
          std::pair{m.uvs1.size(), "uvs1"}, std::pair{m.tangents.size(), "tangents"},
          std::pair{m.colors.size(), "colors"}}) {
        if (count != 0 && count != n)
            return sink.invalid(where, "has " + std::to_string(count) + " " + what + " for " +
                                           std::to_string(n) + " vertices");
    }
    if (m.material < -1 || m.material >= int(materials))
        return sink.invalid(where, "refers to material " + std::to_string(m.material) +
                                       " of only " + std::to_string(materials));
    return {};
}

}  // namespace

Imported<void> validate_asset(const Asset& asset, const ErrorSink& sink) {
    // Step 1: meshes, their primitives and their attributes.
    for (std::size_t i = 0; i < asset.meshes.size(); ++i) {
        const AssetMesh& m = asset.meshes[i];
        const std::string where =
            "mesh " + std::to_string(i) + (m.name.empty() ? "" : " ('" + m.name + "')");
        if (auto ok = check_mesh(m, where, asset.materials.size(), sink); !ok) return ok;
    }
    // Step 2: materials, each within the engine's ranges.
    for (std::size_t i = 0; i < asset.materials.size(); ++i) {
        const AssetMaterial& m = asset.materials[i];
        const std::string where =
            "material " + std::to_string(i) + (m.name.empty() ? "" : " ('" + m.name + "')");
        if (Status s = check_material(m.material); !s)
            return sink.invalid(where, s.error().field + ": " + s.error().message);
        for (int texture : m.textures)
            if (texture < -1 || texture >= int(asset.textures.size()))
                return sink.invalid(where, "refers to texture " + std::to_string(texture) +
                                               " of only " + std::to_string(asset.textures.size()));
    }
    // Step 3: the node tree, parents first, and the world transforms it produces.
    std::size_t keyframes = 0;
    for (std::size_t i = 0; i < asset.nodes.size(); ++i) {
        const AssetNode& node = asset.nodes[i];
        const std::string where =
            "node " + std::to_string(i) + (node.name.empty() ? "" : " ('" + node.name + "')");
        if (node.parent < -1 || node.parent >= int(i))
            return sink.invalid(
                where, "its parent " + std::to_string(node.parent) + " does not come before it");
        if (!node.local.is_finite()) return sink.invalid(where, "transform is not finite");
        keyframes += node.animation.size();
        if (keyframes > MAX_IMPORTED_KEYFRAMES)
            return sink.too_large(where, "the animation brings more than " +
                                             std::to_string(MAX_IMPORTED_KEYFRAMES) + " keyframes");
        for (std::size_t k = 0; k < node.animation.size(); ++k) {
            const Keyframe& key = node.animation[k];
            if (!(std::abs(key.time) <= MAX_SCENE_TIME) ||
                (k > 0 && !(key.time > node.animation[k - 1].time)) ||
                transform_problem(key.transform))
                return sink.invalid(where, "keyframe " + std::to_string(k) +
                                               " has a time out of order or range, or a "
                                               "transform the scene cannot use");
        }
        for (int mesh : node.meshes)
            if (mesh < 0 || mesh >= int(asset.meshes.size()))
                return sink.invalid(where, "refers to mesh " + std::to_string(mesh) + " of only " +
                                               std::to_string(asset.meshes.size()));
    }
    return {};
}

}  // namespace strata::assets
