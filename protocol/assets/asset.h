#pragma once
// The intermediate form every importer produces: meshes, materials, textures and a node tree,
// read from untrusted bytes and checked, before anything reaches the scene. asset_batch.h turns
// it into one engine edit batch. Nothing here touches the filesystem, HTTP or the engine's scene:
// an importer is a pure function of the uploaded bytes.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "engine/core/expected.h"
#include "engine/core/math.h"
#include "engine/scene/mesh_kind.h"
#include "engine/scene/types.h"
#include "protocol/problem.h"

namespace strata::assets {

/// The file formats the importers read: four of our own, then those read through assimp
/// (assimp_import.h). New formats go at the end (the sandbox's wire stores the number).
enum class AssetFormat : uint8_t {
    Glb, Gltf, Obj, Ply,
    Fbx, Dae, Stl, ThreeDs, Off, X, Ac, Ase, Lwo, Ms3d, B3d, Dxf, ThreeMf, Amf, Smd, Nff, Cob, Xgl
};
inline constexpr AssetFormat LAST_ASSET_FORMAT = AssetFormat::Xgl;

/// "glb", "gltf", "obj", "ply", "fbx", "dae", "stl", "3ds", ...: the format's usual extension.
const char* format_name(AssetFormat f);
/// The format named by a `format` query value or a file extension (case-insensitive, no dot).
std::optional<AssetFormat> format_from_name(std::string_view name);
/// True for the formats read through assimp.
constexpr bool format_is_assimp(AssetFormat f) {
    return f > AssetFormat::Ply;
}
/// Every format's name, comma separated: "glb, gltf, obj, ply, fbx, ...".
std::string format_names();
/// Every Content-Type format_from_media_type knows.
std::vector<std::string> media_type_names();
/// The format of a Content-Type (model/gltf-binary, model/gltf+json, model/obj, application/ply,
/// model/ply, text/plain is not one), parameters after ';' ignored.
std::optional<AssetFormat> format_from_media_type(std::string_view type);

/// One mesh: triangles, points or linear curves (engine/scene/mesh_kind.h). Optional attributes
/// are empty or hold one entry per position. Points and curves have radii and no triangles, and
/// carry no normals, texture coordinates or tangents (importers drop them, saying so).
struct AssetMesh {
    std::string name;
    MeshKind kind = MeshKind::Triangles;
    std::vector<Vec3> positions;
    std::vector<Triangle> triangles;  ///< triangle meshes only
    std::vector<float> radii;         ///< points and curves: one per position, finite, > 0
    std::vector<uint32_t> strands;    ///< curves: control vertices per linear strand (>= 2)
    std::vector<Vec3> normals;
    std::vector<glm::vec2> uvs;
    std::vector<glm::vec2> uvs1;  ///< a second texture coordinate set (glTF's TEXCOORD_1)
    std::vector<Vec4> tangents;  ///< xyz and the bitangent's sign w (glTF's TANGENT)
    std::vector<Vec3> colors;    ///< linear RGB in [0, 1]
    int material = -1;         ///< index into Asset::materials; -1: the built-in default
};

/// An image a material refers to: encoded bytes (PNG, JPEG) or an external name it could not
/// read (never read from the server's filesystem).
struct AssetTexture {
    std::string name;
    std::string mime_type;       ///< "image/png", "image/jpeg", or "" when unknown
    std::vector<uint8_t> bytes;  ///< empty when only `uri` is known
    std::string uri;             ///< the file's own reference (OBJ map_Kd, glTF external uri)
    /// How the scene decodes it: the space of the material slots that use it (TEXTURE_SLOTS).
    TextureColorSpace color_space = TextureColorSpace::Srgb;
};

/// A PBR metallic-roughness material, values already in the engine's ranges.
struct AssetMaterial {
    std::string name;
    Material material;
    /// By TextureSlot: an index into Asset::textures; -1: none.
    PerTextureSlot<int> textures = {-1, -1, -1, -1, -1};

    int& texture(TextureSlot s) { return textures[slot_index(s)]; }
    int texture(TextureSlot s) const { return textures[slot_index(s)]; }
};

/// One node of the hierarchy: a local transform, its parent and the meshes it places.
struct AssetNode {
    std::string name;
    int parent = -1;  ///< index into Asset::nodes; -1: a root
    Affine local;
    std::vector<int> meshes;  ///< indices into Asset::meshes
    /// Its local transform at times in seconds (glTF's first animation; empty: still), each
    /// key keeping the transform rule, times increasing: the scene's keyframe animation.
    std::vector<Keyframe> animation;
};

/// Most keyframes one import brings, over all its nodes (a too-large error beyond).
inline constexpr std::size_t MAX_IMPORTED_KEYFRAMES = std::size_t(1) << 20;

/// A whole imported file. Nodes are ordered parents first (a node's parent has a lower index).
struct Asset {
    std::vector<AssetMesh> meshes;
    std::vector<AssetMaterial> materials;
    std::vector<AssetTexture> textures;
    std::vector<AssetNode> nodes;
    std::vector<std::string> warnings;  ///< what was read but ignored, for the answer

    /// Vertices (points and control vertices too) and triangles over meshes, each counted once.
    /// Points and curves cost the scene's budget their vertices and each mesh's overhead only.
    uint64_t vertex_count() const;
    uint64_t triangle_count() const;
};

/// Why a file cannot be imported: a Problem (protocol/problem.h) of type invalid-asset (malformed,
/// or uses what Strata does not import) or too-large (more than the scene's budget allows), whose
/// `file` and `element` ("accessors[3]", "line 12", ...; none for the whole file) say where, and
/// whose detail reads "bunny.obj: line 12: face index 900 is outside the 500 vertices".
template <class T>
using Imported = Expected<T, protocol::Problem>;

/// What an importer may allocate: the room left in the scene budget (checked before reading
/// counts a header declares, so a tiny file cannot ask for gigabytes).
struct ImportLimits {
    uint64_t max_vertices = uint64_t(1) << 24;
    uint64_t max_triangles = uint64_t(1) << 24;
    uint32_t max_nodes = 1u << 16;
    uint32_t max_json_depth = 64;  ///< glTF JSON nesting (tinygltf recurses over `extras`)
};

/// Builds errors for one file.
class ErrorSink {
public:
    explicit ErrorSink(std::string file) : m_file(std::move(file)) {}
    const std::string& file() const { return m_file; }
    /// Malformed or inconsistent.
    Unexpected<protocol::Problem> invalid(std::string element, const std::string& message) const {
        return make(protocol::ProblemType::InvalidAsset, std::move(element), message);
    }
    /// Valid, but uses something Strata does not import.
    Unexpected<protocol::Problem> unsupported(std::string element,
                                              const std::string& message) const {
        return make(protocol::ProblemType::InvalidAsset, std::move(element), message);
    }
    /// More than the scene's budget allows.
    Unexpected<protocol::Problem> too_large(std::string element, const std::string& message) const {
        return make(protocol::ProblemType::TooLarge, std::move(element), message);
    }

private:
    Unexpected<protocol::Problem> make(protocol::ProblemType type, std::string element,
                                       const std::string& message) const;
    std::string m_file;
};

/// The radius of each point of a point cloud that brings none (a PLY without a `radius`
/// property, glTF POINTS, which has no point size): half the spacing of its N points spread
/// evenly over a square as wide as their bounds' diagonal D, 0.5 * D / sqrt(N), with D = 1 when
/// the points coincide. Scanned clouds sample surfaces, so neighbours about touch; a cloud that
/// fills a volume looks sparser rather than hiding its shape.
float default_point_radius(const std::vector<Vec3>& positions);

/// The radius of lines that bring none (glTF LINES, LINE_STRIP and LINE_LOOP): 0.002 * D, D as
/// for points: thin next to the whole model, wide enough to be hit.
float default_line_radius(const std::vector<Vec3>& positions);

/// A radius as warnings print it ("0.0125", "3.2e-05").
std::string radius_text(float radius);

/// Checks an asset's counts against `limits` (TooLarge naming the count and the limit).
Imported<void> check_budget(const Asset& asset, const ImportLimits& limits, const ErrorSink& sink);

/// Checks every index, every number and every reference of an asset an importer produced:
/// triangles inside their mesh, finite positions, radii and strands of points and curves,
/// material, texture, mesh and parent indices in range, parents before children. Importers call
/// it last; a failure names the element.
Imported<void> validate_asset(const Asset& asset, const ErrorSink& sink);

}  // namespace strata::assets
