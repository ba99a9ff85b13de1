#include "protocol/assets/draco_decode.h"

#include <cmath>
#include <memory>
#include <new>

#include <draco/compression/decode.h>
#include <draco/core/decoder_buffer.h>

namespace strata::assets {

namespace {

/// Attribute `id`'s values for every point, `width` floats each (a colour's fourth is dropped),
/// or an error naming `name`.
template <class V, int Width>
std::string read_attribute(const draco::Mesh& mesh, int id, const char* name, std::vector<V>& out) {
    const draco::PointAttribute* a = mesh.GetAttributeByUniqueId(uint32_t(id));
    if (!a)
        return std::string(name) + " names Draco attribute " + std::to_string(id) +
               ", which the data does not hold";
    if (a->num_components() < Width)
        return std::string(name) + " has " + std::to_string(int(a->num_components())) +
               " components, not " + std::to_string(Width);
    out.resize(mesh.num_points());
    float value[4] = {0, 0, 0, 0};
    const int8_t n = int8_t(std::min<int>(a->num_components(), 4));
    for (draco::PointIndex p(0); p < mesh.num_points(); ++p) {
        if (!a->ConvertValue<float>(a->mapped_index(p), n, value))
            return std::string(name) + " cannot be read as numbers";
        for (int k = 0; k < Width; ++k) {
            if (!std::isfinite(value[k]))
                return std::string(name) + " of vertex " + std::to_string(p.value()) +
                       " is not finite";
            out[p.value()][k] = value[k];
        }
    }
    return {};
}

std::string decode(std::span<const uint8_t> bytes, const DracoAttributeIds& ids,
                   const DracoCounts& declared, AssetMesh& out) {
    draco::DecoderBuffer buffer;
    buffer.Init(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
    if (!type.ok()) return "not Draco data: " + type.status().error_msg_string();
    if (type.value() != draco::TRIANGULAR_MESH)
        return "the Draco data is a point cloud, not a triangle mesh";
    draco::Decoder decoder;
    auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
    if (!decoded.ok())
        return "the Draco data does not decode: " + decoded.status().error_msg_string();
    const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
    if (mesh->num_points() != declared.vertices)
        return "it decodes to " + std::to_string(mesh->num_points()) +
               " vertices where its POSITION accessor declares " +
               std::to_string(declared.vertices);
    if (uint64_t(mesh->num_faces()) * 3 != declared.indices)
        return "it decodes to " + std::to_string(mesh->num_faces()) +
               " triangles where its indices accessor declares " +
               std::to_string(declared.indices) + " indices";

    out.triangles.resize(mesh->num_faces());
    for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f) {
        const draco::Mesh::Face& face = mesh->face(f);
        for (int k = 0; k < 3; ++k) {
            const uint32_t v = face[k].value();
            if (v >= mesh->num_points())
                return "triangle " + std::to_string(f.value()) + " uses vertex " +
                       std::to_string(v) + " of " + std::to_string(mesh->num_points());
            out.triangles[f.value()][k] = v;
        }
    }
    if (auto e = read_attribute<Vec3, 3>(*mesh, ids.position, "POSITION", out.positions);
        !e.empty())
        return e;
    if (ids.normal >= 0) {
        if (auto e = read_attribute<Vec3, 3>(*mesh, ids.normal, "NORMAL", out.normals); !e.empty())
            return e;
    }
    for (auto [id, name, uvs] : {std::tuple{ids.texcoord, "TEXCOORD_0", &out.uvs},
                                 std::tuple{ids.texcoord1, "TEXCOORD_1", &out.uvs1}}) {
        if (id < 0) continue;
        if (auto e = read_attribute<glm::vec2, 2>(*mesh, id, name, *uvs); !e.empty()) return e;
    }
    if (ids.tangent >= 0) {
        if (auto e = read_attribute<Vec4, 4>(*mesh, ids.tangent, "TANGENT", out.tangents);
            !e.empty())
            return e;
    }
    if (ids.color >= 0) {
        if (auto e = read_attribute<Vec3, 3>(*mesh, ids.color, "COLOR_0", out.colors); !e.empty())
            return e;
        for (Vec3& c : out.colors) c = glm::clamp(c, Vec3(0.0f), Vec3(1.0f));
    }
    return {};
}

}  // namespace

std::string decode_draco_mesh(std::span<const uint8_t> bytes, const DracoAttributeIds& ids,
                              const DracoCounts& declared, AssetMesh& out) {
    try {
        return decode(bytes, ids, declared, out);
    } catch (const std::bad_alloc&) {
        return "the Draco data asks for more memory than there is";
    }
}

}  // namespace strata::assets
