#include "protocol/assets/asset_wire.h"

#include "engine/durable/byte_io.h"

namespace strata::assets {

namespace {

using durable::ByteReader;
using durable::ByteWriter;

constexpr uint32_t MAGIC = 0x31575341;  // "ASW1"
enum class Kind : uint8_t { Outcome = 1, Problem = 2 };

void put_ints(ByteWriter& w, const std::vector<int>& v) {
    w(uint64_t(v.size()));
    for (int x : v) w(int32_t(x));
}

bool get_ints(ByteReader& r, std::vector<int>& v) {
    uint64_t n = 0;
    r(n);
    if (!r.ok() || n > r.remaining() / sizeof(int32_t)) {
        r.fail("index list of " + std::to_string(n) + " entries");
        return false;
    }
    v.resize(n);
    for (int& x : v) {
        int32_t i = 0;
        r(i);
        x = i;
    }
    return r.ok();
}

void put_bytes(ByteWriter& w, const std::vector<uint8_t>& v) {
    w(uint64_t(v.size()));
    w.raw(v.data(), v.size());
}

void get_bytes(ByteReader& r, std::vector<uint8_t>& v) {
    uint64_t n = 0;
    r(n);
    if (!r.ok()) return;
    if (n > r.remaining()) return r.fail("byte string of " + std::to_string(n) + " bytes");
    v.resize(n);
    r.raw(v.data(), n);
}

/// A count of records that each take at least `least` bytes.
bool get_count(ByteReader& r, uint64_t& n, std::size_t least, const char* what) {
    r(n);
    if (r.ok() && n > r.remaining() / least) r.fail(std::string(what) + " count " + std::to_string(n));
    return r.ok();
}

/// Every field of a material, tagged rows too (the wire is written and read by one binary).
template <class Io, class M>
void material_rows(Io& io, M& m) {
    for_each_field<MaterialFields>([&](const auto& row) { io(m.*(row.add)); });
    io(m.base_color_sampler.wrap, m.base_color_sampler.filter);
}

void put_asset(ByteWriter& w, const Asset& a) {
    w(uint64_t(a.meshes.size()));
    for (const AssetMesh& m : a.meshes) {
        w(m.name, m.kind, m.positions, m.triangles, m.radii, m.strands, m.normals, m.uvs, m.uvs1,
          m.tangents, m.colors, int32_t(m.material));
    }
    w(uint64_t(a.materials.size()));
    for (const AssetMaterial& m : a.materials) {
        w(m.name);
        material_rows(w, m.material);
        for (int texture : m.textures) w(int32_t(texture));
    }
    w(uint64_t(a.textures.size()));
    for (const AssetTexture& t : a.textures) {
        w(t.name, t.mime_type, t.uri, t.color_space);
        put_bytes(w, t.bytes);
    }
    w(uint64_t(a.nodes.size()));
    for (const AssetNode& n : a.nodes) {
        w(n.name, int32_t(n.parent), n.local, n.animation);
        put_ints(w, n.meshes);
    }
    w(a.warnings);
}

void get_asset(ByteReader& r, Asset& a) {
    uint64_t n = 0;
    // The least bytes each record takes: its name's length, its kind, its arrays' counts and
    // its material. The kind's byte is checked against MeshKind's range; what the arrays must
    // hold for the kind is validate_asset's business.
    if (!get_count(r, n, 4 + 1 + 9 * 8 + 4, "mesh")) return;
    a.meshes.resize(n);
    for (AssetMesh& m : a.meshes) {
        int32_t material = -1;
        r(m.name, m.kind, m.positions, m.triangles, m.radii, m.strands, m.normals, m.uvs, m.uvs1,
          m.tangents, m.colors, material);
        m.material = material;
    }
    if (!get_count(r, n, 4 + 8, "material")) return;
    a.materials.resize(n);
    for (AssetMaterial& m : a.materials) {
        r(m.name);
        material_rows(r, m.material);
        for (int& texture : m.textures) {
            int32_t t = -1;
            r(t);
            texture = t;
        }
    }
    if (!get_count(r, n, 3 * 4 + 8, "texture")) return;
    a.textures.resize(n);
    for (AssetTexture& t : a.textures) {
        r(t.name, t.mime_type, t.uri, t.color_space);
        get_bytes(r, t.bytes);
    }
    if (!get_count(r, n, 4 + 4 + 48 + 8 + 8, "node")) return;
    a.nodes.resize(n);
    for (AssetNode& node : a.nodes) {
        int32_t parent = -1;
        r(node.name, parent, node.local, node.animation);
        node.parent = parent;
        get_ints(r, node.meshes);
    }
    r(a.warnings);
}

constexpr uint8_t LAST_PROBLEM_TYPE = uint8_t(protocol::ProblemType::Internal);

}  // namespace

std::string encode_outcome(const Imported<ImportOutcome>& result) {
    std::string out;
    ByteWriter w(out);
    w(MAGIC);
    if (result) {
        const ImportOutcome& o = result.value();
        w(Kind::Outcome, o.format, o.model);
        put_asset(w, o.asset);
    } else {
        const protocol::Problem& p = result.error();
        w(Kind::Problem, uint8_t(p.type), p.detail, p.file, p.element);
    }
    return out;
}

Expected<Imported<ImportOutcome>, std::string> decode_outcome(std::string_view bytes) {
    ByteReader r(bytes);
    uint32_t magic = 0;
    uint8_t kind = 0;
    r(magic, kind);
    if (r.ok() && magic != MAGIC) r.fail("not an import result");
    Imported<ImportOutcome> result = ImportOutcome{};
    if (r.ok() && kind == uint8_t(Kind::Outcome)) {
        ImportOutcome& o = result.value();
        uint8_t format = 0;
        r(format, o.model);
        if (r.ok() && format > uint8_t(LAST_ASSET_FORMAT)) r.fail("format " + std::to_string(format));
        o.format = AssetFormat(format);
        get_asset(r, o.asset);
    } else if (r.ok() && kind == uint8_t(Kind::Problem)) {
        uint8_t type = 0;
        std::string detail;
        std::optional<std::string> file, element;
        r(type, detail, file, element);
        if (r.ok() && type > LAST_PROBLEM_TYPE) r.fail("problem type " + std::to_string(type));
        protocol::Problem p = protocol::make_problem(protocol::ProblemType(type), detail);
        p.file = std::move(file);
        p.element = std::move(element);
        result = Unexpected(std::move(p));
    } else if (r.ok()) {
        r.fail("kind " + std::to_string(kind));
    }
    if (r.ok() && r.remaining() != 0)
        r.fail(std::to_string(r.remaining()) + " bytes after the result");
    if (!r.ok()) return Unexpected(r.error());
    return result;
}

}  // namespace strata::assets
