// libFuzzer target for the snapshot decoder, which reads untrusted bytes (POST
// /v1/scene/snapshot) as well as the data directory's snapshot files: the header checks
// (open_snapshot), the scene batch (decode_batch), and both ways a decoded scene is loaded.
//
// An input that starts with the snapshot magic is read as is; any other input becomes the payload
// of a snapshot with a correct header and checksum, so that mutations reach the scene decoder
// instead of all dying at the checksum. Checks, besides "no crash, no sanitizer report":
//   - decode_snapshot and open_snapshot agree;
//   - the import path (Scene::apply of the decoded batch, what POST does) and the restore path
//     (Scene::load edit by edit, what recovery does) accept the same snapshots and build the same
//     scene; a refused import leaves the scene untouched.
// Seeds are written by the encoder itself (durable_corpus.cpp); build and run: scripts/run-fuzz.sh.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "engine/durable/crc32c.h"
#include "engine/durable/journal_format.h"
#include "tests/fuzz/durable_fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace strata;
    std::string_view input(reinterpret_cast<const char*>(data), size);
    std::string wrapped;
    if (size < 8 || std::memcmp(data, "STRATAS1", 8) != 0) {
        // The encoder's header for this payload: its checksum at 12, its length at 24.
        wrapped = durable::encode_snapshot(EditBatch{}, 7).substr(0, durable::SNAPSHOT_HEADER_BYTES);
        const uint32_t crc = durable::crc32c(input.data(), input.size());
        const uint64_t length = input.size();
        std::memcpy(wrapped.data() + 12, &crc, sizeof crc);
        std::memcpy(wrapped.data() + 24, &length, sizeof length);
        wrapped += input;
        input = wrapped;
    }

    // Step: the header, then the scene.
    auto view = durable::open_snapshot(input);
    auto decoded = durable::decode_snapshot(input);
    if (!view) {
        FUZZ_CHECK(!decoded);
        return 0;
    }
    auto batch = durable::decode_batch(view->payload);
    FUZZ_CHECK(batch.has_value() == decoded.has_value());
    if (!decoded) return 0;
    FUZZ_CHECK(decoded->version == view->version);
    FUZZ_CHECK(fuzz::encoded(decoded->scene) == view->payload);

    // Step: import (one atomic batch) against restore (edit by edit, no undo log).
    Scene imported = fuzz::fuzz_scene();
    const bool import_ok = imported.apply(std::move(decoded->scene)).has_value();
    if (!import_ok) {
        FUZZ_CHECK(imported.version() == 0);
        FUZZ_CHECK(imported.changes().empty());
    }
    Scene restored = fuzz::fuzz_scene();
    Status loaded = durable::decode_each(view->payload,
                                         [&](Edit&& e) { return restored.load(std::move(e)); });
    if (loaded) loaded = restored.finish_load(1);
    FUZZ_CHECK(import_ok == loaded.has_value());
    if (import_ok) FUZZ_CHECK(fuzz::encoded(imported.to_batch()) == fuzz::encoded(restored.to_batch()));
    return 0;
}
