// libFuzzer target for tar uploads (POST /v1/assets with application/x-tar): the tar reader
// (protocol/assets/tar_reader.h), the choice of the one model, the side-file lookups and the
// importer it leads to (protocol/assets/archive_import.h), then the asset's batch through the
// scene's rules.
//
// Checks, besides "no crash, no sanitizer report, no exception":
//   - every entry the reader keeps lies inside the input, with a normal, relative name;
//   - a refusal names the archive and says what is wrong;
//   - an accepted asset validates again and a refused batch leaves the scene as it was.
// Seeds: archives `tar` writes at run time (scripts/run-fuzz.sh), of an OBJ with its MTL and
// image and of a .gltf with its .bin and PNG.

#include <cstddef>
#include <cstdint>

#include "engine/scene/scene.h"
#include "protocol/assets/archive_import.h"
#include "protocol/assets/asset_batch.h"
#include "protocol/assets/side_files.h"
#include "tests/fuzz/asset_fuzz_util.h"

namespace {

using namespace strata;
using namespace strata::assets;

[[noreturn]] void fail(const char* what) {
    fuzz::fail("archive fuzzer", what);
}

void check_entries(std::span<const uint8_t> body) {
    TarLimits limits;
    limits.max_entries = 256;
    auto entries = read_tar(body, "fuzz.tar", limits);
    if (!entries) {
        if (entries.error().file != "fuzz.tar" || entries.error().detail.empty())
            fail("a tar refusal without its archive or message");
        return;
    }
    for (const TarEntry& e : entries.value()) {
        if (e.bytes.data() < body.data() ||
            e.bytes.data() + e.bytes.size() > body.data() + body.size())
            fail("an entry outside the archive");
        const auto normal = normalize_reference(e.path);
        if (e.path.empty() || !normal || *normal != e.path || e.path.substr(0, 2) == ".." ||
            e.path.find("/../") != std::string::npos)
            fail("an entry name that is not normal and relative");
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
    static Scene scene;
    const std::span<const uint8_t> body(data, size);
    check_entries(body);
    ImportLimits limits;
    limits.max_vertices = 1u << 16;
    limits.max_triangles = 1u << 16;
    limits.max_nodes = 1024;
    TarLimits tar_limits;
    tar_limits.max_entries = 256;
    auto archived = import_archive(body, "fuzz.tar", limits, tar_limits);
    if (!archived) {
        if (archived.error().file.value_or("").rfind("fuzz.tar", 0) != 0 ||
            archived.error().detail.empty())
            fail("a refusal without its archive or message");
        return 0;
    }
    fuzz::apply_accepted("archive fuzzer", scene, std::move(archived.value().asset));
    return 0;
}
