#pragma once
// Shared helpers of the importer tests: reading real files, building small ones.

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "protocol/assets/import.h"

namespace strata::assets::test {

/// The whole file, or "" when it cannot be read (the caller skips or fails).
std::string read_file(const std::string& path);

/// The bytes of a string, as an importer takes them.
inline std::span<const uint8_t> bytes_of(const std::string& s) {
    return {reinterpret_cast<const uint8_t*>(s.data()), s.size()};
}

/// Imports `text` as `format` with default limits.
Imported<Asset> import_text(AssetFormat format, const std::string& text,
                            const SideFiles& side = {}, const ImportLimits& limits = {});

/// A .gltf document whose one buffer is a data: URI holding one triangle (positions then
/// uint16 indices): accessors 0 (POSITION) and 1 (indices). `nodes_json` and `scenes_json` are
/// spliced in as they are; meshes: [{"primitives": [{"attributes": {"POSITION": 0},
/// "indices": 1 <extra>}]}].
std::string triangle_gltf(const std::string& nodes_json, const std::string& primitive_extra = "",
                          const std::string& scenes_json = "[{\"nodes\": [0]}]");

/// Adds a float accessor named `name` (`type`: "VEC2", "VEC3", "VEC4"; three elements, in a
/// buffer, view and accessor of its own) to the first primitive of triangle_gltf()'s document.
void add_float_attribute(nlohmann::json& doc, const char* name, const std::vector<float>& values,
                         const char* type);

}  // namespace strata::assets::test
