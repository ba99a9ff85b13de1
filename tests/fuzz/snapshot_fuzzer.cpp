// libFuzzer target for the snapshot decoder, which reads untrusted bytes (POST
// /v1/scene/snapshot) as well as the data directory's snapshot files: the header checks
// (open_snapshot), the scene batch (decode_batch), and both ways a decoded scene is loaded. The
// same bytes also go to the history file decoder (decode_history: the history-<version>.hist a
// data directory keeps beside each snapshot).
//
// An input that starts with the snapshot (history) magic is read as is; any other input becomes
// the payload of a snapshot (and of a history file) with a correct header and checksum, so that
// mutations reach the decoders instead of all dying at the checksum. Checks, besides "no crash,
// no sanitizer report":
//   - a history file that decodes encodes back to the same bytes;
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

namespace {

/// `input` as it is when it starts with `magic`, else behind the header `empty` (an encoder's
/// file with no payload) begins with, its checksum and length set for `input`.
std::string framed(std::string_view input, const char* magic, const std::string& empty) {
    if (input.size() >= 8 && std::memcmp(input.data(), magic, 8) == 0) return std::string(input);
    std::string out = empty.substr(0, strata::durable::SNAPSHOT_HEADER_BYTES);
    const uint32_t crc = strata::durable::crc32c(input.data(), input.size());
    const uint64_t length = input.size();
    std::memcpy(out.data() + 12, &crc, sizeof crc);
    std::memcpy(out.data() + 24, &length, sizeof length);
    return out += input;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace strata;
    const std::string_view bytes(reinterpret_cast<const char*>(data), size);

    // Step: as a history file.
    const std::string history =
        framed(bytes, "STRATAH1", durable::encode_history(HistoryState{}, 7));
    if (auto h = durable::decode_history(history))
        FUZZ_CHECK(durable::encode_history(h->state, h->version) == history);

    const std::string wrapped = framed(bytes, "STRATAS1", durable::encode_snapshot(EditBatch{}, 7));
    std::string_view input = wrapped;

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
