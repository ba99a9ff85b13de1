#include "tests/assets/asset_test_util.h"

#include <cstring>
#include <fstream>
#include <sstream>

#include "protocol/base64.h"

namespace strata::assets::test {

std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return {};
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

Imported<Asset> import_text(AssetFormat format, const std::string& text, const SideFiles& side,
                            const ImportLimits& limits) {
    return import_asset(format, bytes_of(text), std::string("test.") + format_name(format), limits,
                        side);
}

std::string triangle_gltf(const std::string& nodes_json, const std::string& primitive_extra,
                          const std::string& scenes_json) {
    const float positions[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const uint16_t indices[4] = {0, 1, 2, 0};  // padded to 4-byte alignment
    std::string buffer(sizeof positions + sizeof indices, '\0');
    std::memcpy(buffer.data(), positions, sizeof positions);
    std::memcpy(buffer.data() + sizeof positions, indices, sizeof indices);
    const std::string uri =
        "data:application/octet-stream;base64," + protocol::encode_base64(buffer);
    return R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": )" + scenes_json +
           R"(, "nodes": )" + nodes_json +
           R"(, "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1)" +
           primitive_extra + R"(}]}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "buffers": [{"byteLength": 44, "uri": ")" +
           uri + R"("}]})";
}

void add_float_attribute(nlohmann::json& doc, const char* name, const std::vector<float>& values,
                         const char* type) {
    const std::string bytes(reinterpret_cast<const char*>(values.data()), values.size() * 4);
    const std::size_t buffer = doc["buffers"].size(), view = doc["bufferViews"].size();
    doc["buffers"].push_back({{"byteLength", bytes.size()},
                              {"uri", "data:application/octet-stream;base64," +
                                          protocol::encode_base64(bytes)}});
    doc["bufferViews"].push_back({{"buffer", buffer}, {"byteLength", bytes.size()}});
    doc["accessors"].push_back(
        {{"bufferView", view}, {"componentType", 5126}, {"count", 3}, {"type", type}});
    doc["meshes"][0]["primitives"][0]["attributes"][name] = doc["accessors"].size() - 1;
}

}  // namespace strata::assets::test
