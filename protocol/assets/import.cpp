#include "protocol/assets/import.h"

#include <exception>
#include <new>

#include "protocol/assets/assimp_import.h"
#include "protocol/assets/gltf_import.h"
#include "protocol/assets/ply_import.h"

namespace strata::assets {

Imported<Asset> import_asset(AssetFormat format, std::span<const uint8_t> bytes,
                             const std::string& file, const ImportLimits& limits,
                             const SideFiles& side_files) {
    const ErrorSink sink(file);
    if (bytes.empty()) return sink.invalid("", "the file is empty");
    try {
        switch (format) {
            case AssetFormat::Glb:
                return import_gltf(bytes, true, file, limits, side_files);
            case AssetFormat::Gltf:
                return import_gltf(bytes, false, file, limits, side_files);
            case AssetFormat::Obj:
                return import_obj(bytes, file, side_files, limits);
            case AssetFormat::Ply:
                return import_ply(bytes, file, limits);
            default:
                return import_assimp(bytes, format, file, limits, side_files);
        }
    } catch (const std::bad_alloc&) {
        return sink.too_large("", "reading it needs more memory than this server can give");
    } catch (const std::exception& e) {
        return sink.invalid("", std::string("could not be read: ") + e.what());
    }
    return sink.invalid("", "unknown format");
}

}  // namespace strata::assets
