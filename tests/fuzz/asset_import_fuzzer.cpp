// libFuzzer target for one importer (protocol/assets/), built once per format:
//   gltf_import_fuzzer (.glb when the input starts with "glTF", else .gltf JSON),
//   obj_import_fuzzer, ply_import_fuzzer, and assimp_import_fuzzer: our glue around Debian's
//   assimp (its IOSystem over the upload, the conversion of its scene, materials and textures),
//   the input's first line naming the format ("fbx\n" then the file; run-fuzz.sh writes seeds
//   so). assimp itself is not instrumented, leaks on some broken files and allocates what a
//   header declares: that fuzzer runs without leak detection, in libFuzzer's fork mode skipping
//   out-of-memory inputs (the server's sandbox refuses them with its memory limit).
//
// Checks, besides "no crash, no sanitizer report, no exception":
//   - a refusal names the file and says what is wrong;
//   - an accepted asset crosses the sandbox's wire unchanged, passes validate_asset again (every
//     index in range) and its batch goes through the scene's rules; a refused batch leaves the
//     scene as it was;
//   - the input read as that wire either is refused or encodes back to itself.
// Small limits keep each input cheap: the budget checks run on every input.
// Build and run: scripts/run-fuzz.sh (its corpora are seeded from assimp-testmodels).

#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <cstring>
#include <optional>

#include "engine/scene/scene.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/asset_wire.h"
#include "protocol/assets/import.h"
#include "tests/fuzz/asset_fuzz_util.h"

namespace {

using namespace strata;
using namespace strata::assets;

[[noreturn]] void fail(const char* what) {
    fuzz::fail("asset fuzzer", what);
}

/// The format the input is read as, and the input without what named it (the assimp fuzzer's
/// first line); nullopt for an input that names no assimp format.
std::optional<AssetFormat> format_of(const uint8_t*& data, std::size_t& size) {
#if defined(STRATA_FUZZ_ASSIMP)
    const auto* end = static_cast<const uint8_t*>(std::memchr(data, '\n', std::min<std::size_t>(size, 8)));
    if (!end) return std::nullopt;
    const auto format =
        format_from_name(std::string_view(reinterpret_cast<const char*>(data), std::size_t(end - data)));
    if (!format || !format_is_assimp(*format)) return std::nullopt;
    size -= std::size_t(end + 1 - data);
    data = end + 1;
    return format;
#elif defined(STRATA_FUZZ_GLTF)
    return size >= 4 && std::memcmp(data, "glTF", 4) == 0 ? AssetFormat::Glb : AssetFormat::Gltf;
#elif defined(STRATA_FUZZ_OBJ)
    (void)data, (void)size;
    return AssetFormat::Obj;
#else
    (void)data, (void)size;
    return AssetFormat::Ply;
#endif
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    static Scene scene;
    // The input as the sandbox's wire (asset_wire.h), what a subverted importer could send: a
    // result that decodes encodes back to the same bytes.
    const std::string_view wire(reinterpret_cast<const char*>(data), size);
    if (auto decoded = decode_outcome(wire); decoded && encode_outcome(decoded.value()) != wire)
        fail("a decoded wire result does not encode back to its bytes");
    ImportLimits limits;
    limits.max_vertices = 1u << 16;
    limits.max_triangles = 1u << 16;
    limits.max_nodes = 1024;
    const SideFiles side = {{"fuzz.mtl", "newmtl a\nKd 0.5 0.5 0.5\nmap_Kd a.png\n"}};
    const std::optional<AssetFormat> format = format_of(data, size);
    if (!format) return 0;
    auto asset = import_asset(*format, {data, size}, "fuzz", limits, side);
    if (!asset) {
        if (asset.error().file != "fuzz" || asset.error().detail.empty())
            fail("a refusal without its file or message");
        return 0;
    }
    fuzz::apply_accepted("asset fuzzer", scene, std::move(asset.value()));
    return 0;
}
